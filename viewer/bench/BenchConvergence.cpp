#include "BenchConvergence.h"

#include "BenchRun.h"
#include "SessionCheckpoints.h"
#include "BenchTable.h"
#include "CornellWalkthrough.h"
#include "WalkthroughViews.h"
#include "ExactDirectImage.h"
#include "Gnuplot.h"

#include "cache/ProgressiveSession.h"
#include "cache/IrradianceCache.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/image/ImageMetrics.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "core/scenes/CornellBox.h"
#include "viewer/compositor/Compositor.h"
#include "gpu_sampling/SamplerFactory.h"
#include "gpu_sampling/gl/GlContext.h"

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;

// --- Targets and settings ----------------------------------------------------------

// Issue 4's targets for the still image (relative RMSE against the exact
// image) and for each view of the walkthrough.
constexpr double kStillTargetA = 0.02, kStillSecondsA = 5;
constexpr double kStillTargetB = 0.01, kStillSecondsB = 30;
constexpr double kViewTarget = 0.02;

// Walkthrough: a view is composited once a snapshot made for it predicts at
// most this error (IrradianceCache::estimatedError, what `render
// --until-error` stops at)...
constexpr double kViewEstimatedError = 0.01;
// ...or once this many seconds have passed since the view was set.
constexpr double kViewSecondsLimit = 2.0;

// Sub-pixels per pixel side of the compositor and of the exact image: the
// production default (render --supersample).
constexpr int kSupersample = 4;
// The finer exact image of the crop that measures the sub-pixel approximation.
constexpr int kFineSupersample = 8;
// Walkthrough: the path tracer's samples per pixel double from the first to
// the last until its error matches Meshlight's.
constexpr int kFirstViewSpp = 4, kLastViewSpp = 1024;
// Still: the path tracer starts at 2 samples per pixel (its least: the two
// halves estimate its noise).
constexpr int kFirstStillSpp = 2;

struct Workload {
    int stillSize;                    // pixels per side
    double stillSeconds;              // Meshlight's budget; the path tracer stops past it
    std::vector<double> checkpoints;  // s since the cache was made: a snapshot composited at each
    // The crop around the light that measures the sub-pixel approximation,
    // pixels per side (at the still image's pixel size).
    int cropSize;
    int views;                        // walkthrough
    // Pixels per side of each view. The exact reference of a view costs
    // size² × 16 sub-pixels; the walkthrough's views look at the blocks'
    // penumbrae, where the exact visible polygon is dear: ~7,000 sub-pixels
    // per second per core, so 48² takes ~2.6 s on 2 cores and 30 views
    // ~80 s, which keeps the full bench near 6 minutes. 128² would take
    // 7× as long (~9 minutes of references alone).
    int viewSize;
};

Workload workloadFor(bool quick) {
    if (quick) return {64, 3, {0.5, 1, 2, 3}, 16, 3, 32};
    // 5 s joins the times, to read the first target off directly.
    return {256, 30, {0.5, 1, 2, 4, 5, 8, 15, 30}, 48, 30, 48};
}

// Resident set size of this process in bytes (/proc/self/statm, second
// field, in pages), read after glibc has given its free pages back to the
// system (malloc_trim): what is left is what is held, not what was freed
// and kept for reuse. 0 when it cannot be read.
size_t residentBytesTrimmed() {
    ::malloc_trim(0);
    std::ifstream in("/proc/self/statm");
    size_t total = 0, resident = 0;
    if (!(in >> total >> resident)) return 0;
    return resident * size_t(::sysconf(_SC_PAGESIZE));
}

// --- Cameras ------------------------------------------------------------------------

// A size × size view of the light from `camera`'s eye, its pixels as large
// as those of a full × full image from `camera`: where the path tracer's
// floor is. Seen from the box's camera the light is a thin sliver just
// below the black ceiling, so a pixel on its silhouette holds a bright part
// and a dark one: whether the 4×4 sub-pixel centres hit the light decides
// much of the pixel, while the path tracer integrates its area.
Camera lightCropCamera(const Scene& scene, const Camera& camera, int full, int size) {
    ML_ASSERT(!scene.lights.empty(), "the Cornell box has a light");
    Camera c = camera;
    c.target = scene.lights.front().centroid;
    c.fovYDegrees = glm::degrees(2 * std::atan(std::tan(glm::radians(camera.fovYDegrees) / 2) * size / full));
    c.validate();
    return c;
}

// The pixels of an image from `camera` whose sub-pixel centres (the exact
// image's and the compositor's) see the light, grown by one pixel: a pixel
// on the light's silhouette then counts even when none of its centres hits
// the light. There, beside the black ceiling, the sub-pixel centres and the
// path tracer's pixel area differ by much of the pixel's value; elsewhere
// they differ only along geometric edges.
class LightMask {
public:
    LightMask(const EmbreeScene& rays, const Camera& camera, int size) : size_(size), mask_(size_t(size) * size, 0) {
        Vec3 forward, right, up;
        camera.basis(forward, right, up);
        const double tanY = std::tan(glm::radians(camera.fovYDegrees) / 2);
        const int S = kSupersample;
        std::vector<char> sees(mask_.size(), 0);
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x)
                for (int k = 0; k < S * S && !sees[size_t(y) * size + x]; ++k) {
                    const double u = 2 * (x + (k % S + 0.5) / S) / size - 1;
                    const double v = 1 - 2 * (y + (k / S + 0.5) / S) / size;
                    RayHit hit;
                    if (rays.intersect(camera.position, forward + u * tanY * right + v * tanY * up, 0, kInf, hit) &&
                        rays.lightOf(hit.mesh, hit.triangle) >= 0)
                        sees[size_t(y) * size + x] = 1;
                }
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int nx = x + dx, ny = y + dy;
                        if (nx >= 0 && ny >= 0 && nx < size && ny < size && sees[size_t(ny) * size + nx])
                            mask_[size_t(y) * size + x] = 1;
                    }
        masked_ = size_t(std::count(mask_.begin(), mask_.end(), 1));
    }

    size_t maskedPixels() const { return masked_; }

    // ml::relativeRmse over the pixels outside the mask: masked pixels of
    // `x` take the reference's value, and the mean is rescaled to the others.
    double relativeRmse(const ImageRgb& x, const ImageRgb& reference) const {
        ML_ASSERT(x.width == size_ && x.height == size_, "image ", x.width, "x", x.height, " for a mask of ", size_);
        ImageRgb copy = x;
        for (int y = 0; y < size_; ++y)
            for (int px = 0; px < size_; ++px)
                if (mask_[size_t(y) * size_ + px]) copy.set(px, y, reference.at(px, y));
        const size_t kept = mask_.size() - masked_;
        return kept ? ml::relativeRmse(copy, reference) * std::sqrt(double(mask_.size()) / double(kept)) : 0.0;
    }

