#include "BenchDynamic.h"

#include "BenchRun.h"
#include "BenchStatistics.h"
#include "BenchTable.h"
#include "Gnuplot.h"
#include "SessionCheckpoints.h"

#include "cache/ProgressiveSession.h"
#include "cache/RealtimeIndirect.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/SceneChange.h"
#include "core/image/Image.h"
#include "core/image/ImageMetrics.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "core/scenes/CornellBox.h"
#include "core/scenes/OfficeScene.h"
#include "gpu_sampling/SamplerFactory.h"
#include "gpu_sampling/gl/GlContext.h"
#include "viewer/compositor/Compositor.h"
#include "viewer/window/ViewRefinement.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct Workload {
    int frameWidth = 1280, frameHeight = 720;  // the frames composited while moving
    int errorWidth = 160, errorHeight = 90;    // the images measured
    int spp = 256;                             // the path tracer's reference
    int steps = 6;                             // per motion
    double settle = 20;                        // s refined before the motion
    double limit = 20;                         // s followed after it
    double cold = 40;                          // s of the cold start (its last image: converged)
};

Workload workloadFor(bool quick) {
    Workload w;
    if (!quick) return w;
    w.frameWidth = 320, w.frameHeight = 180;
    w.errorWidth = 64, w.errorHeight = 36;
    w.spp = 64;
    w.steps = 3;
    w.settle = 6;
    w.limit = 8;
    w.cold = 12;
    return w;
}

// Images are taken this often after a motion stops (and from a cold start):
// finely while the cache catches up, where the targets are decided (a
// cold start reaches 2% in under a second), then coarser.
constexpr double kEveryEarly = 0.05, kEarly = 2.0, kEvery = 0.25;

// The times images are taken at, up to `limit` s.
std::vector<double> imageTimes(double limit) {
    std::vector<double> t;
    for (int i = 1; kEveryEarly * i <= kEarly + 1e-9 && kEveryEarly * i <= limit + 1e-9; ++i) t.push_back(kEveryEarly * i);
    for (double due = kEarly + kEvery; due <= limit + 1e-9; due += kEvery) t.push_back(due);
    return t;
}
// A step is applied this long after the one before was, at the soonest.
constexpr double kStepInterval = 0.25;

struct Motion {
    std::string name;
    bool office = false;  // the scene: the built-in office (12 panels) or the Cornell box
    std::vector<SceneChange> steps;
};

Scene sceneOf(const Motion& m) { return m.office ? makeOfficeScene() : makeCornellBox(); }

// The light the office's panel motion moves: the panel nearest the middle
// of the room's (+x) half, in the middle of the camera's view.
size_t officePanel(const Scene& office) {
    const Vec3 aim(1.0, office.bounds.hi.y, 0.0);
    size_t best = 0;
    for (size_t i = 1; i < office.lights.size(); ++i)
        if (glm::length(office.lights[i].centroid - aim) < glm::length(office.lights[best].centroid - aim)) best = i;
    return best;
}

// The Cornell box's light 180 mm along x in `steps` steps, 2 mm below the
// ceiling (548.8); its short block 150 mm along +z and 40 mm along −x. Not
// quick: one of the office's 12 panels 0.6 m along x (a luminaire moved by
// its own width, in its grid cell), the other 11 and the furniture staying:
// the common case for a lighting designer, where the cache keeps the other
// lights' direct light, which the Cornell box's one light cannot.
std::vector<Motion> allMotions(int steps) {
    Motion light{"light", false, {}}, block{"block", false, {}}, panel{"panel", true, {}};
    const Scene cornell = makeCornellBox(), office = makeOfficeScene();
    const Vec3 c = cornell.lights.at(0).centroid;
    const size_t moved = officePanel(office);
    const Vec3 p = office.lights.at(moved).centroid;
    for (int k = 1; k <= steps; ++k) {
        light.steps.push_back(SceneChange::moveLight(0, Vec3(c.x + 180.0 * k / steps, 546.8, c.z)));
        block.steps.push_back(SceneChange::moveObject("shortBlock", Vec3(-40.0, 0.0, 150.0) / double(steps)));
        panel.steps.push_back(SceneChange::moveLight(moved, p + Vec3(0.6 * k / steps, 0.0, 0.0)));
    }
    return {light, block, panel};
}

// The motions asked for (BenchDynamicOptions::motions; none: every one the
// mode runs), in their order.
std::vector<Motion> motionsFor(const BenchDynamicOptions& options, int steps) {
    std::vector<Motion> all = allMotions(steps), chosen;
    for (const std::string& name : options.motions)
        if (std::none_of(all.begin(), all.end(), [&](const Motion& m) { return m.name == name; }))
            throw InputError(concat("--motions: unknown motion '", name, "' (light, block, panel)"));
    for (Motion& m : all) {
        const bool asked = std::find(options.motions.begin(), options.motions.end(), m.name) != options.motions.end();
        if (options.quick && m.office && asked)
            throw InputError("--motions: 'panel' (the office) is not run with --quick");
        if (options.motions.empty() ? !(options.quick && m.office) : asked) chosen.push_back(std::move(m));
    }
    return chosen;
}

