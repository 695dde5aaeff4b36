#include "BenchGi.h"

#include "BenchRun.h"
#include "BenchTable.h"
#include "CornellWalkthrough.h"
#include "WalkthroughViews.h"
#include "CyclesRunner.h"
#include "EstimateAgreement.h"
#include "Gnuplot.h"
#include "NoisyReference.h"
#include "RenderLikeSession.h"
#include "SessionCheckpoints.h"

#include "cache/IrradianceCache.h"
#include "cache/ProgressiveSession.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/image/Image.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "core/scenes/CornellBox.h"
#include "gpu_sampling/SamplerFactory.h"
#include "gpu_sampling/gl/GlContext.h"
#include "viewer/compositor/Compositor.h"
#include "viewer/compositor/ImageErrorEstimate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

// --- Targets and settings ----------------------------------------------------------

// The levels each curve is read at (relative RMSE, the reference's noise taken out).
const std::vector<double> kLevels = {0.05, 0.02, 0.01, 0.005};

// Issue 14's targets for the still image: each level within its time...
struct TimeTarget {
    double level, seconds;
};
const std::vector<TimeTarget> kTimeTargets = {{0.05, 3}, {0.02, 10}, {0.01, 40}};
// ...and no plateau: the curve goes on falling to this level given time.
constexpr double kPlateauLevel = 0.005;
// Walkthrough: every view within this error, in at least this many times
// less total time than Cycles at the same error.
constexpr double kViewTarget = 0.03;
constexpr double kWalkSpeedup = 5;

// As `meshlight reference` renders by default: emission, direct light and 7
// bounces; Cycles' "max bounces" counts the bounces after the first hit.
constexpr int kMaxDepth = 8;
constexpr int kCyclesBounces = kMaxDepth - 1;
// `render`'s composite: --supersample 4, --subpixel-passes 4 (its snapshots'),
// --outline-passes (its default).
constexpr int kSupersample = 4, kSubpixelPasses = 4;

struct Workload {
    int size;                         // still: size × size pixels
    int referenceSpp;                 // each of the two references (B, and A's last doubling)
    double meshlightSeconds;          // Meshlight's budget on the still
    std::vector<double> checkpoints;  // s since the session was made: a snapshot composited at each
    double renderCheckSeconds;        // `meshlight render --time T` as typed; 0: not run
    int cyclesMaxSpp;                 // Cycles' still: doubling stops here...
    double cyclesMaxRenderSeconds;    // ...or before a render predicted (twice the last) to take longer than this
    int views, viewSize, viewReferenceSpp;
    double viewSecondsLimit;  // Meshlight: a view that is not within kViewTarget by then is shown as it is
    int viewCyclesMaxSpp;     // Cycles per view: extrapolated past this
};

Workload workloadFor(bool quick) {
    if (quick) return {64, 128, 3, {0.5, 1, 2, 3}, 0, 64, 5, 3, 32, 128, 3, 256};
    // 3, 10 and 40 s join the issue's times, to read the targets off directly.
    // Measured on 2 shared cores (load 4-8): the references 2 x 70-80 s;
    // Cycles to 1024 spp ~190 s; a view reference of 256 spp at 128x128
    // 3-6 s (its noise, ~3%, is taken out of each view's error); Cycles per
    // view at 128x128: 256 spp ~8 s, beyond it the time is extrapolated
    // (error ∝ 1/√spp, as the still curve shows), which keeps the
    // walkthrough's Cycles part near 5 minutes and the bench near 17.
    return {256, 1024, 120, {0.5, 1, 2, 3, 5, 7, 10, 15, 20, 30, 40, 60, 90, 120}, 10, 4096, 120,
            30, 128, 256, 30, 256};
}

PathTracerSettings tracerSettings(uint32_t seed) {
    PathTracerSettings s;
    s.maxDepth = kMaxDepth;
    s.threads = 0;  // every core
    s.seed = seed;
    return s;
}

CompositorSettings renderComposite(int width, int height) {
    CompositorSettings c;
    c.width = width;
    c.height = height;
    c.supersample = kSupersample;
    c.passes = kSubpixelPasses;
    c.outlinePasses = kRenderOutlinePasses;
    return c;
}

// --- The curves ------------------------------------------------------------------------

// An image of any method on the still view.
struct CurvePoint {
    double seconds = 0;  // wall clock since the method started, to the image being ready
    ImageError error;
    int spp = 0;  // path tracer and Cycles
    // Meshlight
    double estimatedError = 0;  // the cache's own (CacheSnapshot::estimatedError): what the worker schedules by
    // The image's (viewer/compositor/ImageErrorEstimate.h): what `render
    // --until-error` stops on; 1 while no bounce is shown (as render reads
    // it), < 0 where not made.
    double imageEstimate = -1;
    double compositeSeconds = 0;
    size_t vertices = 0, indirectVertices = 0;
    uint64_t samples = 0;
    int bouncesFinished = 0, bounces = 0;
    // Cycles
    double cpuSeconds = 0;
};

struct Curve {
    std::string method;  // "meshlight", "path-tracer", "cycles"
    std::vector<CurvePoint> points;
    std::string skipped;  // why there is no curve ("" when there is)
};

// When a curve first reaches `level`, or, past its last image, how long it
// would take as an unbiased estimator's error falls (time × (error/level)²).
struct LevelTime {
    std::optional<double> measured;
    std::optional<double> extrapolated;  // only for the path tracer and Cycles, when not measured
};

LevelTime levelTime(const Curve& c, double level, bool unbiased) {
    LevelTime t;
    if (c.points.empty()) return t;
    std::vector<double> seconds, errors;
    for (const CurvePoint& p : c.points) {
        seconds.push_back(p.seconds);
        errors.push_back(p.error.corrected);
    }
    t.measured = timeToLevel(seconds, errors, level);
    if (!t.measured && unbiased) {
        const CurvePoint& last = c.points.back();
        const double e = last.error.corrected / level;
        t.extrapolated = last.seconds * e * e;
    }
    return t;
}

std::string levelCell(const LevelTime& t) {
    if (t.measured) return benchNumber(*t.measured);
    if (t.extrapolated) return concat("~", benchNumber(*t.extrapolated));
    return "not reached";
}

// --- The still view: references and the path tracer --------------------------------------

