// meshlight reference: the path-traced reference image of a view (the same
// camera and pixels as `render`) and an estimate of its noise, rendered in
// passes of a few samples per pixel: Ctrl-C writes the passes done, every
// pixel with the same count (the EXR attribute meshlight:spp).
#include "CameraOptions.h"
#include "Commands.h"
#include "Options.h"
#include "Progress.h"
#include "core/Error.h"
#include "core/image/Image.h"
#include "core/io/InterruptGuard.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"

#include <cstdio>
#include <filesystem>
#include <thread>

namespace ml {

std::string referenceNoisePath(const std::string& out) {
    const std::filesystem::path p(out);
    return (p.parent_path() / (p.stem().string() + ".noise" + p.extension().string())).string();
}

int runReference(const std::vector<std::string>& args) {
    Options o("reference");
    declareSceneOptions(o);
    o.value("out", "FILE", "output image, .exr or .hdr (linear radiance); its standard error goes beside it "
                           "as FILE.noise.exr (.hdr)");
    o.value("spp", "N", "samples per pixel, at least 2 (even and odd samples estimate the noise)");
    o.value("pass", "N", "samples per pixel per pass, even: Ctrl-C or SIGTERM writes the passes done",
            std::string("2"));
    declareViewOptions(o);
    o.value("max-depth", "D", "emission + direct light + D-1 indirect bounces (1: direct light only)",
            std::string("8"));
    o.value("seed", "N", "random seed; the same seed gives the same image, whatever --threads",
            std::string("1"));
    o.value("threads", "T", "worker threads, 0 = every core", std::string("0"));
    if (!o.parseOrPrintHelp(args)) return 0;

    // Everything the user can get wrong is checked before any work.
    const std::string out = o.str("out");
    checkOutputPath(out);
    if (outputFormat(out) == ImageFormat::Png)
        throwInputError(SourceLocation{out}, "a reference holds linear radiance: use .exr or .hdr, not .png");
    const std::string noise = referenceNoisePath(out);
    checkOutputPath(noise);
    const int spp = o.integer("spp", 2, 1 << 24);
    const int pass = o.integer("pass", 2, 1 << 24);
    if (pass % 2 != 0) throw InputError(concat("--pass ", pass, ": must be even, so that both halves of the "
                                              "samples (the noise estimate) grow alike"));
    const int width = o.integer("width", 1, 16384), height = o.integer("height", 1, 16384);
    PathTracerSettings settings;
    settings.maxDepth = o.integer("max-depth", 1, 1024);
    settings.seed = o.seed("seed");
    settings.threads = o.integer("threads", 0, 1024);
    settings.validate();

    const Scene scene = loadScene(o);
    for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    const Camera camera = cameraFromOptions(o, scene, double(width) / height);
    const int threads = settings.threads ? settings.threads : std::max(1, int(std::thread::hardware_concurrency()));
    std::printf("scene '%s': %zu meshes, %zu triangles, %zu lights\n", scene.name.c_str(), scene.meshes.size(),
                scene.triangleCount(), scene.lights.size());
    std::printf("plan: path tracing %dx%d, %d samples per pixel in passes of %d, max depth %d (emission + direct + "
                "%d indirect bounces), seed %u, %d threads\n",
                width, height, spp, std::min(pass, spp), settings.maxDepth, settings.maxDepth - 1, settings.seed,
                threads);
    if (scene.lights.empty()) std::printf("  no emissive material (Ke > 0): the image is black\n");

    const EmbreeScene rays(scene);
    const PathTracer tracer(rays, settings);
    Progress progress("reference", size_t(width) * size_t(height) * size_t(spp));
    const InterruptGuard interrupt;
    RenderControl control;
    control.progress = [&](uint64_t done, uint64_t) { progress.update(size_t(done)); };
    control.stop = &interrupt.flag();
    control.passSamples = pass;
    const ReferenceImage image = tracer.render(camera, width, height, spp, control);
    if (image.cancelled)
        progress.abandon();
    else
        progress.finish();
    if (image.samplesPerPixel == 0) {
        std::fprintf(stderr, "meshlight: interrupted: wrote nothing (the first pass of %d samples per pixel had not "
                             "ended after %.1f s; %s)\n",
                     pass, image.seconds, interrupt.signalName());
        return 130;
    }

    // Both files or neither: the noise first, removed again if the image fails.
    const ImageAttributes attributes = {{"meshlight:spp", image.samplesPerPixel},
                                        {"meshlight:max_depth", settings.maxDepth},
                                        {"meshlight:seed", std::to_string(settings.seed)}};
    writeImageLinear(noise, image.standardError, attributes);
    try {
        writeImageLinear(out, image.radiance, attributes);
    } catch (...) {
        std::error_code ignored;
        std::filesystem::remove(noise, ignored);
        throw;
    }
    const double pixels = double(width) * height;
    std::printf("mean relative standard error %.3g %% (luminance, over %zu lit pixels)\n",
                100 * image.meanRelativeError, image.litPixels);
    std::printf("%.0f paths in %.2f s on %d threads: %.4g paths/s, %.4g samples per pixel per second\n",
                double(image.paths), image.seconds, threads, double(image.paths) / image.seconds,
                double(image.paths) / pixels / image.seconds);
    if (image.cancelled) {
        std::fprintf(stderr, "meshlight: interrupted: wrote %s and %s (the %d of %d samples per pixel done after "
                             "%.1f s; %s)\n",
                     out.c_str(), noise.c_str(), image.samplesPerPixel, spp, image.seconds, interrupt.signalName());
        return 130;
    }
    std::printf("wrote %s and %s (%dx%d, %d samples per pixel)\n", out.c_str(), noise.c_str(), width, height, spp);
    return 0;
}

}  // namespace ml