struct Choices {
    DirectChoice direct;
    IndirectChoice indirect;
    RealtimeChoice realtime;
    uint32_t seed = 1;
};

// As the viewer makes them: the sampling threads below the frames and the
// stand-in (ViewRefinement's niceness).
std::unique_ptr<ProgressiveSession> newSession(Scene& scene, const Choices& c, uint32_t seed) {
    SessionSettings ss;
    ss.worker.seed = seed;
    ss.worker.refinementLevels = IrradianceCache::kMaxRefinementLevel;  // as `view` refines
    ss.worker.indirectStandIn = c.realtime.realtime != "off";
    ss.worker.publishSeconds = ViewRefinement::kPublishSeconds;
    if (c.indirect.active()) ss.indirect = c.indirect.solver;
    auto session = std::make_unique<ProgressiveSession>(scene, ss, samplerFactory(scene, c.direct, c.indirect));
    ViewRefinement::lowerWorkerPriority(*session);
    return session;
}

// The viewer's stand-in for indirect light (none with direct light only).
std::unique_ptr<RealtimeIndirect> newRealtime(const Choices& c) {
    if (!c.indirect.active()) return nullptr;
    return std::make_unique<RealtimeIndirect>(c.indirect.solver, realtimeEstimatorFactory(c.indirect),
                                              c.realtime.settings(c.seed), ViewRefinement::kRealtimeNice);
}

// What a frame shows of indirect light: the stand-in's blend, or the cache's.
IndirectShown shownIndirect(const RealtimeIndirect* realtime, const CacheSnapshot& s, uint64_t sceneVersion) {
    if (realtime) return realtime->display(s, sceneVersion);
    IndirectShown shown;
    shown.meshes = s.indirect;
    shown.source = "cache";
    return shown;
}

// Offers each new snapshot to the stand-in, as the viewer does with every
// snapshot it shows.
struct Offers {
    RealtimeIndirect* realtime = nullptr;
    uint64_t sceneVersion = 1;
    std::shared_ptr<const Scene> scene;
    uint64_t offered = 0;  // the snapshot version offered last
    void offer(const CacheSnapshot& s) {
        if (!realtime || s.version == offered) return;
        realtime->offer(s, sceneVersion, scene);
        offered = s.version;
    }
    // A new scene (a step applied), with a new worker: versions start again.
    void sceneChanged(const Scene& now) {
        ++sceneVersion;
        scene = std::make_shared<const Scene>(now);
        offered = 0;
    }
};

struct TimedImage {
    double seconds = 0;
    ImageRgb image;
    uint64_t samples = 0;         // the snapshot's
    int bouncesFinished = 0;      // of its indirect light
    double estimatedError = 1;    // the cache's own
    double realtimeShare = 0;     // of the indirect light shown, the stand-in's (IndirectShown)
    std::string indirectSource;   // IndirectShown::source
    ImageRgb cacheImage;          // the cache's own indirect light instead (the same image where no stand-in shows)
};

// The latest snapshot composited at the error size at imageTimes(limit)
// from `start`, with the indirect light the
// viewer would show; meanwhile every new snapshot is offered to the
// stand-in, as the viewer's frames do.
std::vector<TimedImage> follow(ProgressiveSession& session, CacheWorker::Reader& reader, Offers& offers,
                               Compositor& compositor, const Camera& camera, const Workload& w,
                               Clock::time_point start, double limit) {
    CompositorSettings comp;
    comp.width = w.errorWidth;
    comp.height = w.errorHeight;
    std::vector<TimedImage> images;
    for (double due : imageTimes(limit)) {
        for (double left; (left = due - secondsSince(start)) > 0;) {
            session.rethrowIfFailed();
            if (offers.realtime) offers.realtime->rethrowIfFailed();
            if (const CacheSnapshot* s = reader.acquire()) offers.offer(*s);
            std::this_thread::sleep_for(std::chrono::duration<double>(std::min(left, 0.02)));
        }
        const CacheSnapshot* s = firstSnapshot(session, reader);
        // The time the snapshot was taken, not the time it was due: where a
        // composite takes longer than the interval (the office's meshes at
        // the error size), later images come late, and are timed so.
        const double taken = secondsSince(start);
        offers.offer(*s);
        const IndirectShown shown = shownIndirect(offers.realtime, *s, offers.sceneVersion);
        ImageRgb image = compositor.render(camera, s->direct, shown.meshes, comp);
        ImageRgb cacheImage = shown.realtimeShare > 0 ? compositor.render(camera, s->direct, s->indirect, comp) : image;
        images.push_back({taken, std::move(image), s->samples, s->bouncesFinished, s->estimatedError,
                          shown.realtimeShare, shown.source, std::move(cacheImage)});
    }
    return images;
}