private:
    int size_;
    std::vector<char> mask_;
    size_t masked_ = 0;
};

// --- The path tracer ---------------------------------------------------------------

// The path tracer's image of one view at doubling samples per pixel. Each
// step renders as many new samples per pixel as the image already has, from
// fresh streams (another seed), and averages: the image at N samples costs
// one N-sample render, not the 2N of rendering every count from scratch, and
// is the same estimator (each sample uniform in its pixel, independent).
class DoublingPathTracer {
public:
    DoublingPathTracer(const EmbreeScene& rays, const Camera& camera, int size, uint32_t seed, int firstSpp)
        : rays_(rays), camera_(camera), size_(size), seed_(seed), next_(firstSpp) {}

    // Doubles the samples per pixel (the first step renders firstSpp).
    void step() {
        const Clock::time_point start = Clock::now();
        PathTracerSettings s;
        s.maxDepth = 1;  // emission + direct light: what render --direct-only computes
        s.threads = 0;   // every core
        s.seed = seedFor(seed_, uint32_t(steps_++));
        const PathTracer tracer(rays_, s);
        const ReferenceImage r = tracer.render(camera_, size_, size_, next_);
        if (spp_ == 0) {
            image_ = r.radiance;
        } else {
            const float wOld = float(spp_) / float(spp_ + next_), wNew = float(next_) / float(spp_ + next_);
            for (size_t i = 0; i < image_.data.size(); ++i)
                image_.data[i] = wOld * image_.data[i] + wNew * r.radiance.data[i];
        }
        spp_ += next_;
        next_ = spp_;
        seconds_ += secondsSince(start);
    }
    int spp() const { return spp_; }
    double seconds() const { return seconds_; }  // wall time of every step so far
    const ImageRgb& image() const { return image_; }

private:
    const EmbreeScene& rays_;
    Camera camera_;
    int size_;
    uint32_t seed_;
    int next_;
    int spp_ = 0, steps_ = 0;
    double seconds_ = 0;
    ImageRgb image_;
};

// --- Part 1: the still image ----------------------------------------------------------

struct MeshlightPoint {
    double checkpoint = 0;  // s, when it was due
    double seconds = 0;     // s since the cache was made, when the snapshot was taken
    double error = 0;       // relative RMSE against the exact image
    size_t vertices = 0;
    uint64_t samples = 0, rounds = 0;
    double estimatedError = 0;
    double compositeSeconds = 0;
    double errorOffLight = 0;  // relative RMSE without the pixels that see the light (LightMask)
};

struct PathPoint {
    int spp = 0;
    double seconds = 0;  // s: BVH and tracer setup + every render up to this count
    double error = 0;
    double errorOffLight = 0;
};

struct MemoryResult {
    size_t bytesPerVertex = 0;  // IrradianceCache::bytesPerVertex()
    size_t cacheBytes = 0;      // IrradianceCache::memoryBytes() at the end
    size_t baseVertices = 0;    // when the cache was made
    size_t vertices = 0;        // at the end
    // Resident set, bytes, each read after returning the allocator's free
    // pages to the system (residentBytesTrimmed): before the cache was made,
    // at the end (worker stopped, cache and last snapshot alive), and once
    // the worker, its snapshots and the cache are destroyed.
    size_t rssBefore = 0, rssAfter = 0, rssFreed = 0;

    // The growth since before the cache, over every vertex: also what the
    // worker left behind (its thread's allocator arena, GL driver caches).
    double rssGrowthPerVertex() const {
        return vertices ? (double(rssAfter) - double(rssBefore)) / double(vertices) : 0;
    }
    // What destroying the cache and its snapshots gave back: their live memory.
    double rssFreedPerVertex() const {
        return vertices ? (double(rssAfter) - double(rssFreed)) / double(vertices) : 0;
    }
    double accountedPerVertex() const { return vertices ? double(cacheBytes) / double(vertices) : 0; }
    // What stayed after the cache was freed: one-off, whatever the vertex count.
    double leftBytes() const { return double(rssFreed) - double(rssBefore); }
};

struct StillResult {
    double exactSeconds = 0;
    size_t lightPixels = 0;  // pixels the LightMask leaves out of the *OffLight errors
    double cacheBuildSeconds = 0;
    std::vector<MeshlightPoint> meshlight;
    double pathSetupSeconds = 0;
    std::vector<PathPoint> path;
    // The path tracer's floor, and the sub-pixel approximation, on the
    // crop around the light (lightCropCamera).
    double cropSeconds = 0;      // the 4×4 and 8×8 exact crops and the path tracer's
    int cropSpp = 0;             // the path tracer's samples per pixel there: as at its floor
    double exactGap = 0;         // relative RMSE of the 4×4 exact crop against the 8×8 one
    double pathVsCoarse = 0;     // the path tracer's crop against the 4×4 exact crop
    double pathVsFine = 0;       // ...against the 8×8 one
    MemoryResult memory;
};

