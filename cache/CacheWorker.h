// Refinement and sampling on a worker thread, with immutable, versioned
// snapshots for the renderer.
//
// The worker owns the cache while it runs: it alone refines and samples it,
// and after each round (at most every `publishSeconds`) it publishes a
// snapshot, a complete copy of every light's mesh. Renderers read snapshots
// through a SnapshotExchange reader: no lock on the render path, never a
// torn read. The samplers are made on the worker thread by a factory, so a
// GL context lives and dies on the thread that uses it.
#pragma once

#include "CausticCache.h"
#include "DirectSampler.h"
#include "IndirectEstimator.h"
#include "IndirectSolver.h"
#include "IrradianceCache.h"
#include "SnapshotExchange.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>

namespace ml {

class SamplerPool;

struct CacheSnapshot {
    uint64_t version = 0;             // 1, 2, ... in publication order
    double seconds = 0;               // worker time since start()
    // One per light, in the scene's order, then the mesh the lights share
    // if the cache has one (IrradianceCache::hasSharedMesh).
    std::vector<IrradianceMeshCopy> direct;
    // Indirect irradiance, one mesh per bounce (bounce 1 first); empty with
    // direct light only or before the indirect pass has started. Then, when
    // the scene has caustics (causticMeshes = 1), their mesh
    // (CausticCache). The irradiance a surface receives is Σ direct +
    // Σ indirect.
    std::vector<IrradianceMeshCopy> indirect;
    // False while `indirect` is not yet every bounce as gathered for the
    // scene as it is (IndirectSolver::firstPassDone, showingStale: at the
    // start, after a scene change or restart()); then `bounceMeshes` holds
    // every started bounce as gathered so far (IndirectSolver::copyMeshes: a
    // vertex not gathered since has samples 0), which the real-time stand-in
    // blends with (RealtimeIndirect.h); empty once complete. True with
    // direct light only.
    bool indirectComplete = true;
    std::vector<IrradianceMeshCopy> bounceMeshes;
    // `indirect` is the light from before a scene change that moved little
    // light, kept until every bounce is gathered again
    // (IndirectSolver::keepingStale, kKeepOldLightShare): no stand-in
    // replaces it.
    bool oldIndirectKept = false;
    // `indirect` is the light from before a scene change (on the old
    // geometry), shown until bounce 1 is gathered again
    // (IndirectSolver::showingStale); oldIndirectKept: until every bounce is.
    bool indirectStale = false;
    // How the bounces' base meshes are laid for the worker's gather
    // (bounceCacheLayout(estimator)): the stand-in lays its estimate the
    // same way, vertex for vertex.
    CacheLayout bounceLayout = bounceCacheLayout();
    size_t causticMeshes = 0;         // the last of `indirect` that are caustics (0 or 1)
    // The bounces `indirect` shows: its meshes but the caustics'.
    size_t shownBounces() const { return indirect.size() - std::min(causticMeshes, indirect.size()); }
    uint64_t causticPhotons = 0;      // photons emitted so far
    double causticError = 0;          // CausticCache::estimatedError
    int bounces = 0;                  // indirect bounces planned
    int bouncesFinished = 0;          // of those, converged once
    size_t indirectVertices = 0;      // over the indirect meshes (also in `vertices`)
    uint64_t indirectSamples = 0;     // gathers taken (also in `samples`)
    double directError = 0;           // direct meshes' estimated error
    double indirectError = 0;         // IndirectSolver::estimatedError (1 until every bounce is done)
    IndirectStats indirectStats;      // the estimator's memory and times
    DirectPhaseTimes directPhases;    // the direct sampler's time per phase, all samples so far
    size_t vertices = 0;              // over all meshes
    std::vector<size_t> verticesPerMesh;
    uint64_t samples = 0;             // estimates taken, all meshes
    uint64_t rounds = 0;
    double estimatedError = 0;        // the largest of directError, indirectError and causticError
    bool converged = false;           // the last round found nothing to do
    uint64_t cameraSerial = 0;          // the setCamera() call the last round served (0: none)
};

struct WorkerSettings {
    uint32_t seed = 1;
    // Estimates per refinement round; 0 picks one from the cache size (a
    // thirty-second of its vertices, 256 to 16,384), so scoring the edges
    // stays a small part of each round.
    size_t roundBudget = 0;
    // Snapshots are published after a round at most this often (seconds);
    // always after the first and the last round. A snapshot copies every
    // mesh and scores its error: where that costs more than a tenth of this
    // (a tenth of a second and more with 10^5 vertices and more), they come
    // further apart, so that publishing keeps at most a tenth of the
    // worker's time. 0: after every round, whatever it costs.
    double publishSeconds = 0.25;
    // Stop on your own after this many estimates in all, direct and
    // indirect (0: no limit); a budget in samples makes a run repeat
    // whatever the machine's speed.
    uint64_t maxSamples = 0;
    // The worker's schedule reads no clock: direct and indirect light share
    // it by rounds (as under a sample budget, which implies this) instead of
    // by time, so the same scene refined again makes the same cache, loaded
    // machine or not. Time shares are better for an image at a time (the
    // back rooms' indirect light); tests comparing caches bit for bit across
    // runs want this.
    bool repeatable = false;
    // Gathers per indirect round; 0 picks one from the bounce's mesh: an
    // eighth of its vertices, 16 to 16,384, and no more than a second's at
    // the last round's rate (512 at least; at most 512 under a sample
    // budget or `repeatable`, which no clock may decide).
    size_t indirectBudget = 0;
    // Sampling threads, each with samplers of its own (SamplerPool); 0: one
    // per core. The cache a sample budget makes does not depend on it.
    int threads = 0;
    // Progressive refinement: once a part has converged at its level (direct
    // light, the bounces, the caustics), tighten that part's caches
    // (IrradianceCache::tighten: tolerances halved), each on its own, up to this
    // level and go on refining, so that waiting longer keeps getting closer
    // to the exact answer; 0: stop at the settings' tolerances (idle once
    // converged). The commands use IrradianceCache::kMaxRefinementLevel.
    int refinementLevels = 0;
    // The image shows a stand-in for indirect light while its bounces are
    // gathered (RealtimeIndirect.h): indirect light then starts once direct
    // light's first pass is complete, whose light it reflects, rather than
    // early (IndirectSettings::startFraction) or at once after a scene
    // change (for an image without a stand-in, which would show no indirect
    // light or the old one meanwhile). Gathers from an incomplete first pass
    // are made again (IndirectSolver::restart) and its worker time is then
    // direct light's.
    bool indirectStandIn = false;
    // Called on the worker's thread with each snapshot as it is published,
    // before the next round: for a caller that must see every round (a
    // test of what each did), which a reader polling the exchange cannot
    // promise (under load it missed a snapshot published 9 ms after the one
    // before). It must be quick and must not call back into the worker.
    std::function<void(const CacheSnapshot&)> onPublish;