// One row of the stand-in's table: a method at one resolution estimating
// `bounces` bounces from the converged direct light of the final pose.
struct MethodRow {
    std::string method;        // "volume"
    std::string resolution;    // "8 probes"
    bool isDefault = false;    // the resolution the options default to (--probes, --vpls, --lpv-cells)
    int bounces = 0;
    // Bounces 1..chained are the converged cache's, the method's from there
    // on (chainBounces: how the stand-in goes on once the cache has
    // gathered a bounce); 0: from direct light.
    int chained = 0;
    // The old light moved by the method's change (correctByChange): the
    // settled cache before the motion, plus this estimate, less the
    // method's estimate from that cache's direct light on the pose before.
    bool onOldLight = false;
    double setupSeconds = 0;   // the estimator and the base mesh for the scene (once per pose)
    double updateSeconds = 0;  // every bounce estimated, the tail added
    double error = 0;          // the image with it against the converged image
};

struct MotionResult {
    std::string name;
    std::string scene;     // its name ("cornell", "office")
    std::string indirect;  // the plan's gather and bounces there
    std::vector<double> frameMs;      // every frame while moving
    std::vector<double> stepSeconds;  // the helper's time per step
    std::vector<size_t> stepFrames;   // frames drawn while each step was being applied
    std::vector<std::string> reports;
    std::vector<double> warmCurve, coldCurve;  // relative RMSE against converged, at warm[i].seconds, cold[i].seconds
    std::vector<TimedImage> warm, cold;         // their images (samples, bounces, estimated error)
    int levelAtMove = 0;                        // the direct cache's refinement level when the motion began
    size_t verticesAtMove = 0;
    double warmPt05 = 0, warmPt5 = 0, coldPt05 = 0, coldPt5 = 0;  // against the path tracer
    double convergedPt = 0;           // the converged image against the path tracer
    double referenceNoise = 0;        // the reference's mean relative standard error
    double coldOwnWithin2 = -1;       // the cold start against its own last image (the old, biased measure; -1: never)
    std::optional<double> warmWithin2, coldWithin2;
    // The same with the cache's own indirect light, the stand-in left out.
    std::vector<double> warmCacheCurve, coldCacheCurve;
    std::optional<double> warmCacheWithin2, coldCacheWithin2;
    std::vector<MethodRow> methods;   // the stand-in's candidates on the final pose
    double directOnlyError = 0;       // the converged direct light alone against the converged image
    // The stand-in (RealtimeIndirect::choice: with auto, the method chosen
    // on the settled cache and why) and the time its baseline took, waited
    // for before the motion as a user looks at the settled image.
    std::string standIn;
    double standInSeconds = 0;
};

// Relative RMSE of each image (or, `cacheAlone`, its cache's own) against `reference`.
std::vector<double> curve(const std::vector<TimedImage>& images, const ImageRgb& reference, bool cacheAlone = false) {
    std::vector<double> e;
    for (const TimedImage& t : images) e.push_back(relativeRmse(cacheAlone ? t.cacheImage : t.image, reference));
    return e;
}

// The first image at or after `seconds` (the last if none).
size_t imageAt(const std::vector<TimedImage>& images, double seconds) {
    for (size_t i = 0; i < images.size(); ++i)
        if (images[i].seconds >= seconds - 1e-9) return i;
    return images.size() - 1;
}

double at(const std::vector<TimedImage>& images, const ImageRgb& reference, double seconds) {
    return relativeRmse(images[imageAt(images, seconds)].image, reference);
}

// The error of the first image at or after `seconds`.
double errorAt(const std::vector<TimedImage>& images, const std::vector<double>& errors, double seconds) {
    return errors[imageAt(images, seconds)];
}

// The first time the curve (errors of `images`) is within `level` and stays there.
std::optional<double> within(const std::vector<TimedImage>& images, const std::vector<double>& errors, double level) {
    std::optional<double> t;
    for (size_t i = 0; i < errors.size(); ++i) {
        if (errors[i] > level) t.reset();
        else if (!t) t = images[i].seconds;
    }
    return t;
}