struct StillResult {
    Reference reference;  // A and B together
    Reference referenceB;
    double referenceBSeconds = 0;
    Curve meshlight{"meshlight", {}, ""}, path{"path-tracer", {}, ""}, cycles{"cycles", {}, ""};
    int meshlightBounces = 0;
    std::string indirectMethod;
    double cacheBuildSeconds = 0;
    // `meshlight render --time T` as typed (full run only).
    double renderCheckWall = 0;
    ImageError renderCheckError;
    std::string renderCheckCommand;
};

void renderReferences(const BenchRun& run, const Workload& work, const Scene& scene, const Camera& camera,
                      StillResult& r) {
    const uint32_t seed = run.options().seed;
    {
        run.progress("reference B: %d spp at %dx%d (load %s)\n", work.referenceSpp, work.size, work.size,
                     loadAverage().c_str());
        const EmbreeScene rays(scene);
        r.referenceB = renderReference(rays, camera, work.size, work.size, work.referenceSpp,
                                       tracerSettings(seedFor(seed, 0x6e1bu)));
    }
    std::printf("reference B: %d spp in %.1f s, relative noise %.3f%%\n", r.referenceB.spp, r.referenceB.seconds,
                100 * r.referenceB.noise);

    // The path tracer's curve is reference A in the making, timed, against B.
    run.progress("path tracer: doubling to %d spp (load %s)\n", work.referenceSpp, loadAverage().c_str());
    const Clock::time_point t = Clock::now();
    const EmbreeScene rays(scene);  // its own, timed as part of its work
    const double setup = secondsSince(t);
    DoublingPathTracer tracer(rays, camera, work.size, work.size, tracerSettings(seedFor(seed, 0x6e1au)));
    while (tracer.spp() < work.referenceSpp) {
        tracer.step();
        CurvePoint p;
        p.seconds = setup + tracer.seconds();
        p.spp = tracer.spp();
        p.error = errorAgainst(tracer.image(), r.referenceB);
        p.estimatedError = tracer.ownNoise(r.referenceB.radiance);
        r.path.points.push_back(p);
        std::printf("  path tracer %7.2f s: %5d spp, relative RMSE %6.3f%% (raw %6.3f%%, against B), own noise "
                    "%.3f%%\n",
                    p.seconds, p.spp, 100 * p.error.corrected, 100 * p.error.raw, 100 * p.estimatedError);
    }
    r.reference = averageReferences(tracer.asReference(), r.referenceB);
    std::printf("reference: A (%d spp, %.1f s) and B (%d spp, %.1f s) averaged: %d spp, relative noise %.3f%%\n",
                tracer.spp(), tracer.seconds(), r.referenceB.spp, r.referenceB.seconds, r.reference.spp,
                100 * r.reference.noise);
    writeImageLinear((run.dir() / "gi_reference.exr").string(), r.reference.radiance);
    writeImageLinear((run.dir() / "gi_reference.noise.exr").string(), r.reference.standardError);
}

// --- Meshlight as `render` runs it (RenderLikeSession.h) ------------------------------------

// The snapshot of each checkpoint is copied as it is taken and composited
// once the worker has stopped: `render` composites once, after stopping the
// worker, and a composite made while the worker runs would take its cores.
// An image counts as ready at its checkpoint plus its composite time.
ImageRgb runMeshlightStill(const BenchRun& run, const Workload& work, const Scene& scene, const Camera& camera,
                           Compositor& compositor, StillResult& r) {
    const RenderLikeSession how = renderLikeSession(run, scene);
    r.meshlightBounces = how.bounces();
    r.indirectMethod = how.indirect.active() ? how.indirect.describe() : std::string("none");
    struct Taken {
        CurvePoint point;
        std::vector<IrradianceMeshCopy> direct, indirect;
        bool lacksBounces = false;  // no bounce shown yet: the image's estimate reads 1
    };
    std::vector<Taken> taken;
    run.progress("meshlight: %g s (load %s)\n", work.meshlightSeconds, loadAverage().c_str());
    {
        const Clock::time_point start = Clock::now();
        StopRule stop;
        stop.seconds = work.meshlightSeconds;
        ProgressiveSession session(scene, how.settings, samplerFactory(scene, how.direct, how.indirect), stop);
        r.cacheBuildSeconds = secondsSince(start);
        session.start(RefinementCamera{camera, work.size, work.size});
        CacheWorker::Reader reader = session.reader();
        for (double due : work.checkpoints) {
            const CacheSnapshot* s = snapshotAt(session, reader, start, due);
            Taken t;
            t.point.seconds = secondsSince(start);
            t.point.estimatedError = s->estimatedError;
            t.point.vertices = s->vertices;
            t.point.indirectVertices = s->indirectVertices;
            t.point.samples = s->samples;
            t.point.bouncesFinished = s->bouncesFinished;
            t.point.bounces = s->bounces;
            t.direct = s->direct;
            t.indirect = s->indirect;
            t.lacksBounces = lacksBounces(*s, how.indirect.active());
            taken.push_back(std::move(t));
        }
        session.stop();
        session.rethrowIfFailed();
    }
    const CompositorSettings comp = renderComposite(work.size, work.size);
    ImageRgb image;
    for (Taken& t : taken) {
        const Clock::time_point c = Clock::now();
        image = compositor.render(camera, t.direct, t.indirect, comp);
        CurvePoint p = t.point;
        p.compositeSeconds = secondsSince(c);
        p.seconds += p.compositeSeconds;
        p.error = errorAgainst(image, r.reference);
        // Not timed: a user's render makes it only where asked to stop on it.
        p.imageEstimate =
            t.lacksBounces ? 1.0 : estimateCacheError(compositor, scene, camera, t.direct, t.indirect, comp, image);
        t.direct = {};
        t.indirect = {};
        r.meshlight.points.push_back(p);
        std::printf("  meshlight   %7.2f s: relative RMSE %6.3f%% (raw %6.3f%%), image's estimate %6.3f%%, cache's "
                    "%6.3f%%, %zu vertices (%zu indirect), bounces %d/%d; composite %.2f s\n",
                    p.seconds, 100 * p.error.corrected, 100 * p.error.raw, 100 * p.imageEstimate,
                    100 * p.estimatedError, p.vertices, p.indirectVertices, p.bouncesFinished, p.bounces,
                    p.compositeSeconds);
    }
    return image;
}