    void validate() const;
};

// The samplers of one worker, made and destroyed on its thread.
struct WorkerSamplers {
    std::unique_ptr<DirectSampler> direct;
    // Null with direct light only. Declared after `direct`, so destroyed
    // before it: it may draw with the direct sampler's GL context.
    std::unique_ptr<IndirectEstimator> indirect;
};
// Called once on the worker thread, before its first round.
using SamplerFactory = std::function<WorkerSamplers()>;

class CacheWorker {
public:
    // `cache` (and `indirect` and `caustics`, if given) must outlive the
    // worker and not be touched while it runs. Without `indirect` only
    // direct light is refined; with it, the factory must make an indirect
    // estimator too. With active `caustics`, photon rounds run once direct
    // light's first pass is complete, until under their tolerance, and
    // bounce 1 reflects the caustics with direct light.
    CacheWorker(IrradianceCache& cache, SamplerFactory factory, const WorkerSettings& settings,
                IndirectSolver* indirect = nullptr, CausticCache* caustics = nullptr);
    ~CacheWorker();  // stops and joins
    CacheWorker(const CacheWorker&) = delete;
    CacheWorker& operator=(const CacheWorker&) = delete;

    void start();
    void pause();
    void resume();
    // Asks the worker to finish its round, publish, and end; joins it.
    void stop();
    bool paused() const { return paused_.load(); }
    // The worker has ended: stopped, out of samples, or failed.
    bool finished() const { return finished_.load(); }
    // The camera to serve: refined first, and no finer than its pixels.
    // Returns the call's serial: snapshots with this cameraSerial or later
    // were made for this view.
    uint64_t setCamera(const std::optional<RefinementCamera>& view);

    using Reader = SnapshotExchange<CacheSnapshot>::Reader;
    // One per reading thread; see SnapshotExchange.
    Reader reader() { return snapshots_.reader(); }

    // Rethrows, on the calling thread, what ended the worker if it failed:
    // the message names the light, vertex and point where it happened.
    void rethrowIfFailed() const;
    // Blocks until a snapshot with version ≥ `version` exists or the worker
    // has ended; false on timeout.
    bool waitForVersion(uint64_t version, double timeoutSeconds);

private:
    void run();
    void publish(double seconds, bool converged, const std::optional<RefinementCamera>& view, uint64_t cameraSerial,
                 SamplerPool& samplers);
    uint64_t totalSamples() const;

    IrradianceCache& cache_;
    SamplerFactory factory_;
    IndirectSolver* indirect_;
    CausticCache* caustics_;  // null or active
    WorkerSettings settings_;
    SnapshotExchange<CacheSnapshot> snapshots_;
    std::thread thread_;

    mutable std::mutex mutex_;  // control only: pause, view, failure, waits
    std::condition_variable wake_;
    std::atomic<bool> paused_{false}, stopping_{false}, finished_{false};
    std::optional<RefinementCamera> view_;
    bool viewChanged_ = false;
    uint64_t cameraSerial_ = 0;
    std::exception_ptr failure_;
    uint64_t published_ = 0;
    // Direct light's estimated error in the last snapshot, and the state it
    // was scored in: the cache's change key and the camera's serial. While
    // only indirect light works (a bounce's first pass runs with no direct
    // rounds) snapshots reuse it: scoring took 32 of a snapshot's 75 ms in
    // the office, every 0.33 s, on the thread whose helpers wait meanwhile.
    struct KeptScore {
        std::array<uint64_t, 4> cache{};  // IrradianceCache::changeKey
        uint64_t camera = 0;              // setCamera's serial
        double error = 0;
    };
    std::optional<KeptScore> lastDirectError_;
};

}  // namespace ml