// Each method standing in, on the final pose, from the converged cache's
// direct light (and caustics), at its default resolution and one coarser
// and one finer: its time on this thread with nothing else of the bench
// running, and the image it gives against the converged one.
// With `before` (the settled cache on the pose before the motion,
// `beforeScene`) also each default method on the old light: its estimate
// of every bounce (quick: 3) corrected by its change since then
// (correctByChange), the baseline's time counted in the update.
std::vector<MethodRow> measureMethods(const Scene& scene, const Choices& choices, const CacheSnapshot& converged,
                                      const Scene& beforeScene, const CacheSnapshot& before, Compositor& compositor,
                                      const Camera& camera, const CompositorSettings& comp, const ImageRgb& reference,
                                      bool quick) {
    std::vector<IrradianceMeshCopy> source = converged.direct;
    const size_t caustics = std::min(converged.causticMeshes, converged.indirect.size());
    const std::vector<IrradianceMeshCopy> causticMeshes(converged.indirect.end() - std::ptrdiff_t(caustics),
                                                        converged.indirect.end());
    source.insert(source.end(), causticMeshes.begin(), causticMeshes.end());
    const IndirectSettings& settings = choices.indirect.solver;
    std::vector<int> counts;
    for (int n : quick ? std::vector<int>{1, 3} : std::vector<int>{1, 2, 3, settings.bounces})
        if (n <= settings.bounces && std::find(counts.begin(), counts.end(), n) == counts.end()) counts.push_back(n);
    struct Variant {
        std::string method, resolution;
        IndirectChoice choice;
        bool isDefault;
    };
    std::vector<Variant> variants;
    const IndirectChoice& base = choices.indirect;
    for (int probes : {6, base.volume.probes, 12}) {
        IndirectChoice c = base;
        c.volume.probes = probes;
        variants.push_back({"volume", concat(probes, " probes"), c, probes == base.volume.probes});
    }
    for (int lights : {base.vpl.lights, 4 * base.vpl.lights}) {
        IndirectChoice c = base;
        c.vpl.lights = lights;
        variants.push_back({"vpl", concat(lights, " lights"), c, lights == base.vpl.lights});
    }
    for (int cells : {base.lpv.cells, 2 * base.lpv.cells}) {
        IndirectChoice c = base;
        c.lpv.cells = cells;
        variants.push_back({"lpv", concat(cells, " cells"), c, cells == base.lpv.cells});
    }
    std::vector<MethodRow> rows;
    for (const Variant& v : variants) {
        if (quick && !v.isDefault) continue;
        Clock::time_point t = Clock::now();
        const RealtimeMesh mesh(scene, settings, converged.bounceLayout);
        std::unique_ptr<IndirectEstimator> estimator = realtimeEstimatorFactory(v.choice)(scene, v.method);
        const double setup = secondsSince(t);
        for (int n : counts) {
            t = Clock::now();
            std::vector<IrradianceMeshCopy> bounces =
                *estimateBounces(mesh, *estimator, settings, n, source, choices.seed);
            const double update = secondsSince(t);
            bounces.insert(bounces.end(), causticMeshes.begin(), causticMeshes.end());
            const double error = relativeRmse(compositor.render(camera, converged.direct, bounces, comp), reference);
            rows.push_back({v.method, v.resolution, v.isDefault, n, 0, false, setup, update, error});
            if (!v.isDefault || n != counts.back() || !before.indirectComplete) continue;
            // On the old light (as the stand-in does it once the cache was
            // complete): the baseline on the pose before, then the same
            // estimate corrected.
            t = Clock::now();
            const size_t beforeCaustics = std::min(before.causticMeshes, before.indirect.size());
            std::vector<IrradianceMeshCopy> beforeSource = before.direct;
            beforeSource.insert(beforeSource.end(), before.indirect.end() - std::ptrdiff_t(beforeCaustics),
                                before.indirect.end());
            const std::vector<IrradianceMeshCopy> beforeBounces(before.indirect.begin(),
                                                                before.indirect.end() - std::ptrdiff_t(beforeCaustics));
            const RealtimeMesh beforeMesh(beforeScene, settings, before.bounceLayout);
            std::unique_ptr<IndirectEstimator> beforeEstimator =
                realtimeEstimatorFactory(v.choice)(beforeScene, v.method);
            const std::vector<IrradianceMeshCopy> baseline =
                *estimateBounces(beforeMesh, *beforeEstimator, settings, n, beforeSource, choices.seed);
            std::vector<IrradianceMeshCopy> corrected =
                *estimateBounces(mesh, *estimator, settings, n, source, choices.seed);
            correctByChange(corrected, baseline, beforeBounces);
            const double both = secondsSince(t);
            corrected.insert(corrected.end(), causticMeshes.begin(), causticMeshes.end());
            const double onOld = relativeRmse(compositor.render(camera, converged.direct, corrected, comp), reference);
            rows.push_back({v.method, v.resolution, v.isDefault, n, 0, true, setup, both, onOld});
        }
        // Chained onto the converged cache's bounce 1 (on the base mesh, as
        // the solver's first pass leaves it: the bounce's base vertices,
        // resampled from the refined mesh, would differ, so its refined mesh
        // is the source and its own display stands for bounce 1).
        if (!v.isDefault || converged.indirect.size() <= caustics || settings.bounces < 2) continue;
        t = Clock::now();
        const IrradianceMeshCopy& first = converged.indirect.front();
        std::vector<IrradianceMeshCopy> bounces =
            *chainBounces(mesh, *estimator, settings, 0, {mesh.geometry}, {first}, choices.seed);
        const double update = secondsSince(t);
        bounces.front() = first;
        bounces.insert(bounces.end(), causticMeshes.begin(), causticMeshes.end());
        const double error = relativeRmse(compositor.render(camera, converged.direct, bounces, comp), reference);
        rows.push_back({v.method, v.resolution, v.isDefault, settings.bounces - 1, 1, false, setup, update, error});
    }
    return rows;
}

