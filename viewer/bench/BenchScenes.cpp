#include "BenchScenes.h"

#include "BenchRun.h"
#include "Gnuplot.h"
#include "core/Error.h"
#include "core/image/Image.h"
#include "core/image/ImageMetrics.h"
#include "core/image/ToneMap.h"

#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace ml {

namespace fs = std::filesystem;

namespace {

struct SceneCase {
    const char* id;
    const char* file;    // under the scenes folder
    const char* camera;  // extra options: the view
    int width, height;
};

const SceneCase kCases[] = {
    {"sphere", "mcguire-cornellbox/CornellBox-Sphere.obj", "", 256, 256},
    {"water", "mcguire-cornellbox/CornellBox-Water.obj", "", 256, 256},
    {"backrooms", "backrooms-gltf/scene.gltf",
     "--camera-pos 199.8,50,-40 --camera-target 199.8,62,-166 --fov 70", 240, 135},
};

fs::path scenesFolder() {
    const char* dir = std::getenv("MESHLIGHT_SCENES_DIR");
    return dir && *dir ? fs::path(dir) : fs::path("../shared/scenes");
}

double meanOf(const ImageRgb& image) {
    double sum = 0;
    for (float v : image.data) sum += v;
    return image.data.empty() ? 0.0 : sum / double(image.data.size());
}

// Render and reference side by side (a 4-pixel gap), both at the reference's
// auto exposure, so a difference in brightness shows.
void writeSideBySide(const fs::path& path, const ImageRgb& render, const ImageRgb& reference) {
    const int gap = 4, w = render.width, h = render.height;
    ImageRgb both(2 * w + gap, h, Rgb(0.0));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                both.data[both.offset(x, y) + size_t(c)] = render.data[render.offset(x, y) + size_t(c)];
                both.data[both.offset(w + gap + x, y) + size_t(c)] = reference.data[reference.offset(x, y) + size_t(c)];
            }
    ToneMapSettings tone;
    tone.autoExposure = false;
    tone.exposureEV = std::log2(autoExposureScale(reference));
    writeImage8(path.string(), toneMap(both, tone), both.width, both.height);
}

}  // namespace

int runBenchScenes(const BenchOptions& options) {
    BenchRun run(options);
    const fs::path folder = scenesFolder();
    const double seconds = options.quick ? 2 : 60;
    const int spp = options.quick ? 64 : 1024;
    BenchTable table({"scene", "width", "height", "render_s", "reference_spp", "relative_rmse_pct", "mean_ratio"});
    std::ostringstream summary;
    summary << "# Public scenes: render against the path tracer\n\n"
            << "- mode: " << run.mode() << "; machine load at the start " << run.loadAtStart() << "\n"
            << "- each picture: `render` (left) and `reference` (right) at the reference's exposure\n";
    int rendered = 0;
    for (const SceneCase& c : kCases) {
        const fs::path scene = folder / c.file;
        std::error_code ec;
        if (!fs::is_regular_file(scene, ec)) {
            summary << "- " << c.id << ": " << scene.string() << " not found; skipped\n";
            std::printf("note: %s not found (set MESHLIGHT_SCENES_DIR); %s skipped\n", scene.string().c_str(), c.id);
            continue;
        }
        const int width = options.quick ? 64 : c.width, height = options.quick ? 64 * c.height / c.width : c.height;
        const std::string view = concat(shellQuoted(scene.string()), " ", c.camera, " --width ", width, " --height ",
                                        height, " --seed ", options.seed);
        const fs::path out = run.dir() / concat("scenes_", c.id, "_render.exr");
        const fs::path ref = run.dir() / concat("scenes_", c.id, "_reference.exr");
        const std::string renderArgs =
            concat("render ", view, " --time ", seconds, " --layers none --out ", shellQuoted(out.string()));
        const std::string referenceArgs =
            concat("reference ", view, " --spp ", spp, " --out ", shellQuoted(ref.string()));
        run.progress("%s: render, %g s\n", c.id, seconds);
        runSelf(renderArgs, run.dir() / concat("scenes_", c.id, "_render.log"));
        run.progress("%s: reference, %d spp\n", c.id, spp);
        runSelf(referenceArgs, run.dir() / concat("scenes_", c.id, "_reference.log"));
        const ImageRgb image = readImageLinear(out.string()), reference = readImageLinear(ref.string());
        const double error = relativeRmse(image, reference);
        const double ratio = meanOf(image) / std::max(meanOf(reference), 1e-30);
        writeSideBySide(run.dir() / concat("scenes_", c.id, ".png"), image, reference);
        table.addRow({c.id, concat(width), concat(height), benchNumber(seconds), concat(spp), benchPct(error),
                      benchNumber(ratio)});
        summary << "- " << c.id << " (" << c.file << ", " << width << "x" << height << "): relative RMSE "
                << benchPct(error) << "% after " << benchNumber(seconds) << " s against " << spp
                << " spp (the reference's own noise included), mean ratio " << benchNumber(ratio)
                << "; `meshlight " << renderArgs << "` against `meshlight " << referenceArgs << "`\n";
        ++rendered;
    }
    std::printf("%s", table.aligned().c_str());
    run.writeCsv("scenes.csv", table);
    run.write("scenes_summary.md", summary.str());
    run.printWallTime(run.seconds());
    return rendered > 0 || options.quick ? 0 : 1;
}

}  // namespace ml