// Direct light only, sampled as `choice` says, seeded with `seed`.
std::unique_ptr<ProgressiveSession> directSession(const Scene& scene, const DirectChoice& choice, uint32_t seed) {
    SessionSettings settings;
    settings.worker.seed = seed;
    IndirectChoice none;
    none.enabled = false;
    return std::make_unique<ProgressiveSession>(scene, settings, samplerFactory(scene, choice, none));
}

StillResult runStill(const Scene& scene, const Workload& work, const DirectChoice& choice, Compositor& compositor,
                     uint32_t seed) {
    StillResult r;
    const Camera camera = *scene.camera;
    const int size = work.stillSize;
    ExactImageSettings exactSettings;
    exactSettings.width = exactSettings.height = size;
    exactSettings.supersample = kSupersample;
    Clock::time_point t = Clock::now();
    const ImageRgb exact = renderExactDirect(scene, camera, exactSettings);
    r.exactSeconds = secondsSince(t);
    std::printf("still: exact direct image %dx%d, %dx%d sub-pixels: %.1f s\n", size, size, kSupersample,
                kSupersample, r.exactSeconds);

    t = Clock::now();
    const EmbreeScene rays(scene);  // the path tracer's, timed as part of its work
    r.pathSetupSeconds = secondsSince(t);
    const LightMask offLight(rays, camera, size);
    r.lightPixels = offLight.maskedPixels();

    // Meshlight: render's progressive loop, its clock started before the
    // cache is made. The block ends with the worker, its snapshots and the
    // cache destroyed, to measure what they held.
    CompositorSettings comp;
    comp.width = comp.height = size;
    comp.supersample = kSupersample;
    r.memory.rssBefore = residentBytesTrimmed();
    {
        const Clock::time_point start = Clock::now();
        const std::unique_ptr<ProgressiveSession> session = directSession(scene, choice, seed);
        const IrradianceCache& cache = session->cache();
        r.cacheBuildSeconds = secondsSince(start);
        r.memory.baseVertices = cache.totalVertices();
        session->start(RefinementCamera{camera, size, size});
        CacheWorker::Reader reader = session->reader();
        for (double due : work.checkpoints) {
            const CacheSnapshot* s = snapshotAt(*session, reader, start, due);
            MeshlightPoint p;
            p.checkpoint = due;
            p.seconds = secondsSince(start);
            const Clock::time_point c = Clock::now();
            const ImageRgb image = compositor.render(camera, s->direct, comp);
            p.compositeSeconds = secondsSince(c);
            p.error = relativeRmse(image, exact);
            p.errorOffLight = offLight.relativeRmse(image, exact);
            p.vertices = s->vertices;
            p.samples = s->samples;
            p.rounds = s->rounds;
            p.estimatedError = s->estimatedError;
            r.meshlight.push_back(p);
            std::printf("  meshlight %5.2f s: relative RMSE %.3f%% (%.3f%% off the light), %zu vertices, %llu "
                        "samples, estimated error %.3f%%\n",
                        p.seconds, 100 * p.error, 100 * p.errorOffLight, p.vertices,
                        static_cast<unsigned long long>(p.samples), 100 * p.estimatedError);
        }
        session->stop();
        session->rethrowIfFailed();
        r.memory.rssAfter = residentBytesTrimmed();
        r.memory.bytesPerVertex = IrradianceCache::bytesPerVertex();
        r.memory.cacheBytes = cache.memoryBytes();
        r.memory.vertices = cache.totalVertices();
    }
    r.memory.rssFreed = residentBytesTrimmed();

    // The path tracer, alone on the machine now, until it has used the budget.
    DoublingPathTracer tracer(rays, camera, size, seed, kFirstStillSpp);
    do {
        tracer.step();
        const PathPoint p{tracer.spp(), r.pathSetupSeconds + tracer.seconds(), relativeRmse(tracer.image(), exact),
                          offLight.relativeRmse(tracer.image(), exact)};
        r.path.push_back(p);
        std::printf("  path tracer %4d spp %6.2f s: relative RMSE %.3f%% (%.3f%% off the light)\n", p.spp, p.seconds,
                    100 * p.error, 100 * p.errorOffLight);
    } while (r.path.back().seconds <= work.stillSeconds);

    // How much of the path tracer's floor is the exact image's sub-pixel
    // centres: around the light, the exact image at 4×4 and at 8×8
    // sub-pixels, and the path tracer at its last sample count.
    t = Clock::now();
    const Camera cropCamera = lightCropCamera(scene, camera, size, work.cropSize);
    ExactImageSettings crop;
    crop.width = crop.height = work.cropSize;
    crop.supersample = kSupersample;
    const ImageRgb coarseCrop = renderExactDirect(scene, cropCamera, crop);
    crop.supersample = kFineSupersample;
    const ImageRgb fineCrop = renderExactDirect(scene, cropCamera, crop);
    DoublingPathTracer cropTracer(rays, cropCamera, work.cropSize, seedFor(seed, 0xc0u), kFirstStillSpp);
    while (cropTracer.spp() < tracer.spp()) cropTracer.step();
    r.cropSeconds = secondsSince(t);
    r.cropSpp = cropTracer.spp();
    r.exactGap = relativeRmse(coarseCrop, fineCrop);
    r.pathVsCoarse = relativeRmse(cropTracer.image(), coarseCrop);
    r.pathVsFine = relativeRmse(cropTracer.image(), fineCrop);
    std::printf("  %dx%d crop around the light: exact 4x4 vs 8x8 %.3f%%; path tracer (%d spp) vs 4x4 %.3f%%, "
                "vs 8x8 %.3f%% (%.1f s)\n",
                work.cropSize, work.cropSize, 100 * r.exactGap, r.cropSpp, 100 * r.pathVsCoarse, 100 * r.pathVsFine,
                r.cropSeconds);
    return r;
}

// --- Part 2: the walkthrough ----------------------------------------------------------