MotionResult runMotion(const BenchRun& run, GlContext& context, const Motion& motion, const Choices& undecided,
                       const Workload& w) {
    MotionResult r;
    r.name = motion.name;
    Scene live = sceneOf(motion);  // the session's: the helper thread changes it
    Choices choices = undecided;   // the plan's gather and bounces for this scene
    choices.indirect.decide(live);
    r.scene = live.name;
    r.indirect = concat(choices.indirect.method, ", ", choices.indirect.solver.bounces, " bounces");
    Scene shown = live;             // the compositor's
    const Camera camera = *live.camera;
    auto compositor = std::make_unique<Compositor>(context, shown);
    std::unique_ptr<ProgressiveSession> session = newSession(live, choices, choices.seed);
    std::unique_ptr<RealtimeIndirect> realtime = newRealtime(choices);
    Offers offers{realtime.get(), 1, std::make_shared<const Scene>(live), 0};
    session->start(RefinementCamera{camera, w.frameWidth, w.frameHeight});
    CacheWorker::Reader reader = session->reader();
    run.progress("%s: settling for %.0f s\n", motion.name.c_str(), w.settle);
    snapshotAt(*session, reader, Clock::now(), w.settle);
    session->stop();  // to read the cache: the frame loop's first step would stop it anyway
    r.levelAtMove = session->cache().level();
    r.verticesAtMove = session->cache().totalVertices();
    reader = CacheWorker::Reader();
    session->start(RefinementCamera{camera, w.frameWidth, w.frameHeight});
    reader = session->reader();
    offers.offered = 0;
    // The settled cache, offered as the viewer offers what it shows: the
    // stand-in keeps it as the pose before the motion.
    const CacheSnapshot settled = *snapshotAt(*session, reader, Clock::now(), 0);
    offers.offer(settled);
    if (realtime) {
        const Clock::time_point baselineAt = Clock::now();
        realtime->waitBaseline(300);  // a guard against a stall only
        r.standInSeconds = secondsSince(baselineAt);
        r.standIn = realtime->choice();
        if (!r.standIn.empty()) run.progress("%s: stand-in %s\n", motion.name.c_str(), r.standIn.c_str());
    }

    // The frame loop while moving, each step applied on a helper thread.
    CompositorSettings frame;
    frame.width = w.frameWidth;
    frame.height = w.frameHeight;
    frame.supersample = 1;  // the viewer's while interactive (ViewSettings::supersample)
    std::vector<IrradianceMeshCopy> lastDirect, lastIndirect;  // shown until the new worker's first snapshot
    bool fromCopies = false;
    std::thread helper;
    std::atomic<bool> helperDone{false};
    double helperSeconds = 0;
    std::string helperReport;
    size_t next = 0, framesThisStep = 0;
    const Clock::time_point loop = Clock::now();
    double nextStepAt = 0;
    while (next < motion.steps.size() || helper.joinable()) {
        if (!helper.joinable() && next < motion.steps.size() && secondsSince(loop) >= nextStepAt) {
            helperDone = false;
            helper = std::thread([&, change = motion.steps[next++]] {
                const Clock::time_point t = Clock::now();
                helperReport = session->applyChange(live, change).describe();
                helperSeconds = secondsSince(t);
                helperDone = true;
            });
        }
        if (helper.joinable() && helperDone.load()) {
            helper.join();
            r.stepSeconds.push_back(helperSeconds);
            r.stepFrames.push_back(framesThisStep);
            framesThisStep = 0;
            r.reports.push_back(helperReport);
            nextStepAt = secondsSince(loop) + kStepInterval;
            // The viewer's finishChange: the last frame's image stays on
            // screen until the new worker's first snapshot, the compositor
            // made again, the stand-in told of the new scene.
            if (const CacheSnapshot* s = reader.acquire())
                lastDirect = s->direct, lastIndirect = shownIndirect(realtime.get(), *s, offers.sceneVersion).meshes;
            fromCopies = true;
            reader = CacheWorker::Reader();
            compositor.reset();
            shown = live;
            compositor = std::make_unique<Compositor>(context, shown);
            offers.sceneChanged(live);
            session->start(RefinementCamera{camera, w.frameWidth, w.frameHeight});
            reader = session->reader();
        }
        const Clock::time_point f = Clock::now();
        const CacheSnapshot* s = reader.acquire();
        if (s) fromCopies = false;
        if (s || fromCopies) {
            if (s) offers.offer(*s);
            compositor->render(camera, s ? s->direct : lastDirect,
                               s ? shownIndirect(realtime.get(), *s, offers.sceneVersion).meshes : lastIndirect, frame);
            r.frameMs.push_back(1e3 * secondsSince(f));
            if (helper.joinable()) ++framesThisStep;
        }
    }
    session->rethrowIfFailed();

    // After the motion: the warm cache, then a cold start on the final pose.
    run.progress("%s: %zu steps applied; following the cache for %.0f s\n", motion.name.c_str(), motion.steps.size(),
                 w.limit);
    const std::vector<TimedImage> warm =
        follow(*session, reader, offers, *compositor, camera, w, Clock::now(), w.limit);
    reader = CacheWorker::Reader();
    session.reset();
    realtime.reset();
    run.progress("%s: cold start for %.0f s\n", motion.name.c_str(), w.cold);
    Scene coldScene = live;
    const Clock::time_point coldStart = Clock::now();  // the cache's construction counts
    std::unique_ptr<ProgressiveSession> fresh = newSession(coldScene, choices, choices.seed);
    std::unique_ptr<RealtimeIndirect> coldRealtime = newRealtime(choices);
    Offers coldOffers{coldRealtime.get(), 1, std::make_shared<const Scene>(coldScene), 0};
    fresh->start(RefinementCamera{camera, w.frameWidth, w.frameHeight});
    CacheWorker::Reader coldReader = fresh->reader();
    const std::vector<TimedImage> cold =
        follow(*fresh, coldReader, coldOffers, *compositor, camera, w, coldStart, w.cold);
    coldReader = CacheWorker::Reader();
    fresh.reset();
    coldRealtime.reset();

    // The converged image: a third session on the final pose with a seed of
    // its own, refined as long as the cold start. Neither curve is measured
    // against its own images (a run's last image shares its refinement and
    // jitter with the images before it, which favoured the cold start when
    // it was the reference).
    run.progress("%s: an independent converged image, %.0f s\n", motion.name.c_str(), w.cold);
    Scene referenceScene = live;
    std::unique_ptr<ProgressiveSession> independent =
        newSession(referenceScene, choices, seedFor(choices.seed, 0xc0de5u));
    independent->start(RefinementCamera{camera, w.frameWidth, w.frameHeight});
    CacheWorker::Reader independentReader = independent->reader();
    const CacheSnapshot* last = snapshotAt(*independent, independentReader, Clock::now(), w.cold);
    independent->stop();
    last = independentReader.acquire();
    CompositorSettings comp;
    comp.width = w.errorWidth;
    comp.height = w.errorHeight;
    const ImageRgb converged = compositor->render(camera, last->direct, last->indirect, comp);
    r.coldOwnWithin2 = within(cold, curve(cold, cold.back().image), 0.02).value_or(-1);

    run.progress("%s: the stand-in's methods on the converged direct light\n", motion.name.c_str());
    if (choices.indirect.active()) {
        r.methods = measureMethods(live, choices, *last, sceneOf(motion), settled, *compositor, camera, comp, converged,
                                   run.options().quick);
        r.directOnlyError = relativeRmse(compositor->render(camera, last->direct, {}, comp), converged);
    }
    independentReader = CacheWorker::Reader();
    independent.reset();

    run.progress("%s: path tracer reference, %d spp at %dx%d\n", motion.name.c_str(), w.spp, w.errorWidth,
                 w.errorHeight);
    const EmbreeScene rays(shown);
    PathTracerSettings pts;
    pts.seed = seedFor(choices.seed, 0xd1a3u);
    const ReferenceImage reference = PathTracer(rays, pts).render(camera, w.errorWidth, w.errorHeight, w.spp);
    r.referenceNoise = reference.meanRelativeError;
    r.warmCurve = curve(warm, converged);
    r.coldCurve = curve(cold, converged);
    r.warmPt05 = at(warm, reference.radiance, 0.5);
    r.warmPt5 = at(warm, reference.radiance, 5.0);
    r.coldPt05 = at(cold, reference.radiance, 0.5);
    r.coldPt5 = at(cold, reference.radiance, 5.0);
    r.convergedPt = relativeRmse(converged, reference.radiance);
    r.warmWithin2 = within(warm, r.warmCurve, 0.02);
    r.warm = warm;
    r.cold = cold;
    r.coldWithin2 = within(cold, r.coldCurve, 0.02);
    r.warmCacheCurve = curve(warm, converged, true);
    r.coldCacheCurve = curve(cold, converged, true);
    r.warmCacheWithin2 = within(warm, r.warmCacheCurve, 0.02);
    r.coldCacheWithin2 = within(cold, r.coldCacheCurve, 0.02);
    return r;
}