// `meshlight render --time T` as a user types it; its process wall time
// (start-up, scene, session, refinement, composite, the EXR) and error.
void runRenderCheck(const BenchRun& run, const Workload& work, StillResult& r) {
    const fs::path out = run.dir() / concat("gi_render_", work.renderCheckSeconds, "s.exr");
    r.renderCheckCommand = concat("render cornell --width ", work.size, " --height ", work.size, " --time ",
                                  work.renderCheckSeconds, " --seed ", run.options().seed, " --gl ",
                                  glBackendName(run.options().backend), " --layers none --out ");
    run.progress("meshlight %s%s (load %s)\n", r.renderCheckCommand.c_str(), out.filename().c_str(),
                 loadAverage().c_str());
    const Clock::time_point t = Clock::now();
    runSelf(r.renderCheckCommand + shellQuoted(out.string()), run.dir() / "gi_render_check.log");
    r.renderCheckWall = secondsSince(t);
    r.renderCheckError = errorAgainst(readImageLinear(out.string()), r.reference);
    r.renderCheckCommand += fs::path(out).filename().string();
    std::printf("  meshlight %s: process wall %.2f s, relative RMSE %.3f%% (raw %.3f%%)\n",
                r.renderCheckCommand.c_str(), r.renderCheckWall, 100 * r.renderCheckError.corrected,
                100 * r.renderCheckError.raw);
}

// --- Cycles --------------------------------------------------------------------------------

struct CyclesState {
    std::optional<CyclesSetup> setup;
    std::unique_ptr<CyclesRunner> runner;
    std::string skipped;  // why Cycles was not run, or stopped ("" while it can run)
    double startupSeconds = 0;  // Blender's start, the scene, and a first 16x16 render at 1 spp
    double warmUpSeconds = 0;
    Camera warmUpCamera;
    std::string version;

    // The runner, started on first use; null (skipped says why) when it cannot be.
    CyclesRunner* get(const BenchRun& run) {
        if (!skipped.empty()) return nullptr;
        if (!runner) {
            try {
                runner = std::make_unique<CyclesRunner>(*setup, kCyclesBounces, 0, run.dir() / "cycles.log");
            } catch (const std::exception& e) {
                fail(e);
                return nullptr;
            }
            // Cycles' first render in a process loads and sets up its kernels: a one-off cost, timed with the
            // start-up, not with the first image.
            try {
                const Clock::time_point t = Clock::now();
                runner->render(warmUpCamera, 16, 16, 1, 0, run.dir() / "gi_cycles_warmup.exr");
                warmUpSeconds = secondsSince(t);
            } catch (const std::exception& e) {
                fail(e);
                return nullptr;
            }
            startupSeconds = runner->startupSeconds() + warmUpSeconds;
            version = runner->version();
            std::printf("cycles: Blender %s (%s) ready in %.2f s (start-up, scene and a first render, not "
                        "counted)\n",
                        version.c_str(), setup->blender.c_str(), startupSeconds);
        }
        return runner.get();
    }
    void fail(const std::exception& e) {
        skipped = concat("Blender failed: ", e.what());
        std::printf("note: %s; Cycles skipped from here on (never a failure of the bench)\n", skipped.c_str());
        runner.reset();
    }
};

void runCyclesStill(const BenchRun& run, const Workload& work, const Camera& camera, CyclesState& cycles,
                    StillResult& r) {
    CyclesRunner* runner = cycles.get(run);
    if (!runner) {
        r.cycles.skipped = cycles.skipped;
        return;
    }
    run.progress("cycles: doubling from 1 spp (load %s)\n", loadAverage().c_str());
    try {
        for (int spp = 1; spp <= work.cyclesMaxSpp; spp *= 2) {
            const CyclesRender c = runner->render(camera, work.size, work.size, spp, 0, run.dir() / "gi_cycles.exr");
            CurvePoint p;
            p.seconds = c.seconds;
            p.cpuSeconds = c.cpuSeconds;
            p.spp = spp;
            p.error = errorAgainst(c.image, r.reference);
            r.cycles.points.push_back(p);
            std::printf("  cycles      %7.2f s: %5d spp, relative RMSE %6.3f%% (raw %6.3f%%); CPU %.2f s, load %s\n",
                        p.seconds, spp, 100 * p.error.corrected, 100 * p.error.raw, p.cpuSeconds,
                        loadAverage().c_str());
            // The next render takes about twice as long: not started past the cap.
            if (p.error.corrected <= kLevels.back() || 2 * c.seconds > work.cyclesMaxRenderSeconds) break;
        }
    } catch (const std::exception& e) {
        cycles.fail(e);
        if (r.cycles.points.empty()) r.cycles.skipped = cycles.skipped;
    }
}

// --- The walkthrough --------------------------------------------------------------------

struct CyclesTry {
    int spp = 0;
    double seconds = 0;
    ImageError error;
};

// Cycles' time on one view at one error: interpolated between the renders
// that bracket it, or bounded / extrapolated where none does.
struct CyclesAtError {
    double seconds = 0;
    std::string how;  // "interpolated", "at most (1 spp already below)", "extrapolated from N spp"
    int sppBelow = 0;  // the fewest samples per pixel measured at or below the error (0: none)
};

// Meshlight's view (ViewShown: from setCamera, the first view's from before
// the session, to the passing composite), its reference, and Cycles'.
struct ViewResult : ViewShown {
    double referenceSeconds = 0;
    double referenceNoise = 0;
    // Cycles
    std::vector<CyclesTry> tries;  // by samples per pixel
    double cyclesLevel = 0;        // the error Cycles is held to: Meshlight's, floored (see runWalkthrough)
    std::optional<CyclesAtError> atMeshlight, atTarget;
};

struct WalkResult {
    int size = 0;
    std::vector<ViewResult> views;
    double cacheBuildSeconds = 0;
    double referenceSeconds = 0;
    double referenceNoiseMax = 0;
    std::string cyclesSkipped;
    double meshlightTotal() const {
        double s = 0;
        for (const ViewResult& v : views) s += v.seconds;
        return s;
    }
    double maxError() const {
        double e = 0;
        for (const ViewResult& v : views) e = std::max(e, v.error.corrected);
        return e;
    }
    bool allReached() const {
        return std::all_of(views.begin(), views.end(), [](const ViewResult& v) { return v.reached; });
    }
    bool cyclesMeasured() const {
        return !views.empty() &&
               std::all_of(views.begin(), views.end(), [](const ViewResult& v) { return bool(v.atMeshlight); });
    }
    double cyclesTotal(bool target) const {
        double s = 0;
        for (const ViewResult& v : views) s += target ? v.atTarget->seconds : v.atMeshlight->seconds;
        return s;
    }
};