struct ViewResult {
    double referenceSeconds = 0;  // the exact image of the view
    // Meshlight
    double waitSeconds = 0;       // from setView to the snapshot composited
    double compositeSeconds = 0;
    double seconds() const { return waitSeconds + compositeSeconds; }
    double error = 0;
    size_t vertices = 0;
    double estimatedError = 0;
    // A snapshot made after the view was set estimated at most
    // kViewEstimatedError, or converged, within kViewSecondsLimit.
    bool estimateReached = false;
    // The path tracer: the first sample count whose error is at most
    // Meshlight's on this view (or the last tried)...
    int spp = 0;
    double pathSeconds = 0;
    double pathError = 0;
    bool pathReached = false;
    // ...and the first within kViewTarget (or the last tried).
    int sppTarget = 0;
    double pathSecondsTarget = 0;
    bool pathReachedTarget = false;
};

struct WalkthroughResult {
    std::vector<ViewResult> views;
    double referenceSeconds = 0, cacheBuildSeconds = 0, pathSetupSeconds = 0;
    double meshlightTotal() const {
        double s = 0;
        for (const ViewResult& v : views) s += v.seconds();
        return s;
    }
    double pathTotal() const {
        double s = pathSetupSeconds;
        for (const ViewResult& v : views) s += v.pathSeconds;
        return s;
    }
    double pathTargetTotal() const {
        double s = pathSetupSeconds;
        for (const ViewResult& v : views) s += v.pathSecondsTarget;
        return s;
    }
    double maxError() const {
        double e = 0;
        for (const ViewResult& v : views) e = std::max(e, v.error);
        return e;
    }
    bool pathReachedAll() const {
        return std::all_of(views.begin(), views.end(), [](const ViewResult& v) { return v.pathReached; });
    }
    bool pathReachedTargetAll() const {
        return std::all_of(views.begin(), views.end(), [](const ViewResult& v) { return v.pathReachedTarget; });
    }
};

WalkthroughResult runWalkthrough(const Scene& scene, const Workload& work, const DirectChoice& choice,
                                 Compositor& compositor, uint32_t seed) {
    WalkthroughResult r;
    const int size = work.viewSize;
    const std::vector<Camera> cameras = walkthroughCameras(scene, work.views);
    Clock::time_point t = Clock::now();
    const EmbreeScene rays(scene);
    r.pathSetupSeconds = secondsSince(t);
    checkViewsInside(rays, cameras, size, size);
    r.views.resize(cameras.size());

    // The references first, so that nothing else runs while Meshlight and the path tracer are timed.
    ExactImageSettings exactSettings;
    exactSettings.width = exactSettings.height = size;
    exactSettings.supersample = kSupersample;
    std::vector<ImageRgb> references;
    for (size_t v = 0; v < cameras.size(); ++v) {
        t = Clock::now();
        references.push_back(renderExactDirect(scene, cameras[v], exactSettings));
        r.views[v].referenceSeconds = secondsSince(t);
        r.referenceSeconds += r.views[v].referenceSeconds;
    }
    std::printf("walkthrough: %zu views %dx%d; exact references %.1f s (%.2f s each)\n", cameras.size(), size, size,
                r.referenceSeconds, r.referenceSeconds / double(cameras.size()));

    // Meshlight: one cache, refined all along; the first view's time includes making it.
    CompositorSettings comp;
    comp.width = comp.height = size;
    comp.supersample = kSupersample;
    const Clock::time_point start = Clock::now();
    const std::unique_ptr<ProgressiveSession> session = directSession(scene, choice, seed);
    r.cacheBuildSeconds = secondsSince(start);
    std::optional<CacheWorker::Reader> reader;
    for (size_t v = 0; v < cameras.size(); ++v) {
        ViewResult& out = r.views[v];
        const Clock::time_point viewStart = v == 0 ? start : Clock::now();
        const RefinementCamera view{cameras[v], size, size};
        const uint64_t serial = v == 0 ? session->start(view) : session->setCamera(view);
        if (v == 0) reader = session->reader();
        // Only snapshots made for this view (CacheSnapshot::cameraSerial) count.
        StopRule stop;
        stop.seconds = std::max(0.0, kViewSecondsLimit - secondsSince(viewStart));
        stop.error = kViewEstimatedError;
        const CacheSnapshot* latest = session->refineUntil(*reader, stop, serial);
        const bool done = latest && latest->cameraSerial >= serial &&
                          (latest->converged || latest->estimatedError <= kViewEstimatedError);
        const CacheSnapshot* s = firstSnapshot(*session, *reader);  // the latest
        out.waitSeconds = secondsSince(viewStart);
        const Clock::time_point c = Clock::now();
        const ImageRgb image = compositor.render(cameras[v], s->direct, comp);
        out.compositeSeconds = secondsSince(c);
        out.error = relativeRmse(image, references[v]);
        out.vertices = s->vertices;
        out.estimatedError = s->estimatedError;
        out.estimateReached = done;
        std::printf("  view %2zu meshlight %.2f s: relative RMSE %.3f%%, %zu vertices, estimated error %.3f%%%s\n", v,
                    out.seconds(), 100 * out.error, out.vertices, 100 * out.estimatedError,
                    out.estimateReached ? "" : " (time limit)");
    }
    session->stop();
    session->rethrowIfFailed();

    // The path tracer, per view, up to Meshlight's error on that view.
    for (size_t v = 0; v < cameras.size(); ++v) {
        ViewResult& out = r.views[v];
        DoublingPathTracer tracer(rays, cameras[v], size, seedFor(seed, 0x77a1u, uint32_t(v)), kFirstViewSpp);
        for (;;) {
            tracer.step();
            const double error = relativeRmse(tracer.image(), references[v]);
            if (!out.pathReached) {
                out.spp = tracer.spp();
                out.pathSeconds = tracer.seconds();
                out.pathError = error;
                out.pathReached = error <= out.error;
            }
            if (!out.pathReachedTarget) {
                out.sppTarget = tracer.spp();
                out.pathSecondsTarget = tracer.seconds();
                out.pathReachedTarget = error <= kViewTarget;
            }
            if ((out.pathReached && out.pathReachedTarget) || tracer.spp() >= kLastViewSpp) break;
        }
        std::printf("  view %2zu path tracer: %4d spp %.2f s to %.3f%%%s; %4d spp %.2f s to %g%%%s\n", v, out.spp,
                    out.pathSeconds, 100 * out.pathError, out.pathReached ? "" : " (not Meshlight's)", out.sppTarget,
                    out.pathSecondsTarget, 100 * kViewTarget, out.pathReachedTarget ? "" : " (not reached)");
    }
    return r;
}

