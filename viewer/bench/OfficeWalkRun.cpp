#include "OfficeWalkRun.h"

#include "BenchRun.h"
#include "OfficeWalkthrough.h"
#include "RenderLikeSession.h"
#include "SessionCheckpoints.h"
#include "WalkthroughViews.h"

#include "core/Error.h"
#include "core/image/Image.h"
#include "core/raytrace/EmbreeScene.h"
#include "gpu_sampling/gl/GlContext.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace ml {

namespace {

// Below a quarter of the reference's noise the corrected error (a
// difference of two near-equal sums) can come out near zero: the path
// tracer's time to an error is not read below it.
constexpr double kNoiseFloor = 0.25;

// The path tracer's time to relative RMSE `level` on a view whose
// reference, its own noise `noise`, took `seconds`: its error is its noise,
// falling as 1/√samples.
double pathSecondsAt(double seconds, double noise, double level) { return seconds * (noise / level) * (noise / level); }

}  // namespace

double OfficeWalkResult::meshlightTotal() const {
    double s = 0;
    for (const OfficeWalkView& v : views) s += v.seconds;
    return s;
}

double OfficeWalkResult::pathTotal(bool atLevel) const {
    double s = 0;
    for (const OfficeWalkView& v : views) s += atLevel ? v.pathAtLevel : v.pathAtMeshlight;
    return s;
}

bool OfficeWalkResult::allReached() const {
    return std::all_of(views.begin(), views.end(), [](const OfficeWalkView& v) { return v.reached; });
}

double OfficeWalkResult::maxError() const {
    double e = 0;
    for (const OfficeWalkView& v : views) e = std::max(e, v.error.corrected);
    return e;
}

BenchTable OfficeWalkResult::table() const {
    BenchTable t({"view", "meshlight_s", "composites", "composite_s", "relative_rmse_pct", "raw_relative_rmse_pct",
                  "estimated_error_pct", "vertices", "reached", "reference_s", "reference_noise_pct",
                  "path_level_pct", "path_at_meshlight_s", "path_at_level_s"});
    for (size_t i = 0; i < views.size(); ++i) {
        const OfficeWalkView& v = views[i];
        t.addRow({std::to_string(i), benchNumber(v.seconds), std::to_string(v.composites),
                  benchNumber(v.compositeSeconds), benchPct(v.error.corrected), benchPct(v.error.raw),
                  benchPct(v.estimatedError), std::to_string(v.vertices), v.reached ? "yes" : "no",
                  benchNumber(v.referenceSeconds), benchPct(v.referenceNoise), benchPct(v.pathLevel),
                  benchNumber(v.pathAtMeshlight), benchNumber(v.pathAtLevel)});
    }
    return t;
}

std::vector<BenchTarget> OfficeWalkResult::targets() const {
    const OfficeWalkSettings& s = settings;
    const std::string n = std::to_string(views.size()), pct = benchPct(s.level);
    std::vector<BenchTarget> rows;
    const size_t reached = size_t(std::count_if(views.begin(), views.end(), [](const OfficeWalkView& v) { return v.reached; }));
    rows.push_back({concat("walkthrough (", n, " views): each within ", pct, "%"),
                    concat(reached, " of ", n, " within; worst ", benchPct(maxError()), "%"),
                    allReached() ? "met" : "not met"});
    const double ratio = pathTotal(false) / meshlightTotal();
    rows.push_back({concat("walkthrough: >= ", s.speedup, "x less total time than the path tracer at the same error"),
                    concat(benchNumber(meshlightTotal()), " s vs ", benchNumber(pathTotal(false)), " s: ",
                           benchNumber(ratio), "x"),
                    allReached() ? (ratio >= s.speedup ? "met" : "not met") : "not met (not every view within)"});
    return rows;
}