CyclesAtError cyclesAt(const std::vector<CyclesTry>& tries, double level) {
    // tries sorted by spp
    CyclesAtError a;
    std::vector<double> seconds, errors;
    for (const CyclesTry& t : tries) {
        seconds.push_back(t.seconds);
        errors.push_back(t.error.corrected);
        if (!a.sppBelow && t.error.corrected <= level) a.sppBelow = t.spp;
    }
    if (tries.front().error.corrected <= level) {
        a.seconds = tries.front().seconds;
        a.how = concat("at most (", tries.front().spp, " spp already there)");
    } else if (const std::optional<double> t = timeToLevel(seconds, errors, level)) {
        a.seconds = *t;
        a.how = "interpolated";
    } else {
        const CyclesTry& last = tries.back();
        const double e = last.error.corrected / level;
        a.seconds = last.seconds * e * e;
        a.how = concat("extrapolated from ", last.spp, " spp");
    }
    return a;
}

// Renders the view at doubling (or halving) samples per pixel, from `start`,
// until two neighbouring counts bracket `level` (or 1 spp is already below,
// or `maxSpp` is not); renders already in `tries` are not made again.
void bracketCycles(CyclesRunner& runner, const BenchRun& run, const Camera& camera, int size, const Reference& ref,
                   double level, int start, int maxSpp, std::vector<CyclesTry>& tries) {
    auto find = [&](int spp) -> const CyclesTry* {
        for (const CyclesTry& t : tries)
            if (t.spp == spp) return &t;
        return nullptr;
    };
    auto at = [&](int spp) -> const CyclesTry& {
        if (const CyclesTry* t = find(spp)) return *t;
        const CyclesRender c = runner.render(camera, size, size, spp, 0, run.dir() / "gi_walk_cycles.exr");
        tries.push_back({spp, c.seconds, errorAgainst(c.image, ref)});
        std::sort(tries.begin(), tries.end(), [](const CyclesTry& a, const CyclesTry& b) { return a.spp < b.spp; });
        return *find(spp);
    };
    int spp = std::clamp(start, 1, maxSpp);
    for (;;) {
        const bool below = at(spp).error.corrected <= level;
        if (below) {
            if (spp == 1) return;
            const CyclesTry* fewer = find(spp / 2);
            if (fewer && fewer->error.corrected > level) return;
            spp /= 2;
        } else {
            if (spp * 2 > maxSpp) return;
            const CyclesTry* more = find(spp * 2);
            if (more && more->error.corrected <= level) return;
            spp *= 2;
        }
    }
}

WalkResult runWalkthrough(const BenchRun& run, const Workload& work, const Scene& scene, Compositor& compositor,
                          CyclesState& cycles) {
    WalkResult r;
    r.size = work.viewSize;
    const uint32_t seed = run.options().seed;
    const std::vector<Camera> cameras = walkthroughCameras(scene, work.views);
    const EmbreeScene rays(scene);
    checkViewsInside(rays, cameras, work.viewSize, work.viewSize);
    r.views.resize(cameras.size());

    // The references first, so that nothing else runs while Meshlight and Cycles are timed.
    const ViewReferences references = renderViewReferences(run, rays, cameras, work.viewSize, work.viewSize,
                                                           work.viewReferenceSpp, tracerSettings(seed), 0x71e0u);
    const std::vector<Reference>& refs = references.views;
    r.referenceSeconds = references.seconds;
    r.referenceNoiseMax = references.noiseMax;
    for (size_t v = 0; v < cameras.size(); ++v) {
        r.views[v].referenceSeconds = refs[v].seconds;
        r.views[v].referenceNoise = refs[v].noise;
    }

    // Meshlight: one cache from cold, refined while the views are shown.
    run.progress("walkthrough: meshlight (load %s)\n", loadAverage().c_str());
    r.cacheBuildSeconds = walkViewsUntilWithin(
        scene, renderLikeSession(run, scene), compositor, cameras, renderComposite(work.viewSize, work.viewSize), refs,
        kViewTarget, work.viewSecondsLimit, work.viewSecondsLimit, [&](size_t v, ViewShown&& shown) {
            ViewResult& out = r.views[v];
            static_cast<ViewShown&>(out) = std::move(shown);
            std::printf("  view %2zu meshlight %6.2f s (%d composite%s, %.2f s): relative RMSE %6.3f%% (raw "
                        "%.3f%%), estimated %.3f%%, %zu vertices%s\n",
                        v, out.seconds, out.composites, out.composites == 1 ? "" : "s", out.compositeSeconds,
                        100 * out.error.corrected, 100 * out.error.raw, 100 * out.estimatedError, out.vertices,
                        out.reached ? "" : " (time limit)");
        });

    // Cycles: per view, to the error Meshlight reached there, and to the target.
    CyclesRunner* runner = cycles.get(run);
    if (!runner) {
        r.cyclesSkipped = cycles.skipped;
        return r;
    }
    run.progress("walkthrough: cycles (load %s)\n", loadAverage().c_str());
    // Where to start each search: Cycles' error falls as 1/√spp (the still curve: ×1.42–1.45 per doubling from
    // 128 to 1024 spp), so error² × spp from the last view's densest render predicts the count for a level.
    double k = 0;
    auto guess = [&](double level) {
        if (k <= 0) return 4;
        return int(std::exp2(std::round(std::log2(std::max(1.0, k / (level * level))))));
    };
    try {
        for (size_t v = 0; v < cameras.size(); ++v) {
            ViewResult& out = r.views[v];
            // The error Meshlight reached, but not below a quarter of the view reference's noise: under it the
            // corrected error (a difference of two near-equal sums) can come out near zero.
            const double level = std::max(out.error.corrected, 0.25 * refs[v].noise);
            out.cyclesLevel = level;
            bracketCycles(*runner, run, cameras[v], work.viewSize, refs[v], level, guess(level),
                          work.viewCyclesMaxSpp, out.tries);
            out.atMeshlight = cyclesAt(out.tries, level);
            bracketCycles(*runner, run, cameras[v], work.viewSize, refs[v], kViewTarget, guess(kViewTarget),
                          work.viewCyclesMaxSpp, out.tries);
            out.atTarget = cyclesAt(out.tries, kViewTarget);
            const CyclesTry& densest = out.tries.back();
            if (densest.error.corrected > 0) k = densest.error.corrected * densest.error.corrected * densest.spp;
            std::string tried;
            for (const CyclesTry& t : out.tries)
                tried += concat(tried.empty() ? "" : ", ", t.spp, " spp ", benchNumber(t.seconds), " s ",
                                benchPct(t.error.corrected), "%");
            std::printf("  view %2zu cycles: %.2f s at %.3f%% (Meshlight's %.3f%%, floor %.3f%%) (%s), %.2f s at "
                        "%g%% (%s); tried %s\n",
                        v, out.atMeshlight->seconds, 100 * level, 100 * out.error.corrected, 25 * refs[v].noise,
                        out.atMeshlight->how.c_str(), out.atTarget->seconds,
                        100 * kViewTarget, out.atTarget->how.c_str(), tried.c_str());
        }
    } catch (const std::exception& e) {
        cycles.fail(e);
        r.cyclesSkipped = cycles.skipped;
        for (ViewResult& v : r.views) v.atMeshlight.reset(), v.atTarget.reset();
    }
    return r;
}