// --- Tables ------------------------------------------------------------------------------

BenchTable stillTable(const StillResult& r) {
    BenchTable t({"method", "checkpoint_s", "seconds", "relative_rmse_pct", "off_light_rmse_pct", "spp", "vertices",
                  "samples", "rounds", "estimated_error_pct", "composite_ms"});
    for (const MeshlightPoint& p : r.meshlight)
        t.addRow({"meshlight", benchNumber(p.checkpoint), benchNumber(p.seconds), benchPct(p.error),
                  benchPct(p.errorOffLight), "", std::to_string(p.vertices), std::to_string(p.samples),
                  std::to_string(p.rounds), benchPct(p.estimatedError), benchNumber(1e3 * p.compositeSeconds)});
    for (const PathPoint& p : r.path)
        t.addRow({"path-tracer", "", benchNumber(p.seconds), benchPct(p.error), benchPct(p.errorOffLight),
                  std::to_string(p.spp), "", "", "", "", ""});
    return t;
}

BenchTable walkthroughTable(const WalkthroughResult& r) {
    BenchTable t({"view", "meshlight_s", "meshlight_cum_s", "relative_rmse_pct", "vertices", "estimated_error_pct",
                  "estimate_reached", "composite_ms", "pt_spp", "pt_s", "pt_cum_s", "pt_relative_rmse_pct",
                  "pt_reached", "pt_spp_target", "pt_s_target", "pt_reached_target", "reference_s"});
    double cum = 0, ptCum = r.pathSetupSeconds;
    for (size_t v = 0; v < r.views.size(); ++v) {
        const ViewResult& w = r.views[v];
        cum += w.seconds();
        ptCum += w.pathSeconds;
        t.addRow({std::to_string(v), benchNumber(w.seconds()), benchNumber(cum), benchPct(w.error),
                  std::to_string(w.vertices), benchPct(w.estimatedError), benchYesNo(w.estimateReached),
                  benchNumber(1e3 * w.compositeSeconds), std::to_string(w.spp), benchNumber(w.pathSeconds),
                  benchNumber(ptCum), benchPct(w.pathError), benchYesNo(w.pathReached), std::to_string(w.sppTarget),
                  benchNumber(w.pathSecondsTarget), benchYesNo(w.pathReachedTarget), benchNumber(w.referenceSeconds)});
    }
    return t;
}

// The last image made within `seconds` (Meshlight's by when it was due);
// null when there is none.
const MeshlightPoint* lastWithin(const std::vector<MeshlightPoint>& points, double seconds) {
    const MeshlightPoint* last = nullptr;
    for (const MeshlightPoint& p : points)
        if (p.checkpoint <= seconds) last = &p;
    return last;
}

const PathPoint* lastWithin(const std::vector<PathPoint>& points, double seconds) {
    const PathPoint* last = nullptr;
    for (const PathPoint& p : points)
        if (p.seconds <= seconds) last = &p;
    return last;
}

struct TargetRow {
    std::string target, method, value, status;
};

std::vector<TargetRow> targetRows(const StillResult& still, const WalkthroughResult& walk, const Workload& work) {
    std::vector<TargetRow> rows;
    auto stillRows = [&](double target, double seconds) {
        const std::string name = concat("still <= ", 100 * target, "% within ", seconds, " s");
        if (work.stillSeconds < seconds) {
            const std::string why = concat("not measured (this run stops at ", work.stillSeconds, " s)");
            for (const char* method : {"meshlight", "path-tracer"}) rows.push_back({name, method, "-", why});
            return;
        }
        // The metric over the whole image, and without the pixels
        // that see the light (where the path tracer's floor is).
        auto add = [&](const std::string& method, const auto* p) {
            if (!p) {
                rows.push_back({name, method, "no image yet", "not met"});
                rows.push_back({name + " (off the light)", method, "no image yet", "not met"});
                return;
            }
            rows.push_back({name, method, concat(benchPct(p->error), "% at ", benchNumber(p->seconds), " s"),
                            p->error <= target ? "met" : "not met"});
            rows.push_back({name + " (off the light)", method,
                            concat(benchPct(p->errorOffLight), "% at ", benchNumber(p->seconds), " s"),
                            p->errorOffLight <= target ? "met" : "not met"});
        };
        add("meshlight", lastWithin(still.meshlight, seconds));
        add("path-tracer", lastWithin(still.path, seconds));
    };
    stillRows(kStillTargetA, kStillSecondsA);
    stillRows(kStillTargetB, kStillSecondsB);
    const std::string views = concat("walkthrough: every view <= ", 100 * kViewTarget, "%");
    rows.push_back({views, "meshlight", concat("worst ", benchPct(walk.maxError()), "%"),
                    walk.maxError() <= kViewTarget ? "met" : "not met"});
    // Where the path tracer did not reach the error on some view its total
    // is a lower bound: Meshlight below it is met, above it undecided.
    auto totals = [&](const std::string& name, double pt, bool complete) {
        const double ml = walk.meshlightTotal();
        const std::string more = complete ? "" : " or more";
        rows.push_back({name, "meshlight",
                        concat(benchNumber(ml), " s vs ", benchNumber(pt), " s", more, ": ratio ", benchNumber(pt / ml),
                               more),
                        ml < pt ? "met" : complete ? "not met" : "undecided"});
    };
    totals("walkthrough: total time below the path tracer's at Meshlight's error per view", walk.pathTotal(),
           walk.pathReachedAll());
    totals(concat("walkthrough: total time below the path tracer's at ", 100 * kViewTarget, "% per view"),
           walk.pathTargetTotal(), walk.pathReachedTargetAll());
    return rows;
}