std::string OfficeWalkResult::markdown() const {
    const OfficeWalkSettings& s = settings;
    std::ostringstream md;
    md << "## Walkthrough\n\n"
       << "- " << views.size() << " views of " << s.width << "×" << s.height << " through the office with "
       << s.office.panelsX * s.office.panelsZ << " panels (viewer/bench/OfficeWalkthrough.h: along the front "
          "wall and down the left side at eye height, turning from the room's centre to the back-left corner and "
          "across to the front-right one)\n"
       << "- references: the path tracer, " << s.referenceSpp << " samples per pixel per view, "
       << benchNumber(referenceSeconds) << " s in all, relative noise up to " << benchPct(referenceNoiseMax)
       << "% (taken out of every error)\n"
       << "- Meshlight, as a user walking through gets it: one cache from cold (" << benchNumber(cacheBuildSeconds)
       << " s to make, counted in the first view), its camera set to each view in turn; every new snapshot "
          "composited (" << s.composite.supersample << "×" << s.composite.supersample
       << " sub-pixels) until the view is within " << benchPct(s.level) << "% (limits " << s.firstViewSeconds
       << " s for the first view, " << s.viewSeconds << " s for the others); a view's time runs from its camera "
          "being set to that composite, composites included\n"
       << "- the path tracer on the same views: the reference's time × (its noise / error)², its error falling as "
          "1/√samples; at Meshlight's error per view (floored at " << kNoiseFloor << " × the reference's noise) "
          "and at " << benchPct(s.level) << "%; its BVH is not counted (an animation builds it once)\n"
       << "- totals: Meshlight **" << benchNumber(meshlightTotal()) << " s**; the path tracer "
       << benchNumber(pathTotal(false)) << " s at the same error (" << benchNumber(pathTotal(false) / meshlightTotal())
       << "×), " << benchNumber(pathTotal(true)) << " s at " << benchPct(s.level) << "% per view ("
       << benchNumber(pathTotal(true) / meshlightTotal()) << "×)\n\n"
       << table().markdown() << "\n"
       << "Every view: lights_walkthrough.csv.\n";
    return md.str();
}

OfficeWalkResult runOfficeWalk(const BenchRun& run, GlContext& context, const OfficeWalkSettings& settings) {
    OfficeWalkResult r;
    r.settings = settings;
    const OfficeWalkSettings& s = settings;
    const Scene scene = makeOfficeScene(s.office);
    const std::vector<Camera> cameras = officeWalkthroughCameras(scene, s.office, s.views);
    const EmbreeScene rays(scene);
    checkViewsInside(rays, cameras, s.width, s.height);
    r.views.resize(cameras.size());

    // The references first, so that nothing else runs while Meshlight is timed.
    const ViewReferences references =
        renderViewReferences(run, rays, cameras, s.width, s.height, s.referenceSpp, s.tracer, 0x3a1cu);
    const std::vector<Reference>& refs = references.views;
    r.referenceSeconds = references.seconds;
    r.referenceNoiseMax = references.noiseMax;

    run.progress("walkthrough: meshlight (load %s)\n", loadAverage().c_str());
    context.use();
    Compositor compositor(context, scene);
    CompositorSettings comp = s.composite;
    comp.width = s.width;
    comp.height = s.height;
    r.cacheBuildSeconds = walkViewsUntilWithin(
        scene, renderLikeSession(run, scene), compositor, cameras, comp, refs, s.level, s.firstViewSeconds,
        s.viewSeconds, [&](size_t v, ViewShown&& shown) {
            OfficeWalkView& out = r.views[v];
            static_cast<ViewShown&>(out) = std::move(shown);
            out.referenceSeconds = refs[v].seconds;
            out.referenceNoise = refs[v].noise;
            const std::string name = concat("lights_walk_", v < 10 ? "0" : "", v);
            writeImageLinear((run.dir() / (name + "_meshlight.exr")).string(), out.image);
            writeImageLinear((run.dir() / (name + "_reference.exr")).string(), refs[v].radiance);
            out.pathLevel = std::max(out.error.corrected, kNoiseFloor * refs[v].noise);
            out.pathAtMeshlight = pathSecondsAt(refs[v].seconds, refs[v].noise, out.pathLevel);
            out.pathAtLevel = pathSecondsAt(refs[v].seconds, refs[v].noise, s.level);
            std::printf("  view %2zu meshlight %6.2f s (%d composite%s, %.2f s): relative RMSE %6.3f%% (raw "
                        "%.3f%%), estimated %.3g%%, %zu vertices%s; path tracer %.2f s at that error, %.2f s at "
                        "%g%%\n",
                        v, out.seconds, out.composites, out.composites == 1 ? "" : "s", out.compositeSeconds,
                        100 * out.error.corrected, 100 * out.error.raw, 100 * out.estimatedError, out.vertices,
                        out.reached ? "" : " (time limit)", out.pathAtMeshlight, out.pathAtLevel, 100 * s.level);
        });
    std::printf("walkthrough: meshlight %.2f s in all; the path tracer %.2f s at the same error (%.2fx), %.2f s at "
                "%g%% per view\n",
                r.meshlightTotal(), r.pathTotal(false), r.pathTotal(false) / r.meshlightTotal(), r.pathTotal(true),
                100 * s.level);
    return r;
}

}  // namespace ml