// --- Tables --------------------------------------------------------------------------------

BenchTable curvesTable(const StillResult& r) {
    BenchTable t({"method", "seconds", "spp", "relative_rmse_pct", "raw_relative_rmse_pct", "estimated_error_pct",
                  "vertices", "indirect_vertices", "samples", "bounces_done", "composite_ms", "cpu_s",
                  "image_estimated_error_pct"});
    for (const Curve* c : {&r.meshlight, &r.path, &r.cycles})
        for (const CurvePoint& p : c->points) {
            const bool ml = c->method == "meshlight";
            t.addRow({c->method, benchNumber(p.seconds), ml ? "" : std::to_string(p.spp), benchPct(p.error.corrected),
                      benchPct(p.error.raw),
                      c->method == "cycles" ? "" : benchPct(p.estimatedError), ml ? std::to_string(p.vertices) : "",
                      ml ? std::to_string(p.indirectVertices) : "", ml ? std::to_string(p.samples) : "",
                      ml ? concat(p.bouncesFinished, "/", p.bounces) : "", ml ? benchMs(p.compositeSeconds) : "",
                      c->method == "cycles" ? benchNumber(p.cpuSeconds) : "",
                      ml && p.imageEstimate >= 0 ? benchPct(p.imageEstimate) : ""});
        }
    return t;
}

BenchTable levelsTable(const StillResult& r) {
    BenchTable t({"level_pct", "meshlight_s", "path_tracer_s", "cycles_s", "cycles_over_meshlight"});
    for (double level : kLevels) {
        const LevelTime m = levelTime(r.meshlight, level, false), p = levelTime(r.path, level, true),
                        c = levelTime(r.cycles, level, true);
        std::string ratio = "-";
        const std::optional<double> cs = c.measured ? c.measured : c.extrapolated;
        if (m.measured && cs) ratio = concat(c.measured ? "" : "~", benchNumber(*cs / *m.measured));
        t.addRow({benchPct(level), levelCell(m), levelCell(p),
                  r.cycles.points.empty() ? std::string("skipped") : levelCell(c), ratio});
    }
    return t;
}

BenchTable walkTable(const WalkResult& w) {
    BenchTable t({"view", "meshlight_s", "composites", "composite_s", "relative_rmse_pct", "raw_relative_rmse_pct",
                  "estimated_error_pct", "within_target", "reference_noise_pct", "cycles_level_pct",
                  "cycles_s_same_error",
                  "cycles_how", "cycles_s_at_target", "cycles_spp_tried"});
    for (size_t v = 0; v < w.views.size(); ++v) {
        const ViewResult& x = w.views[v];
        std::string tried;
        for (const CyclesTry& c : x.tries) tried += concat(tried.empty() ? "" : " ", c.spp);
        t.addRow({std::to_string(v), benchNumber(x.seconds), std::to_string(x.composites),
                  benchNumber(x.compositeSeconds), benchPct(x.error.corrected), benchPct(x.error.raw),
                  benchPct(x.estimatedError), benchYesNo(x.reached), benchPct(x.referenceNoise),
                  x.atMeshlight ? benchPct(x.cyclesLevel) : "-",
                  x.atMeshlight ? benchNumber(x.atMeshlight->seconds) : "skipped",
                  x.atMeshlight ? x.atMeshlight->how : "-", x.atTarget ? benchNumber(x.atTarget->seconds) : "skipped",
                  tried.empty() ? "-" : tried});
    }
    return t;
}

// `s` as a table cell: no comma, quote or line break (a message from Blender may hold them).
std::string tableCell(std::string s) {
    for (char& c : s)
        if (c == ',') c = ';';
        else if (c == '"' || c == '\n' || c == '\r') c = ' ';
    return s;
}