double percentile(std::vector<double> v, double q) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, size_t(q * double(v.size() - 1) + 0.5))];
}

// A free text as a CSV cell: no commas (BenchTable's cells hold none).
std::string csvCell(std::string text) {
    std::replace(text.begin(), text.end(), ',', ';');
    return text;
}

std::string cell(const std::optional<double>& t) { return t ? benchNumber(*t) : std::string("never"); }

const std::vector<GnuplotOutput> kPlots = {{"out_curves", "dynamic_curves.png"}};

std::string gnuplotScript(const std::vector<MotionResult>& results) {
    std::ostringstream gp;
    gp << "# Written by 'meshlight bench dynamic'; run with gnuplot in this folder.\n"
       << gnuplotOutputDefaults(kPlots)
       << "set terminal pngcairo enhanced size 1000,600 font ',11'\n"
          "set datafile separator ','\n"
          "set grid\nset logscale y\n"
          "set xlabel 'seconds after the motion stopped (warm) or the session started (cold)'\n"
          "set ylabel 'relative RMSE against the converged image, %'\n"
          "set output out_curves\n";
    for (size_t i = 0; i < results.size(); ++i)
        for (const char* kind : {"warm", "cold"}) {
            const bool isWarm = std::string(kind) == "warm";
            const std::vector<double>& c = isWarm ? results[i].warmCurve : results[i].coldCurve;
            const std::vector<TimedImage>& im = isWarm ? results[i].warm : results[i].cold;
            gp << "$" << results[i].name << "_" << kind << " << EOD\n";
            for (size_t k = 0; k < c.size(); ++k) gp << benchNumber(im[k].seconds) << "," << benchPct(std::max(c[k], 1e-5)) << "\n";
            gp << "EOD\n";
        }
    gp << "plot 2 with lines dt 2 lc 'black' title '2%'";
    for (const MotionResult& r : results)
        for (const char* kind : {"warm", "cold"})
            gp << ", $" << r.name << "_" << kind << " using 1:2 with linespoints title '" << r.name << " " << kind << "'";
    gp << "\n";
    return gp.str();
}

}  // namespace