BenchTable targetsTable(const std::vector<TargetRow>& rows) {
    BenchTable t({"target", "method", "value", "status"});
    for (const TargetRow& r : rows) t.addRow({r.target, r.method, r.value, r.status});
    return t;
}

BenchTable memoryTable(const MemoryResult& m) {
    const double million = 1e6;
    BenchTable t({"quantity", "bytes_per_vertex", "per_1000_vertices_MB", "million_vertices_MB", "within_1GB"});
    auto row = [&](const std::string& name, double perVertex, double fixed = 0) {
        t.addRow({name, benchNumber(perVertex), benchNumber(perVertex * 1e3 / 1e6),
                  benchNumber((fixed + perVertex * million) / 1e6), benchYesNo(fixed + perVertex * million <= 1e9)});
    };
    row("IrradianceCache::bytesPerVertex", double(m.bytesPerVertex));
    row("IrradianceCache::memoryBytes per vertex", m.accountedPerVertex());
    row("resident set given back when the cache and its snapshots are freed", m.rssFreedPerVertex());
    row("resident set growth since before the cache", m.rssGrowthPerVertex());
    row("given back per vertex + what stayed after freeing (one-off)", m.rssFreedPerVertex(), m.leftBytes());
    return t;
}

// --- Plots ------------------------------------------------------------------------------

const std::vector<GnuplotOutput> kPlots = {
    {"out_still", "convergence_still.png"},
    {"out_walk", "convergence_walkthrough.png"},
    {"out_walk_error", "convergence_walkthrough_error.png"},
};

std::string gnuplotScript(const StillResult& still, const WalkthroughResult& walk, const Workload& work) {
    std::ostringstream gp;
    gp << "# Written by 'meshlight bench convergence'; run with gnuplot in this folder.\n"
       << gnuplotOutputDefaults(kPlots)
       << "set terminal pngcairo enhanced size 1200,800 font ',11'\n"
          "set datafile separator ','\n"
          "set grid\n"
          "set key top right\n\n"
          "# seconds, relative RMSE %, the same off the light %\n$meshlight << EOD\n";
    for (const MeshlightPoint& p : still.meshlight)
        gp << benchNumber(p.seconds) << "," << benchPct(p.error) << "," << benchPct(p.errorOffLight) << "\n";
    gp << "EOD\n# seconds, relative RMSE %, spp, the same off the light %\n$path << EOD\n";
    for (const PathPoint& p : still.path)
        gp << benchNumber(p.seconds) << "," << benchPct(p.error) << "," << p.spp << "," << benchPct(p.errorOffLight)
           << "\n";
    gp << "EOD\n# frame, cumulative s: meshlight, path tracer at its error, path tracer at the target; "
          "relative RMSE %: meshlight, path tracer at its error\n$walk << EOD\n";
    double cum = 0, ptCum = walk.pathSetupSeconds, ptTargetCum = walk.pathSetupSeconds;
    for (size_t v = 0; v < walk.views.size(); ++v) {
        cum += walk.views[v].seconds();
        ptCum += walk.views[v].pathSeconds;
        ptTargetCum += walk.views[v].pathSecondsTarget;
        gp << v + 1 << "," << benchNumber(cum) << "," << benchNumber(ptCum) << "," << benchNumber(ptTargetCum) << ","
           << benchPct(walk.views[v].error) << "," << benchPct(walk.views[v].pathError) << "\n";
    }
    gp << "EOD\n\n";

    double tMin = 1e30, tMax = 0;
    for (const MeshlightPoint& p : still.meshlight) tMin = std::min(tMin, p.seconds), tMax = std::max(tMax, p.seconds);
    for (const PathPoint& p : still.path) tMin = std::min(tMin, p.seconds), tMax = std::max(tMax, p.seconds);
    gp << "set output out_still\n"
          "set title 'Cornell box, direct light, " << work.stillSize << "^2 pixels: relative RMSE against the exact "
          "image (" << kSupersample << "x" << kSupersample << " sub-pixels)'\n"
          "set logscale xy\n"
          "set xrange [" << tMin / 1.3 << ":" << tMax * 1.3 << "]\n"
          "set xlabel 'wall-clock seconds (Meshlight: since the cache was made; path tracer: BVH + renders)'\n"
          "set ylabel 'relative RMSE (%)'\n"
          "set arrow 1 from " << kStillSecondsA << ", graph 0 to " << kStillSecondsA
       << ", graph 1 nohead dt 3 lc rgb 'gray50'\n"
          "set arrow 2 from " << kStillSecondsB << ", graph 0 to " << kStillSecondsB
       << ", graph 1 nohead dt 3 lc rgb 'gray50'\n"
          "plot $meshlight using 1:2 with linespoints lc rgb '#1f5fa8' pt 7 ps 1.3 "
          "title 'Meshlight (progressive cache)', \\\n"
          "     $path using 1:2 with linespoints lc rgb '#c0392b' pt 5 ps 1.3 title 'path tracer, depth 1, "
       << std::thread::hardware_concurrency() << " threads', \\\n"
          "     $path using 1:2:(sprintf('%d', $3)) with labels font ',8' offset char 0,-1 notitle, \\\n"
          "     $meshlight using 1:3 with linespoints dt 4 lc rgb '#1f5fa8' pt 6 ps 1.1 "
          "title 'Meshlight, pixels that see the light left out', \\\n"
          "     $path using 1:4 with linespoints dt 4 lc rgb '#c0392b' pt 4 ps 1.1 "
          "title 'path tracer, pixels that see the light left out', \\\n"
          "     " << 100 * kStillTargetA << " with lines dt 2 lc rgb 'gray40' title 'targets: "
       << 100 * kStillTargetA << "% within " << kStillSecondsA << " s, " << 100 * kStillTargetB << "% within "
       << kStillSecondsB << " s', \\\n"
          "     " << 100 * kStillTargetB << " with lines dt 2 lc rgb 'gray40' notitle\n\n"
          "unset arrow 1\nunset arrow 2\n";

    gp << "set output out_walk\n"
          "set title 'Walkthrough, " << walk.views.size() << " views of " << work.viewSize << "^2 pixels: cumulative "
          "time (path tracer: samples doubled per view until its error is at most Meshlight)'\n"
          "unset logscale\n"
          "set autoscale x\n"
          "set xrange [0.5:" << walk.views.size() + 0.5 << "]\n"
          "set xtics " << (walk.views.size() > 10 ? 5 : 1) << "\n"
          "set yrange [0:*]\n"
          "set key top left\n"
          "set xlabel 'frames'\n"
          "set ylabel 'cumulative wall-clock seconds'\n"
          "plot $walk using 1:2 with linespoints lc rgb '#1f5fa8' pt 7 title 'Meshlight (one cache, refined all "
          "along)', \\\n"
          "     $walk using 1:3 with linespoints lc rgb '#c0392b' pt 5 "
          "title 'path tracer at the error of Meshlight (up to " << kLastViewSpp << " spp)', \\\n"
          "     $walk using 1:4 with linespoints lc rgb '#d68910' pt 9 "
          "title 'path tracer at " << 100 * kViewTarget << "%'\n\n";

    gp << "set output out_walk_error\n"
          "set title 'Walkthrough: relative RMSE per view against its exact image'\n"
          "set logscale y\n"
          "set yrange [*:*]\n"
          "set key top right\n"
          "set ylabel 'relative RMSE (%)'\n"
          "plot $walk using 1:5 with linespoints lc rgb '#1f5fa8' pt 7 title 'Meshlight', \\\n"
          "     $walk using 1:6 with linespoints lc rgb '#c0392b' pt 5 title 'path tracer (first count at or below "
          "Meshlight, or its last)', \\\n"
          "     " << 100 * kViewTarget << " with lines dt 2 lc rgb 'gray40' title 'target'\n";
    return gp.str();
}