std::vector<BenchTarget> targetRows(const StillResult& r, const WalkResult& w, const Workload& work, bool quick) {
    std::vector<BenchTarget> rows;
    // Quick runs are another size and budget: they run the bench, they do not judge it.
    auto status = [&](const std::string& s) { return quick ? std::string("quick run: not judged") : s; };
    const std::string size = concat(work.size, "x", work.size);
    for (const TimeTarget& target : kTimeTargets) {
        const LevelTime m = levelTime(r.meshlight, target.level, false);
        const std::string name = concat("Cornell ", size, ": ", benchPct(target.level), "% within ", target.seconds,
                                        " s");
        if (m.measured)
            rows.push_back({name, concat(benchNumber(*m.measured), " s"),
                            status(*m.measured <= target.seconds ? "met" : "not met")});
        else
            rows.push_back({name, concat("not reached in ", work.meshlightSeconds, " s"),
                            status(work.meshlightSeconds >= target.seconds ? "not met" : "not measured")});
    }
    {
        const LevelTime m = levelTime(r.meshlight, kPlateauLevel, false);
        const std::string name = concat("no plateau: falls to ", benchPct(kPlateauLevel), "% given time");
        const CurvePoint& last = r.meshlight.points.back();
        // The slope of log error against log time over the last doubling of time or more.
        std::string slope;
        for (size_t i = r.meshlight.points.size(); i-- > 0;) {
            const CurvePoint& p = r.meshlight.points[i];
            if (p.seconds <= last.seconds / 2 && p.error.corrected > 0 && last.error.corrected > 0) {
                slope = concat("; slope of log error in log time from ", benchNumber(p.seconds), " s: ",
                               benchNumber(std::log(last.error.corrected / p.error.corrected) /
                                           std::log(last.seconds / p.seconds)));
                break;
            }
        }
        if (m.measured)
            rows.push_back({name, concat(benchNumber(*m.measured), " s", slope), status("met")});
        else
            rows.push_back({name, concat("not reached in ", work.meshlightSeconds, " s: ",
                                         benchPct(last.error.corrected), "% at ", benchNumber(last.seconds), " s",
                                         slope),
                            status("not met")});
    }
    {
        std::vector<EstimatePoint> points;
        for (const CurvePoint& p : r.meshlight.points)
            points.push_back({p.seconds, p.error.corrected, p.imageEstimate});
        BenchTarget row = issueEstimateTarget("", points);
        row.status = status(row.status);
        rows.push_back(row);
    }
    const std::string views = concat(w.views.size(), " views ", w.size, "x", w.size);
    rows.push_back({concat("walkthrough (", views, "): each within ", benchPct(kViewTarget), "%"),
                    concat("worst ", benchPct(w.maxError()), "%", w.allReached() ? "" : " (some views hit the limit)"),
                    status(w.allReached() ? "met" : "not met")});
    const std::string speed = concat("walkthrough: >= ", kWalkSpeedup, "x less total time than Cycles at the same "
                                     "error");
    if (!w.cyclesMeasured()) {
        rows.push_back({speed, concat("Meshlight ", benchNumber(w.meshlightTotal()), " s; Cycles skipped"),
                        concat("not measured (", tableCell(w.cyclesSkipped), ")")});
    } else {
        const double ratio = w.cyclesTotal(false) / w.meshlightTotal();
        rows.push_back({speed,
                        concat("Meshlight ", benchNumber(w.meshlightTotal()), " s; Cycles ",
                               benchNumber(w.cyclesTotal(false)), " s: ", benchNumber(ratio), "x"),
                        status(ratio >= kWalkSpeedup ? "met" : "not met")});
        // The same with Cycles held only to the target on every view, not to Meshlight's (lower) error: what
        // Cycles needs for views a user would accept, a lower bar than the target's.
        const double atTarget = w.cyclesTotal(true) / w.meshlightTotal();
        rows.push_back({concat("walkthrough: the same with Cycles at ", benchPct(kViewTarget), "% per view"),
                        concat("Cycles ", benchNumber(w.cyclesTotal(true)), " s: ", benchNumber(atTarget), "x"),
                        concat("not a target (", atTarget >= kWalkSpeedup ? ">=" : "<", " ", kWalkSpeedup, "x)")});
    }
    return rows;
}

// --- Plots ------------------------------------------------------------------------------

const std::vector<GnuplotOutput> kPlots = {
    {"out_error", "gi_error_vs_time.png"},
    {"out_walk", "gi_walkthrough.png"},
};

std::string gnuplotScript(const StillResult& r, const WalkResult& w, const Workload& work) {
    std::ostringstream gp;
    gp << "# Written by 'meshlight bench gi'; run with gnuplot in this folder.\n"
       << gnuplotOutputDefaults(kPlots)
       << "set terminal pngcairo enhanced size 1200,800 font ',11'\n"
          "set datafile separator ','\n"
          "set grid\n\n";
    const Curve* curves[] = {&r.meshlight, &r.path, &r.cycles};
    const char* names[] = {"ml", "pt", "cy"};
    for (size_t i = 0; i < 3; ++i) {
        gp << "# " << curves[i]->method << ": seconds, relative RMSE % (noise-corrected), spp\n$" << names[i]
           << " << EOD\n";
        for (const CurvePoint& p : curves[i]->points)
            gp << benchNumber(p.seconds) << "," << benchPct(std::max(p.error.corrected, 1e-4)) << "," << p.spp
               << "\n";
        gp << "EOD\n";
    }
    gp << "# meshlight: seconds, the image's estimated error %\n$mlest << EOD\n";
    for (const CurvePoint& p : r.meshlight.points)
        if (p.imageEstimate > 0 && p.imageEstimate < 1)
            gp << benchNumber(p.seconds) << "," << benchPct(p.imageEstimate) << "\n";
    gp << "EOD\n";
    gp << "# the issue's targets: seconds, level %\n$targets << EOD\n";
    for (const TimeTarget& t : kTimeTargets) gp << t.seconds << "," << benchPct(t.level) << "\n";
    gp << "EOD\n\n";
    gp << "set output out_error\n"
          "set title 'Cornell box " << work.size << "x" << work.size << ", full GI (depth " << kMaxDepth
       << " = Cycles " << kCyclesBounces << " bounces): relative RMSE against a " << r.reference.spp
       << "-spp reference, its " << benchPct(r.reference.noise) << "% noise taken out'\n"
          "set logscale xy\n"
          "set xlabel 'wall-clock seconds (Cycles: render time, Blender start-up excluded)'\n"
          "set ylabel 'relative RMSE (%)'\n"
          "set key inside right top box opaque\n"
          "plot $ml using 1:2 with linespoints lc rgb '#1f5fa8' pt 7 ps 1.1 title 'Meshlight (render)', \\\n"
          "     $mlest using 1:2 with linespoints dt 3 lc rgb '#1f5fa8' pt 6 ps 1.0 title 'Meshlight: its own estimate "
          "of that error', \\\n"
          "     $pt using 1:2 with linespoints dt 2 lc rgb '#c0392b' pt 5 ps 1.0 title 'Meshlight path tracer', \\\n"
          "     $pt using 1:2:(sprintf('%d', $3)) with labels offset 0,-1 font ',8' tc rgb '#c0392b' notitle";
    if (!r.cycles.points.empty())
        gp << ", \\\n     $cy using 1:2 with linespoints dt 4 lc rgb '#1e8449' pt 9 ps 1.2 title 'Blender Cycles "
              "(CPU)', \\\n     $cy using 1:2:(sprintf('%d', $3)) with labels offset 0,1 font ',8' tc rgb '#1e8449' "
              "notitle";
    gp << ", \\\n     $targets using 1:2 with points pt 12 ps 2.5 lc rgb 'black' title 'targets: 5% in 3 s, 2% in "
          "10 s, 1% in 40 s'";
    for (size_t k = 0; k < kLevels.size(); ++k)
        gp << ", \\\n     " << benchPct(kLevels[k]) << " with lines dt 3 lc rgb 'gray50' "
           << (k ? "notitle" : "title 'levels: 5, 2, 1, 0.5%'");
    gp << "\n\n";

    gp << "# view, meshlight s, cycles s at the same error (NaN: skipped), meshlight error %, cycles at 3% s\n"
          "$walk << EOD\n";
    for (size_t v = 0; v < w.views.size(); ++v) {
        const ViewResult& x = w.views[v];
        gp << v << "," << benchNumber(x.seconds) << ","
           << (x.atMeshlight ? benchNumber(x.atMeshlight->seconds) : std::string("NaN")) << ","
           << benchPct(x.error.corrected) << "," << (x.atTarget ? benchNumber(x.atTarget->seconds) : "NaN") << "\n";
    }
    gp << "EOD\n"
          "set datafile missing 'NaN'\n"
          "set output out_walk\n"
          "set multiplot layout 2,1 title 'Walkthrough, " << w.views.size() << " views " << w.size << "x" << w.size
       << ": one Meshlight cache from cold against Cycles per view'\n"
          "set key outside right top noopaque nobox\n"
          "unset logscale x\n"
          "set logscale y\n"
          "set xtics " << (w.views.size() <= 10 ? 1 : 5) << "\n"
          "set xlabel 'view'\n"
          "set ylabel 'seconds for the view'\n"
          "set title 'Time per view (Meshlight: every composite for the view; Cycles: interpolated at the error)'\n"
          "set key outside right top\n"
          "plot $walk using 1:2 with linespoints lc rgb '#1f5fa8' pt 7 title 'Meshlight'";
    if (w.cyclesMeasured())
        gp << ", \\\n     $walk using 1:3 with linespoints dt 4 lc rgb '#1e8449' pt 9 title 'Cycles, same error', "
              "\\\n     $walk using 1:5 with linespoints dt 2 lc rgb '#82c09a' pt 8 title 'Cycles, 3%'";
    gp << "\n"
          "unset logscale y\n"
          "set ylabel 'relative RMSE (%)'\n"
          "set title 'Meshlight: relative RMSE per view (the view reference noise taken out)'\n"
          "set yrange [0:" << benchPct(std::max(1.3 * kViewTarget, 1.15 * w.maxError())) << "]\n"
          "plot $walk using 1:4 with linespoints lc rgb '#1f5fa8' pt 7 title 'Meshlight', \\\n"
          "     " << benchPct(kViewTarget) << " with lines dt 3 lc rgb 'black' title 'target'\n"
          "unset multiplot\n";
    return gp.str();
}

