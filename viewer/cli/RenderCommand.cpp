// meshlight render: the first image. Direct light from every area light,
// sampled at the vertices of the cache meshes, composited and tone-mapped.
#include "Commands.h"
#include "DirectSetup.h"
#include "Progress.h"
#include "cache/IrradianceCache.h"
#include "core/Error.h"
#include "core/image/Image.h"
#include "viewer/Compositor.h"
#include "viewer/ToneMap.h"

#include <chrono>
#include <cstdio>

namespace ml {

namespace {

Camera cameraFromOptions(const Options& o, const Scene& scene, double aspect) {
    Camera c = scene.cameraOrDefault(aspect);
    if (o.has("camera-pos")) c.position = o.vec3("camera-pos");
    if (o.has("camera-target")) c.target = o.vec3("camera-target");
    if (o.has("camera-up")) c.up = o.vec3("camera-up");
    if (o.has("fov")) c.fovYDegrees = o.number("fov", 1e-3, 179.0);
    c.validate();
    return c;
}

// What will be simulated, and why: printed before any work.
void printPlan(const Scene& scene, const DirectChoice& choice, bool directOnly) {
    std::printf("plan:\n");
    for (const AreaLight& l : scene.lights)
        std::printf("  light '%s': %zu triangles, area %.6g, %s; direct light by %s\n", l.name.c_str(),
                    l.triangles.size(), l.area, l.planar ? "planar" : "not planar",
                    choice.describe().c_str());
    if (scene.lights.empty()) std::printf("  no emissive material (Ke > 0): the image is black\n");
    std::printf("  indirect light: not simulated (%s)\n",
                directOnly ? "--direct-only" : "the indirect gather is not implemented yet; direct light only");
    if (scene.hasGlossy())
        std::printf("  specular: some materials have Ks > 0, but the Phong specular pass is not implemented yet:"
                    " they render as Lambertian\n");
    else
        std::printf("  specular: no pass (no material has Ks > 0)\n");
}

}  // namespace

int runRender(const std::vector<std::string>& args) {
    Options o("render");
    o.positional("scene", "cornell, bench or an OBJ file");
    o.value("out", "FILE", "output image: .exr/.hdr (linear radiance) or .png (tone-mapped)",
            std::string("meshlight.png"));
    o.value("width", "W", "image width, pixels", std::string("512"));
    o.value("height", "H", "image height, pixels", std::string("512"));
    o.value("camera-pos", "X,Y,Z", "camera position (default: the scene's camera or a framing one)");
    o.value("camera-target", "X,Y,Z", "point the camera looks at");
    o.value("camera-up", "X,Y,Z", "camera up vector");
    o.value("fov", "DEG", "vertical field of view, degrees");
    o.flag("direct-only", "direct light only (the only light simulated so far)");
    declareDirectOptions(o);
    o.value("cache-edge", "F", "cache mesh edges at most F × the scene diagonal", std::string("0.015625"));
    o.value("supersample", "S", "S×S sub-pixels per pixel (box filter)", std::string("4"));
    o.value("exposure", "EV", "exposure in stops, on top of auto exposure", std::string("0"));
    o.flag("no-auto-exposure", "do not scale the log-average luminance to middle grey");
    o.value("tonemap", "OP", "aces, reinhard or clamp", std::string("aces"));
    if (!o.parseOrPrintHelp(args)) return 0;

    // Everything the user can get wrong is checked before any work.
    const std::string out = o.str("out");
    checkOutputPath(out);
    const ImageFormat format = outputFormat(out);
    CompositorSettings comp;
    comp.width = o.integer("width", 1, 16384);
    comp.height = o.integer("height", 1, 16384);
    comp.supersample = o.integer("supersample", 1, 16);
    comp.validate();
    const DirectChoice choice = readDirectOptions(o);
    CacheSettings cacheSettings;
    cacheSettings.maxEdgeFraction = o.number("cache-edge", 1e-5, 1.0);
    cacheSettings.validate();
    ToneMapSettings tone;
    tone.exposureEV = o.number("exposure", -50, 50);
    tone.autoExposure = !o.isSet("no-auto-exposure");
    tone.op = parseToneOperator(o.str("tonemap"));

    const auto t0 = std::chrono::steady_clock::now();
    const Scene scene = loadSceneArgument(o.positionalValue("scene"));
    for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    const Camera camera = cameraFromOptions(o, scene, double(comp.width) / comp.height);
    std::printf("scene '%s': %zu meshes, %zu triangles, %zu lights\n", scene.name.c_str(), scene.meshes.size(),
                scene.triangleCount(), scene.lights.size());
    printPlan(scene, choice, o.isSet("direct-only"));

    DirectEstimators estimators(scene, choice, true);
    std::printf("OpenGL: %s\n", estimators.context()->describe().c_str());
    IrradianceCache cache(scene, cacheSettings);
    size_t vertices = 0;
    for (size_t l = 0; l < cache.lightCount(); ++l) vertices += cache.vertexCount(l);
    std::printf("cache: %zu vertices over %zu light meshes, %.1f MB\n", vertices, cache.lightCount(),
                cache.memoryBytes() / 1e6);

    Progress progress("direct light", vertices);
    sampleEveryVertex(cache, estimators.estimate(), choice.passes, choice.seed,
                      [&](size_t done, size_t) { progress.update(done); });
    progress.finish();
    const auto t1 = std::chrono::steady_clock::now();

    std::vector<IrradianceMeshView> views;
    for (size_t l = 0; l < cache.lightCount(); ++l) views.push_back(cache.view(l));
    Compositor compositor(*estimators.context(), scene);
    const ImageRgb image = compositor.render(camera, views, comp);
    if (format == ImageFormat::Png)
        writeImage8(out, toneMap(image, tone), image.width, image.height);
    else
        writeImageLinear(out, image);
    const auto t2 = std::chrono::steady_clock::now();

    const double sampling = std::chrono::duration<double>(t1 - t0).count();
    const DirectPhaseTimes& p = estimators.totals();
    std::printf("sampling: %.2f s (%.1f us per vertex and light; GPU phases: setup %.2f s, draw %.2f s, "
                "readback %.2f s, weighting %.2f s)\n",
                sampling, vertices ? sampling / double(vertices * size_t(choice.passes)) * 1e6 : 0.0, p.setup,
                p.draw, p.readback, p.weighting);
    std::printf("compositing and writing: %.2f s\nwrote %s (%dx%d)\n",
                std::chrono::duration<double>(t2 - t1).count(), out.c_str(), image.width, image.height);
    return 0;
}

}  // namespace ml