// --- Summary ------------------------------------------------------------------------------

std::string summaryMarkdown(const BenchRun& run, double wallSeconds, const Workload& work, const StillResult& still,
                            const WalkthroughResult& walk, const std::vector<TargetRow>& targets) {
    const unsigned threads = std::thread::hardware_concurrency();
    std::ostringstream md;
    md << "# Convergence bench: progressive cache against the path tracer\n\n"
       << "- scene: Cornell box, direct light only; OpenGL: " << run.glDescription() << "\n"
       << "- mode: " << run.mode() << ", seed " << run.options().seed << ", " << threads
       << " hardware threads; wall time " << benchNumber(wallSeconds) << " s; load average " << run.loadAtStart()
       << " at the start, " << loadAverage() << " at the end (other processes slow every timing)\n"
       << "- Meshlight: production settings (cache defaults, jittered 64×64, 8 bits, cv), the worker thread "
          "refining and sampling, this thread compositing snapshots (" << kSupersample << "×" << kSupersample
       << " sub-pixels); its clock starts before the cache is made\n"
       << "- path tracer: depth 1 (emission + direct light), " << threads << " threads, box filter; samples per "
          "pixel doubled by rendering as many again with fresh streams and averaging, so N samples cost one N-sample "
          "render; its time includes the BVH build\n"
       << "- error: relative RMSE (core/image/ImageMetrics.h) against the exact direct image "
          "(viewer/bench/ExactDirectImage.h: the compositor's " << kSupersample << "×" << kSupersample
       << " sub-pixel centres)\n\n";

    md << "## Targets\n\n" << targetsTable(targets).markdown() << "\n";

    md << "## Still image, " << work.stillSize << "×" << work.stillSize << "\n\n"
       << "Exact image: " << benchNumber(still.exactSeconds) << " s. Cache made in "
       << benchNumber(still.cacheBuildSeconds) << " s; path tracer BVH " << benchNumber(still.pathSetupSeconds)
       << " s. Meshlight's snapshots are taken at the checkpoints (seconds: when taken, after the previous "
          "image was composited).\n\n"
       << stillTable(still).markdown() << "\n";
    const PathPoint& last = still.path.back();
    md << "The path tracer's floor: " << benchPct(last.error) << "% at " << last.spp << " spp ("
       << benchNumber(last.seconds) << " s). It integrates each pixel's area, while the exact image (and the "
          "compositor) average " << kSupersample << "×" << kSupersample << " sub-pixel centres; where a pixel holds "
          "a bright and a dark part, the two differ by much of the pixel. From the box's camera the light is a thin "
          "sliver against the black ceiling (direct light only: the ceiling gets none), so its silhouette pixels "
          "dominate. On a " << work.cropSize << "×" << work.cropSize << " crop around the light (same pixel size, "
       << benchNumber(still.cropSeconds) << " s): the " << kSupersample << "×" << kSupersample
       << " exact image differs from an " << kFineSupersample << "×" << kFineSupersample << " one by "
       << benchPct(still.exactGap) << "%; the path tracer at " << still.cropSpp << " spp differs from the "
       << kSupersample << "×" << kSupersample << " one by " << benchPct(still.pathVsCoarse) << "% and from the "
       << kFineSupersample << "×" << kFineSupersample << " one by " << benchPct(still.pathVsFine)
       << "%. What the finer grid removes is sub-pixel approximation, not path-tracing noise. off_light_rmse: the "
          "same metric without the " << still.lightPixels << " pixels whose sub-pixel centres see the light, grown by "
          "one pixel (" << benchPct(double(still.lightPixels) / (double(work.stillSize) * work.stillSize))
       << "% of the image); the path tracer's remaining floor there is its noise and the geometric edges.\n\n";

    const bool reached = walk.pathReachedAll(), reachedTarget = walk.pathReachedTargetAll();
    md << "## Walkthrough, " << walk.views.size() << " views of " << work.viewSize << "×" << work.viewSize << "\n\n"
       << "Per view: setView, then the first snapshot made for the view whose estimated error is at most "
       << benchPct(kViewEstimatedError) << "% (or that converged), else the latest after " << kViewSecondsLimit
       << " s; its time includes compositing (and, for view 0, making the cache: "
       << benchNumber(walk.cacheBuildSeconds) << " s). The path tracer renders " << kFirstViewSpp << ", "
       << 2 * kFirstViewSpp << ", … up to " << kLastViewSpp
       << " spp; pt_* columns: the first count whose error is at most Meshlight's on that view, pt_*_target: the "
          "first within " << benchPct(kViewTarget) << "%; where none does, the last count's time (a lower bound). Its "
          "BVH build (" << benchNumber(walk.pathSetupSeconds) << " s) counts once. The exact references took "
       << benchNumber(walk.referenceSeconds) << " s in all, in neither total; they set the view size (see "
          "BenchConvergence.cpp, Workload).\n\n"
       << "Totals: Meshlight " << benchNumber(walk.meshlightTotal()) << " s; path tracer at Meshlight's error "
       << benchNumber(walk.pathTotal()) << " s" << (reached ? "" : " or more") << " (ratio "
       << benchNumber(walk.pathTotal() / walk.meshlightTotal()) << (reached ? "" : " or more")
       << "), at " << benchPct(kViewTarget) << "% " << benchNumber(walk.pathTargetTotal()) << " s"
       << (reachedTarget ? "" : " or more") << " (ratio " << benchNumber(walk.pathTargetTotal() / walk.meshlightTotal())
       << (reachedTarget ? "" : " or more") << "); worst Meshlight view " << benchPct(walk.maxError()) << "%.\n\n"
       << walkthroughTable(walk).markdown() << "\n";

    const MemoryResult& m = still.memory;
    md << "## Memory per cached vertex\n\n"
       << "Still run: " << m.baseVertices << " vertices when the cache was made, " << m.vertices
       << " at the end; IrradianceCache::memoryBytes " << benchNumber(m.cacheBytes / 1e6)
       << " MB at the end. Resident set (/proc/self/statm, each read after malloc_trim gave glibc's free pages "
          "back): " << benchNumber(m.rssBefore / 1e6) << " MB before the cache was made, "
       << benchNumber(m.rssAfter / 1e6) << " MB at the end (worker stopped, the cache and the last snapshot, a "
          "copy of every mesh, alive), " << benchNumber(m.rssFreed / 1e6)
       << " MB once the worker, its snapshots and the cache were destroyed. The growth since before the cache "
          "also holds what the worker thread left behind (its allocator arena, the GL driver's caches); what "
          "freeing gives back is the cache's and its snapshots' live memory. Extrapolated linearly to a million "
          "vertices against the 1 GB (10^9 bytes) target.\n\n"
       << memoryTable(m).markdown();
    return md.str();
}

}  // namespace