// --- Summary ------------------------------------------------------------------------------

std::string summaryMarkdown(const BenchRun& run, double wallSeconds, const Workload& work, const StillResult& r,
                            const WalkResult& w, const CyclesState& cycles, const std::vector<BenchTarget>& targets,
                            const std::vector<std::string>& loads) {
    const unsigned threads = std::thread::hardware_concurrency();
    std::ostringstream md;
    md << "# Full global illumination: Meshlight, its path tracer and Blender Cycles\n\n"
       << "- scene: the built-in Cornell box, its own camera, " << work.size << "×" << work.size
       << " pixels; full global illumination: path depth " << kMaxDepth << " (emission, direct and "
       << kMaxDepth - 1 << " bounces) = Cycles max bounces " << kCyclesBounces << "\n"
       << "- mode: " << run.mode() << ", seed " << run.options().seed << ", " << threads
       << " hardware threads; OpenGL: " << run.glDescription() << "; wall time " << benchNumber(wallSeconds) << " s\n"
       << "- load average (1 min): " << run.loadAtStart() << " at the start";
    for (const std::string& l : loads) md << ", " << l;
    md << ", " << loadAverage() << " at the end (other processes slow every timing)\n"
       << softwareRasteriserNote(run.glDescription())
       << "- reference: the path tracer, two independent images of " << r.referenceB.spp
       << " spp averaged (" << r.reference.spp << " spp); its relative noise " << benchPct(r.reference.noise)
       << "% (sqrt(mean σ²/(r² + f)), f = min(0.1, mean r)² (ImageMetrics.h), σ from each pixel's even and odd samples), taken out of every error in "
          "quadrature: sqrt(max(0, mean((x − r)² − σ²)/(r² + f))); the raw value is in gi_curves.csv\n"
       << "- Meshlight: the session `meshlight render cornell` makes with its defaults (" << r.indirectMethod
       << "; " << r.meshlightBounces << " bounces; refinement tightened up to level "
       << IrradianceCache::kMaxRefinementLevel << "), the clock started before the cache is made; the snapshot at ";
    for (size_t i = 0; i < work.checkpoints.size(); ++i) md << (i ? ", " : "") << work.checkpoints[i];
    md << " s copied and composited as `render` composites (" << kSupersample << "×" << kSupersample
       << " sub-pixels, " << kSubpixelPasses << " shifted passes) once the worker has stopped; an image's time is "
          "its checkpoint plus its composite; then, untimed, the image's own estimate of its error "
          "(viewer/compositor/ImageErrorEstimate.h, what `render --until-error` stops on; image_estimated_error_pct "
          "in gi_curves.csv, dotted on the plot)\n";
    if (work.renderCheckSeconds > 0)
        md << "- check: `meshlight " << r.renderCheckCommand << "` as typed: " << benchPct(r.renderCheckError.corrected)
           << "% after " << benchNumber(r.renderCheckWall) << " s of process wall time (start-up, scene, GL, "
           << work.renderCheckSeconds << " s of refinement, composite, EXR)\n";
    md << "- path tracer: Meshlight's, depth " << kMaxDepth << ", " << threads
       << " threads, samples per pixel doubled from 2 (fresh streams, averaged); measured against the other "
          "reference image (B, noise "
       << benchPct(r.referenceB.noise) << "%), its time includes its BVH\n";
    if (cycles.version.empty())
        md << "- Blender Cycles: **skipped**: " << (cycles.skipped.empty() ? "not run" : cycles.skipped) << "\n";
    else
        md << "- Blender Cycles " << cycles.version << " (CPU, every core; viewer/bench/cycles/cornell_cycles.py "
              "--serve: the settings of viewer/bench/cycles/README.md) at doubling samples per pixel, each an "
              "image of its own; its time is the render's wall time in one Blender process "
              "(bpy.ops.render.render: scene sync, BVH, path tracing). **Blender's start-up is excluded** ("
           << benchNumber(cycles.startupSeconds)
           << " s here: Blender, the scene built once and a first 16×16 render that sets Cycles up): a user pays it "
              "once per session, as Meshlight's "
              "process start-up is excluded from its curve (both timed from the scene in memory); the EXR write "
              "is excluded too. Where a level was not reached, its time is extrapolated from the last image "
              "(time × (error/level)², marked ~)"
           << (cycles.skipped.empty() ? "" : concat("; then ", cycles.skipped)) << "\n";
    if (run.options().quick)
        md << "- quick mode runs the bench, it does not judge it: the image is smaller and the budget shorter; "
              "read the targets off a full run\n";
    md << "\n## Targets\n\n" << targetsTable(targets).markdown() << "\n";
    md << "## Time to each level (s)\n\n"
       << "Interpolated in log-log between the images around the level; ~: extrapolated (an unbiased estimator's "
          "error falls as 1/√time), \"not reached\": not within Meshlight's " << work.meshlightSeconds
       << " s.\n\n" << levelsTable(r).markdown() << "\n";
    md << "## Walkthrough\n\n"
       << "- " << w.views.size() << " views along the Cornell walkthrough (viewer/bench/CornellWalkthrough.h: from "
          "just inside the open front, dollying in and panning down to the blocks), " << w.size << "×" << w.size
       << " pixels; each against a path-traced reference of " << work.viewReferenceSpp << " spp (noise up to "
       << benchPct(w.referenceNoiseMax) << "%, taken out; " << benchNumber(w.referenceSeconds) << " s in all)\n"
       << "- Meshlight, as a user walking through gets it: one cache from cold (" << benchNumber(w.cacheBuildSeconds)
       << " s to make, counted in view 0), refining all along; at each view `setCamera`, then the latest snapshot "
          "composited as `render` composites, again at each new snapshot, until the view's measured error is "
          "within " << benchPct(kViewTarget) << "% (or " << work.viewSecondsLimit
       << " s): the bench stops on the measured error, which a user does not have (`render --until-error` stops "
          "on the image's estimate, ImageErrorEstimate.h; the column estimated_error_pct is the cache's own, "
          "surface-weighted, what the worker schedules by). A view's time counts every composite made "
          "for it. Total: **" << benchNumber(w.meshlightTotal()) << " s**, worst view " << benchPct(w.maxError())
       << "%\n";
    if (w.cyclesMeasured())
        md << "- Cycles, per view: samples per pixel doubled (or halved) until two neighbouring counts bracket "
              "Meshlight's error on that view (floored at a quarter of the view reference's noise), the time at "
              "that error interpolated in log-log between them (extrapolated as time × (error/level)² past "
           << work.viewCyclesMaxSpp << " spp); each render's wall time, Blender's "
              "start-up excluded (a walkthrough rendered as one animation pays it once). Total at the same error: "
              "**" << benchNumber(w.cyclesTotal(false)) << " s** (" << benchNumber(w.cyclesTotal(false) /
                                                                                     w.meshlightTotal())
           << "× Meshlight's); at " << benchPct(kViewTarget) << "% per view: " << benchNumber(w.cyclesTotal(true))
           << " s\n";
    else
        md << "- Cycles: **skipped** (" << w.cyclesSkipped << ")\n";
    md << "\n" << walkTable(w).markdown() << "\n"
       << "Every image of every method: gi_curves.csv; the reference and its noise: gi_reference.exr, "
          "gi_reference.noise.exr; Meshlight's last still image: gi_meshlight.exr; Blender's output: cycles.log.\n";
    return md.str();
}

}  // namespace