int runBenchDynamic(const BenchDynamicOptions& options) {
    const Workload w = workloadFor(options.quick);
    const std::vector<Motion> motions = motionsFor(options, w.steps);  // refused before the folder is made
    BenchRun run(options);
    const std::unique_ptr<GlContext> context = run.openContext();
    Choices choices;  // the indirect light decided per scene (runMotion)
    choices.seed = options.seed;
    choices.direct.seed = options.seed;
    choices.direct.backend = options.backend;
    choices.realtime = options.realtime;
    choices.realtime.validate();
    const bool cornell = std::any_of(motions.begin(), motions.end(), [](const Motion& m) { return !m.office; });
    const bool office = std::any_of(motions.begin(), motions.end(), [](const Motion& m) { return m.office; });
    const std::string scenes = cornell && office ? "the Cornell box and the office" : cornell ? "the Cornell box" : "the office";
    std::printf("bench dynamic (%s): %s, full GI, frames %dx%d, errors at %dx%d against %d spp; %s\n",
                run.mode(), scenes.c_str(), w.frameWidth, w.frameHeight,
                w.errorWidth, w.errorHeight, w.spp, choices.realtime.describe().c_str());

    std::vector<MotionResult> results;
    for (const Motion& m : motions) results.push_back(runMotion(run, *context, m, choices, w));

    BenchTable frames({"motion", "frame", "ms"});
    BenchTable summary({"motion", "scene", "indirect", "steps", "frames", "frame_median_ms", "frame_p95_ms", "frame_max_ms",
                        "step_median_ms", "step_max_ms", "warm_0.5s_vs_converged_pct", "warm_5s_vs_converged_pct",
                        "warm_0.5s_vs_pt_pct", "warm_5s_vs_pt_pct", "cold_0.5s_vs_pt_pct", "cold_5s_vs_pt_pct",
                        "converged_vs_pt_pct", "reference_noise_pct", "warm_within_2pct_s", "cold_within_2pct_s",
                        "warm_cache_alone_within_2pct_s", "cold_cache_alone_within_2pct_s",
                        "cold_within_2pct_of_itself_s"});
    BenchTable targets({"motion", "target", "measured", "met"});
    BenchTable curves({"motion", "start", "seconds", "vs_converged_pct", "cache_alone_vs_converged_pct", "samples",
                       "bounces_finished", "estimated_error_pct", "realtime_share_pct", "indirect_shown"});
    BenchTable methods({"motion", "method", "resolution", "from", "bounces_estimated", "setup_s", "update_s",
                        "vs_converged_pct"});
    for (const MotionResult& r : results) {
        for (size_t i = 0; i < r.frameMs.size(); ++i) frames.addRow({r.name, std::to_string(i), benchNumber(r.frameMs[i])});
        std::vector<double> stepMs;
        for (double s : r.stepSeconds) stepMs.push_back(1e3 * s);
        const double at05 = errorAt(r.warm, r.warmCurve, 0.5);
        const double at5 = errorAt(r.warm, r.warmCurve, 5.0);
        summary.addRow({r.name, r.scene, csvCell(r.indirect), std::to_string(r.stepSeconds.size()), std::to_string(r.frameMs.size()),
                        benchNumber(median(r.frameMs)), benchNumber(percentile(r.frameMs, 0.95)),
                        benchNumber(percentile(r.frameMs, 1.0)), benchNumber(median(stepMs)),
                        benchNumber(percentile(stepMs, 1.0)), benchPct(at05), benchPct(at5), benchPct(r.warmPt05),
                        benchPct(r.warmPt5), benchPct(r.coldPt05), benchPct(r.coldPt5), benchPct(r.convergedPt),
                        benchPct(r.referenceNoise), cell(r.warmWithin2), cell(r.coldWithin2),
                        cell(r.warmCacheWithin2), cell(r.coldCacheWithin2), r.coldOwnWithin2 >= 0 ? benchNumber(r.coldOwnWithin2) : std::string("never")});
        for (const char* kind : {"warm", "cold"}) {
            const bool isWarm = std::string(kind) == "warm";
            const std::vector<double>& c = isWarm ? r.warmCurve : r.coldCurve;
            const std::vector<double>& alone = isWarm ? r.warmCacheCurve : r.coldCacheCurve;
            const std::vector<TimedImage>& im = isWarm ? r.warm : r.cold;
            for (size_t k = 0; k < c.size(); ++k)
                curves.addRow({r.name, kind, benchNumber(im[k].seconds), benchPct(c[k]), benchPct(alone[k]),
                               std::to_string(im[k].samples),
                               std::to_string(im[k].bouncesFinished), benchPct(im[k].estimatedError),
                               benchPct(im[k].realtimeShare), csvCell(im[k].indirectSource)});
        }
        for (const MethodRow& m : r.methods)
            methods.addRow({r.name, m.method, m.resolution + (m.isDefault ? " (default)" : ""),
                            m.chained      ? concat("the cache's bounce ", m.chained)
                            : m.onOldLight ? std::string("direct light; on the old light")
                                           : std::string("direct light"),
                            std::to_string(m.bounces), benchNumber(m.setupSeconds), benchNumber(m.updateSeconds),
                            benchPct(m.error)});
        if (!r.methods.empty())
            methods.addRow(
                {r.name, "none (direct light alone)", "-", "-", "0", "0", "0", benchPct(r.directOnlyError)});
        std::printf("%s: the direct cache was at refinement level %d with %zu vertices when the motion began\n",
                    r.name.c_str(), r.levelAtMove, r.verticesAtMove);
        // Frames never wait: frames kept coming while every step was being
        // applied (the helper's time is what a frame would have waited).
        const size_t fewest = r.stepFrames.empty() ? 0 : *std::min_element(r.stepFrames.begin(), r.stepFrames.end());
        targets.addRow({r.name, "frames never wait for the cache (fewest frames drawn during a step)",
                        std::to_string(fewest) + " frames during a step of up to " +
                            benchNumber(percentile(stepMs, 1.0)) + " ms",
                        benchYesNo(fewest > 0)});
        targets.addRow({r.name, "0.5 s after the motion within 10% of converged", benchPct(at05) + "%",
                        benchYesNo(at05 <= 0.10)});
        const bool half = r.warmWithin2 && r.coldWithin2 && *r.warmWithin2 < 0.5 * *r.coldWithin2;
        targets.addRow({r.name, "back within 2% in under half a cold start's time",
                        cell(r.warmWithin2) + " s vs " + cell(r.coldWithin2) + " s", benchYesNo(half)});
        const bool cacheHalf =
            r.warmCacheWithin2 && r.coldCacheWithin2 && *r.warmCacheWithin2 < 0.5 * *r.coldCacheWithin2;
        targets.addRow({r.name, "the same with the cache's own indirect light (no stand-in)",
                        cell(r.warmCacheWithin2) + " s vs " + cell(r.coldCacheWithin2) + " s", benchYesNo(cacheHalf)});
        for (size_t i = 0; i < r.reports.size(); ++i)
            std::printf("%s step %zu: %s (%.0f ms)\n", r.name.c_str(), i + 1, r.reports[i].c_str(), stepMs[i]);
    }
    std::printf("\n%s\n%s\n%s\n", summary.aligned().c_str(), targets.aligned().c_str(), methods.aligned().c_str());
    run.writeCsv("dynamic_frames.csv", frames);
    run.writeCsv("dynamic_summary.csv", summary);
    run.writeCsv("dynamic_targets.csv", targets);
    run.writeCsv("dynamic_curves.csv", curves);
    run.writeCsv("dynamic_realtime.csv", methods);
    run.plot("dynamic_plots.gp", gnuplotScript(results), kPlots);
    const double wall = run.seconds();
    std::ostringstream md;
    md << "# bench dynamic (" << run.mode() << ")\n\nMotions:";
    for (size_t i = 0; i < motions.size(); ++i)
        md << (i ? ", " : " ") << motions[i].name
           << (motions[i].office ? " (the office, 12 panels)" : " (the Cornell box)");
    md << "; full GI; frames " << w.frameWidth << "x"
       << w.frameHeight << ", errors at " << w.errorWidth << "x" << w.errorHeight << " against " << w.spp
       << " spp. " << run.glDescription() << "; load at start " << run.loadAtStart() << ".\n\n"
       << choices.realtime.describe() << ".\n\n";
    for (const MotionResult& r : results)
        if (r.standInSeconds > 0)
            md << "- " << r.name << ": the stand-in's baseline on the settled cache took " << r.standInSeconds
               << " s before the motion" << (r.standIn.empty() ? std::string() : "; stand-in " + r.standIn) << ".\n";
    md << "\n"
       << summary.markdown() << "\n" << targets.markdown()
       << "\nThe stand-in's methods on the final pose, from the converged direct light, on the old light (the "
          "settled cache before the motion corrected by the method's change) or chained onto the converged cache's "
          "bounce 1 (as the stand-in goes on once the cache has gathered it; one thread, volume's probes on "
          "every core, nothing else running), against the converged image:\n\n"
       << methods.markdown();
    run.write("dynamic_summary.md", md.str());
    run.printWallTime(wall);
    return 0;
}

}  // namespace ml