int runBenchConvergence(const BenchOptions& options) {
    BenchRun run(options);
    const Workload work = workloadFor(options.quick);
    const Scene scene = makeCornellBox();
    // The compositor's context lives on this thread; the worker makes its own.
    const std::unique_ptr<GlContext> context = run.openContext();
    Compositor compositor(*context, scene);
    DirectChoice choice;  // the production sampler
    choice.seed = options.seed;
    choice.backend = options.backend;

    const StillResult still = runStill(scene, work, choice, compositor, options.seed);
    const WalkthroughResult walk = runWalkthrough(scene, work, choice, compositor, options.seed);
    const std::vector<TargetRow> targets = targetRows(still, walk, work);

    const BenchTable stillT = stillTable(still), walkT = walkthroughTable(walk), targetT = targetsTable(targets),
                     memoryT = memoryTable(still.memory);
    std::printf("\nStill image %dx%d: relative RMSE against the exact image (%.1f s to compute).\n\n%s",
                work.stillSize, work.stillSize, still.exactSeconds, stillT.aligned().c_str());
    std::printf("\nPath tracer floor %.3f%% (%.3f%% off the light, %zu pixels left out) at %d spp; %dx%d crop around "
                "the light: exact 4x4 vs 8x8 %.3f%%, path tracer (%d spp) vs 4x4 %.3f%%, vs 8x8 %.3f%%.\n",
                100 * still.path.back().error, 100 * still.path.back().errorOffLight, still.lightPixels,
                still.path.back().spp, work.cropSize, work.cropSize, 100 * still.exactGap, still.cropSpp,
                100 * still.pathVsCoarse, 100 * still.pathVsFine);
    std::printf("\nWalkthrough, %zu views %dx%d (exact references: %.1f s).\n\n%s", walk.views.size(), work.viewSize,
                work.viewSize, walk.referenceSeconds, walkT.aligned().c_str());
    std::printf("\nMemory per cached vertex (%zu vertices at the end of the still run).\n\n%s",
                still.memory.vertices, memoryT.aligned().c_str());
    std::printf("\nTargets (issue 4).\n\n%s", targetT.aligned().c_str());

    run.writeCsv("convergence_still.csv", stillT);
    run.writeCsv("convergence_walkthrough.csv", walkT);
    run.writeCsv("convergence_targets.csv", targetT);
    run.writeCsv("convergence_memory.csv", memoryT);
    run.plot("convergence_plots.gp", gnuplotScript(still, walk, work), kPlots);
    const double wall = run.seconds();
    run.write("convergence_summary.md", summaryMarkdown(run, wall, work, still, walk, targets));
    std::printf("\n");
    run.printWallTime(wall);
    return 0;
}

}  // namespace ml