int runBenchGi(const BenchOptions& options) {
    BenchRun run(options);
    const Workload work = workloadFor(options.quick);
    const Scene scene = makeCornellBox();
    const Camera camera = scene.cameraOrDefault(1.0);
    // The compositor's context lives on this thread; the workers make their own.
    const std::unique_ptr<GlContext> context = run.openContext();
    Compositor compositor(*context, scene);

    CyclesState cycles;
    cycles.warmUpCamera = camera;
    {
        std::string why;
        cycles.setup = findCycles(why);
        if (!cycles.setup) {
            cycles.skipped = why;
            std::printf("note: Blender Cycles skipped: %s\n", why.c_str());
        }
    }
    std::vector<std::string> loads;

    StillResult still;
    renderReferences(run, work, scene, camera, still);
    loads.push_back(concat(loadAverage(), " after the references"));
    const ImageRgb last = runMeshlightStill(run, work, scene, camera, compositor, still);
    writeImageLinear((run.dir() / "gi_meshlight.exr").string(), last);
    loads.push_back(concat(loadAverage(), " after Meshlight"));
    if (work.renderCheckSeconds > 0) runRenderCheck(run, work, still);
    runCyclesStill(run, work, camera, cycles, still);
    if (!still.cycles.points.empty()) loads.push_back(concat(loadAverage(), " after Cycles"));

    const WalkResult walk = runWalkthrough(run, work, scene, compositor, cycles);
    cycles.runner.reset();  // Blender quits

    const std::vector<BenchTarget> targets = targetRows(still, walk, work, options.quick);
    const BenchTable curvesT = curvesTable(still), levelsT = levelsTable(still), walkT = walkTable(walk),
                     targetsT = targetsTable(targets);
    std::printf("\nTime to each level, seconds (relative RMSE against the %d-spp reference, its %.3f%% noise taken "
                "out; ~ extrapolated).\n\n%s",
                still.reference.spp, 100 * still.reference.noise, levelsT.aligned().c_str());
    std::printf("\nWalkthrough (%zu views %dx%d): Meshlight %.2f s in all", walk.views.size(), walk.size, walk.size,
                walk.meshlightTotal());
    if (walk.cyclesMeasured())
        std::printf(", Cycles %.2f s at the same error per view (%.2fx), %.2f s at %g%%", walk.cyclesTotal(false),
                    walk.cyclesTotal(false) / walk.meshlightTotal(), walk.cyclesTotal(true), 100 * kViewTarget);
    else
        std::printf("; Cycles skipped (%s)", walk.cyclesSkipped.c_str());
    std::printf(".\n\n%s", walkT.aligned().c_str());
    std::printf("\nTargets (issue 14).\n\n%s", targetsT.aligned().c_str());
    if (!cycles.version.empty())
        std::printf("Cycles' times exclude Blender's start-up (%.2f s, once per session) and the EXR write.\n",
                    cycles.startupSeconds);
    else
        std::printf("Blender Cycles skipped: %s.\n", cycles.skipped.c_str());

    run.writeCsv("gi_curves.csv", curvesT);
    run.writeCsv("gi_levels.csv", levelsT);
    run.writeCsv("gi_walkthrough.csv", walkT);
    run.writeCsv("gi_targets.csv", targetsT);
    run.plot("gi_plots.gp", gnuplotScript(still, walk, work), kPlots);
    const double wall = run.seconds();
    run.write("gi_summary.md", summaryMarkdown(run, wall, work, still, walk, cycles, targets, loads));
    std::printf("\n");
    run.printWallTime(wall);
    return 0;
}

}  // namespace ml
