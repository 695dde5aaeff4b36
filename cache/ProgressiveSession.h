// One progressive run of the cache: the direct meshes, the indirect solver,
// the worker that refines them, resuming from and saving to a cache file,
// when to stop, and the progress line. `render`, `probe`, the viewer, the
// benches and the tests all drive refinement through it.
//
//   ProgressiveSession session(scene, settings, samplerFactory(scene, direct, indirect));
//   const uint64_t serial = session.start(RefinementCamera{camera, w, h});
//   CacheWorker::Reader reader = session.reader();
//   const CacheSnapshot& s = session.refineUntil(reader, stop, serial);
//   session.stop();
//
// The samplers are made by the factory on the worker's thread (their GL
// contexts live and die there). The session can be stopped and started
// again (the viewer does so to save the cache): a new worker continues the
// same cache and solver, and refines exactly as if it had never stopped.
#pragma once

#include "CacheInvalidation.h"
#include "CacheWorker.h"
#include "CausticCache.h"
#include "IndirectSolver.h"
#include "IrradianceCache.h"
#include "LightCoverage.h"

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace ml {

// When to stop refining for one image; the first rule met ends it, and
// convergence always does.
struct StopRule {
    std::optional<double> seconds;  // wall clock for this image (s)
    std::optional<double> error;    // the cache's estimated error, relative (0.02 = 2%)
    uint64_t samples = 0;           // estimates in all, 0: no limit; ends the worker (WorkerSettings::maxSamples)
    // "10 s, or an estimated error of 0.02, or convergence"
    std::string describe() const;
};

struct SessionSettings {
    CacheSettings cache;
    WorkerSettings worker;  // maxSamples is taken from the stop rule given to the constructor
    // Indirect bounces; none (or 0 bounces): direct light only.
    std::optional<IndirectSettings> indirect;
    // Caustics, traced with indirect light when some light sees a specular
    // object (CausticCache); none without indirect light.
    CausticSettings caustics;
    // Resume from this cache file when it exists (empty: none). A truncated,
    // corrupt or mismatched file is refused with an InputError.
    std::string cachePath;
};

class ProgressiveSession {
public:
    ProgressiveSession(const Scene& scene, const SessionSettings& settings, SamplerFactory factory,
                       const StopRule& stop = {});
    ~ProgressiveSession();  // stops the worker
    ProgressiveSession(const ProgressiveSession&) = delete;
    ProgressiveSession& operator=(const ProgressiveSession&) = delete;

    // The cache was loaded from settings.cachePath.
    bool resumed() const { return resumed_; }
    const IrradianceCache& cache() const { return cache_; }
    // Null with direct light only.
    const IndirectSolver* indirect() const { return solver_.get(); }
    // Null unless indirect light is on and some light sees a specular object.
    const CausticCache* caustics() const { return caustics_.get(); }
    // Where each light keeps a mesh of its own, the rest shared.
    const LightCoverage& coverage() const { return *coverage_; }

    // Starts a worker serving `view` first; returns that view's serial (see
    // setView). Once stopped, a session may start again: the readers of the
    // worker before must be gone by then.
    // `paused`: the worker waits for resume() before its first round.
    uint64_t start(const std::optional<RefinementCamera>& view = std::nullopt, bool paused = false);
    // Wraps the factory for the next start(): `before` runs on the worker's
    // thread before its samplers are made (the viewer lowers its priority).
    void setThreadSetup(std::function<void()> before) { threadSetup_ = std::move(before); }
    // Asks the worker to finish its round and publish, and joins it; its
    // readers still read its last snapshot.
    void stop();
    // A worker was started and has not ended.
    bool running() const;
    void pause();
    void resume();
    // The worker has ended: stopped, out of samples, or failed.
    bool finished() const;
    // The camera to serve; returns the serial that snapshots made for it carry.
    uint64_t setCamera(const std::optional<RefinementCamera>& view);
    // One per reading thread; readers of a stopped worker hold nothing.
    CacheWorker::Reader reader();
    void rethrowIfFailed() const;
    bool waitForVersion(uint64_t version, double timeoutSeconds);
    // Seconds since the last start().
    double seconds() const;

    // Blocks until `stop` holds for the view of `serial` (a snapshot made for
    // it converged or is under the error, or the image's time is up) or the
    // worker has ended; meanwhile calls `tick` with the latest snapshot at
    // most every `every` seconds of session time. Rethrows a worker's
    // failure. Returns the latest snapshot, if any (valid until `reader`
    // acquires again).
    const CacheSnapshot* refineUntil(CacheWorker::Reader& reader, const StopRule& stop, uint64_t serial,
                                     double every = 1e30,
                                     const std::function<void(const CacheSnapshot&)>& tick = {});

    // A light or an object moves (core/SceneChange.h): stops the worker,
    // applies `change` to `scene`, which must be the scene this session was
    // made with (so everything reading it sees the change: the samplers a
    // new worker makes build their occluders and BVHs from it), and makes
    // the cache keep what is still valid (CacheInvalidation.h). start()
    // again to refine. An InputError (an unknown light or object, a change
    // the cache cannot follow) leaves the scene as it was.
    InvalidationReport applyChange(Scene& scene, const SceneChange& change);

    // Writes the cache (temporary file, then rename); the worker must be stopped.
    void save(const std::string& path) const;

private:
    // Frees a stopped worker on a thread of its own: its samplers died on
    // its thread, but a viewer's window context must not see any context's
    // teardown on the window's thread.
    void release();
    // Makes the caustic cache for the scene as it is (none if no light sees
    // a specular object).
    void traceCaustics();

    const Scene& scene_;
    SessionSettings settings_;
    std::shared_ptr<const LightCoverage> coverage_;  // where lights keep meshes of their own
    SamplerFactory factory_;
    std::function<void()> threadSetup_;
    IrradianceCache cache_;
    std::unique_ptr<IndirectSolver> solver_;
    std::unique_ptr<CausticCache> caustics_;
    std::unique_ptr<CacheWorker> worker_;
    bool resumed_ = false;
    std::chrono::steady_clock::time_point startTime_{};
    double nextTick_ = 0;
};

// One line on a snapshot: "1234 vertices, 56789 samples, bounces 3/8 (456
// gathers), estimated error 1.23%".
std::string describeProgress(const CacheSnapshot& snapshot);

}  // namespace ml
