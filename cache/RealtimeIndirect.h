// The real-time stand-in for indirect light (issue 17): while the cache's
// bounces are being gathered (after a light or an object moved, and at the
// start), the image shows indirect light from one of the real-time methods
// (irradiance volume, virtual point lights, propagation volume:
// gpu_sampling/indirect), computed on a thread of its own from the cache's
// direct light, and blends to the cache's bounces vertex by vertex as they
// are gathered.
//
// The estimate. For the scene as it is, bounce 1's base mesh is laid as the
// indirect solver lays it (bounceCacheSettings, and bounceCacheLayout for the
// worker's gather, which the snapshot carries: the same vertices, bit for
// bit). The method is given the cache's direct light (and
// caustics) as source 0 and estimates bounce 1 at every vertex; that bounce,
// hidden vertices filled as the solver fills them, is source 1 for bounce 2,
// and so on for `methodBounces` bounces; the bounces after those follow the
// last as the solver's own display does while bounces are missing, each
// `tailAlbedo` times the one before. Where the cache's direct light is valid
// (every sample a change left, every vertex sampled since) the source is
// exact; where it is still being sampled, its copies' fill (sampled
// neighbours' means) stands in, and the estimate is made again as direct
// light fills in (offer()).
//
// The blend (blendIndirect). Bounce by bounce: a bounce the cache has not
// started shows the estimate's; a bounce in its first pass (on the base
// mesh, the estimate's own vertices) shows at each vertex the cache's value
// if the vertex was gathered since the change, the estimate's if not (the
// weight is 1 or 0 per vertex, so the mix is exact at both ends), and from a
// quarter gathered on the cache's copy, which fills the rest from gathered
// neighbours; a bounce whose first pass is complete (refined, or every
// vertex gathered) shows the cache's. Once every bounce is complete the
// cache's own display meshes are shown unchanged. Caustics are the cache's throughout (no method estimates
// them). After a change that moved a small share of the light
// (CacheSnapshot::oldIndirectKept, kKeepOldLightShare) the cache's old
// bounces are closer than any method's estimate from scratch: they are
// shown, and nothing is estimated, until the cache has gathered every bounce
// again.
//
// The old light moved by the method's change. Once a session has had a
// complete cache, the cache's bounces from just before a change are exact
// for that pose, and the method's error there is known: its estimate from
// that cache's direct light (the baseline, made once per scene from its
// first complete snapshot, on the estimate's thread while it is idle, so a
// change's first estimate comes no later) less those bounces (the newest
// complete snapshot's, at most a second old). So a change's estimate from
// direct light is shown as the method's estimate with its old error
// corrected away, e + w (old − baseline), at every vertex the scene before
// also had (same position and normal: every surface the change did not
// move), and as the method's own estimate on the moved ones
// (correctByChange). The weight w trusts the old error as far as the
// method's light there stayed the same: 1 where it did not change, falling
// fast as the change grows against the light it had. Measured (bench
// dynamic --quick, the table of the methods, 3 bounces estimated, the
// image against the converged one; each pair from one run), the method
// alone -> on the old light: the Cornell box's light moved 30 mm, volume
// 1.45% -> 0.77%, vpl 3.10% -> 2.71%, lpv 4.84% -> 3.47%; its short block
// moved, volume 1.68% -> 1.16%, vpl 2.91% -> 2.33%, lpv 4.87% -> 2.39%; its
// light moved 180 mm (a third of the box: little of the old error stays),
// volume 1.70% -> 1.67%, vpl 3.00% -> 2.61%, lpv 4.93% -> 4.32%. With
// every bounce estimated (bench dynamic, one run): the block volume 1.73%
// -> 1.36%, vpl 3.33% -> 2.91%, lpv 5.55% -> 2.67%; the light moved 180 mm
// vpl 3.92% -> 3.53%, lpv 5.62% -> 4.97%, but volume 1.74% -> 1.93%. A
// cold start has no complete cache: the method's estimate alone.
//
// Which method. No one method is best on every scene: from converged direct
// light, volume's image is 1.7% from the converged one on the Cornell box
// and 9% on the office, vpl's 3.9% and 26%, lpv's 5.6% and 13% (bench
// dynamic's table of the methods), and their times differ as much. "auto"
// measures them on the scene itself: at the first complete cache (the
// baseline's moment, while the estimate's thread is idle) each candidate's
// baseline is made and compared with the cache's bounces (standInError: the
// indirect light at bounce 1's base vertices), and the one with the least
// error among those fast enough (chooseStandIn) stands in from the next
// change on, its baseline kept. The first candidate stands in until then; a
// change during the measurement ends it, and the next complete cache
// measures again. The panel says what was chosen and why (choice()).
//
// While the new pose's estimate is made. Right after a change the newest
// estimate is of the pose before; if it is older than that pose's complete
// cache (made before the cache completed, as every estimate is), the
// cache's old light shows instead (display()), exact for the pose before.
//
// Threads. offer() and display() run on the caller's (frame) thread and do
// no estimating: offer() hands the snapshot's direct meshes to the
// estimate's thread, which makes the estimator for each new scene (its
// Embree scene, probe grid or geometry volume) and the estimate, then
// publishes it; a request made while one is computed replaces the pending
// one (the newest wins), and ends the one under way between two bounces if
// it is chained further for the same scene, or is for a later scene (a
// motion's next pose: its last pose is then estimated at once) unless two
// estimates in a row ended so (while poses keep coming, every third is
// shown). So frames never wait.
#pragma once

#include "CacheWorker.h"
#include "IndirectEstimator.h"
#include "IndirectSolver.h"
#include "core/Scene.h"

#include <atomic>
#include <condition_variable>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace ml {

// Bounce 1's base mesh for a scene, as the indirect solver lays it for a
// gather (`layout`: CacheSnapshot::bounceLayout): the geometry (irradiance
// 0, samples 0) and each vertex's shading point.
struct RealtimeMesh {
    IrradianceMeshCopy geometry;
    std::vector<SampleRequest> points;  // one per vertex of `geometry`, mesh 0
    CacheLayout layout;
    RealtimeMesh(const Scene& scene, const IndirectSettings& settings, const CacheLayout& layout);
};

// One estimate of every bounce.
struct RealtimeEstimate {
    std::string method;            // the estimator's name()
    uint64_t sceneVersion = 0;     // the scene it is for (as offer() was told)
    uint64_t snapshotVersion = 0;  // the cache snapshot whose direct light it reflects
    double directSampled = 0;      // that snapshot's share of direct vertices with a sample
    // Bounces 1..chained are the cache's as gathered then (on the base
    // mesh; the last may be partly gathered, its copy filled), the later
    // ones the method's from the cache's bounce `chained`; 0: every bounce
    // the method's, from direct light.
    int chained = 0;
    // Bounce 1, 2, ... on bounce 1's base mesh (RealtimeMesh::geometry),
    // samples 0 at every vertex.
    std::vector<IrradianceMeshCopy> bounces;
    // The share of the bounces' vertices that are the old light moved by
    // the method's change (correctByChange); 0: the method's own estimate.
    double onOldLight = 0;
    double seconds = 0;            // making it: estimator (for a new scene), sources, estimates, baseline
    uint64_t serial = 0;           // 1, 2, ... in order of completion
};

// Bounces 1..settings.bounces on `mesh` from `source` (the cache's direct
// meshes, and its caustic mesh if any): the first `methodBounces` (0: all)
// estimated by `estimator` (sources 0.. are replaced and released), the
// rest a tail.
// Estimates draw their jitter from (seed, bounce, vertex). Returns nothing
// when `cancelled` says so between bounces.
std::optional<std::vector<IrradianceMeshCopy>> estimateBounces(const RealtimeMesh& mesh, IndirectEstimator& estimator,
                                                               const IndirectSettings& settings, int methodBounces,
                                                               const std::vector<IrradianceMeshCopy>& source,
                                                               uint32_t seed,
                                                               const std::function<bool()>& cancelled = {});

// The same, chained onto bounces the cache has gathered: bounces 1..k are
// `known` (on `mesh`'s vertices), and bounce k + 1 gathers from `source`,
// the cache's bounce k as it is (refined or not, or partly gathered and
// filled: the method reads the mesh's own vertices). With `known` empty,
// `source` is direct light and this is estimateBounces. A bounce after
// `methodBounces` is a tail of the one before, as there.
std::optional<std::vector<IrradianceMeshCopy>> chainBounces(const RealtimeMesh& mesh, IndirectEstimator& estimator,
                                                            const IndirectSettings& settings, int methodBounces,
                                                            std::vector<IrradianceMeshCopy> known,
                                                            const std::vector<IrradianceMeshCopy>& source,
                                                            uint32_t seed,
                                                            const std::function<bool()>& cancelled = {});

// Bounce by bounce, each vertex of `estimate` (the method's bounces for the
// scene as it is) that `baseline` (the method's bounces for the scene
// before, on that scene's base mesh) and `before` (the cache's complete
// bounces for the scene before, refined or not) also have, at the same
// position with the same normal, becomes e + w (before − baseline) per
// channel, at least 0, with w = (L(baseline) / (L(baseline) + |L(e) −
// L(baseline)|))^6 of the luminances (1 where both are 0); the rest stay
// as they are. A bounce missing from either stays. Returns the share of the
// estimate's vertices changed (RealtimeEstimate::onOldLight).
double correctByChange(std::vector<IrradianceMeshCopy>& estimate, const std::vector<IrradianceMeshCopy>& baseline,
                       const std::vector<IrradianceMeshCopy>& before);

// How many of the snapshot's bounces, from bounce 1, the cache has gathered
// since the scene last changed: each of their vertices has a sample (a first
// pass visits every base vertex before any refines). 0 once the cache's
// indirect light is complete (nothing stands in then).
int gatheredBounces(const CacheSnapshot& s);

// What an image shows of indirect light.
struct IndirectShown {
    // As CacheSnapshot::indirect: bounce meshes, then the caustic mesh if any.
    std::vector<IrradianceMeshCopy> meshes;
    // The share of the shown indirect irradiance (luminance summed over the
    // bounce meshes' vertices) that is the estimate's: 0 the cache alone, 1
    // the estimate alone.
    double realtimeShare = 0;
    uint64_t estimateSerial = 0;  // the estimate shown, 0: none
    // For the panel and status line: "cache", "volume (real-time)",
    // "cache 40% + volume 60% (catching up)", ...
    std::string source;
    // For the panel, with "auto": which method stands in and why
    // (RealtimeIndirect::choice); empty otherwise.
    std::string choice;
};

// The blend above of snapshot `s` (of the scene of version `sceneVersion`)
// and `estimate` (null: none yet). `live`: the estimate alone whenever there
// is one for this scene (the viewer's --indirect-display METHOD). An
// estimate of an earlier scene (the one for this scene still being made)
// stands in whole while the cache is incomplete: it is newer than the
// cache's stale bounces.
IndirectShown blendIndirect(const CacheSnapshot& s, uint64_t sceneVersion, const RealtimeEstimate* estimate,
                            bool live = false);

struct RealtimeSettings {
    // The method ("volume", "vpl" or "lpv", as the factory knows them);
    // "auto": the one of `candidates` chosen by its error on this scene
    // (chooseStandIn), the first of them until it is measured; or "off": no
    // stand-in, the cache's own display (its old bounces after a change,
    // the bounces gathered so far at the start).
    std::string method = "volume";
    std::vector<std::string> candidates;  // for "auto"
    // Show the method's estimate always, not only while the cache catches
    // up (the viewer's --indirect-display METHOD); needs a method.
    bool live = false;
    // Bounces the method estimates, later ones a tail (0: every bounce;
    // kBouncesFromScene: standInBounces, chosen by the scene's albedo;
    // every bounce when live, which shows the method itself).
    static constexpr int kBouncesFromScene = -1;
    int methodBounces = kBouncesFromScene;
    uint32_t seed = 1;
    void validate() const;
};

// The bounces a stand-in estimates when the scene chooses: the fewest k
// after which the tail (each later bounce tailAlbedo r times the one
// before) carries at most kStandInTailShare of the indirect light (r^k of
// it), and at most every bounce: the Cornell box 3 of 8 (r = 0.535), the
// office 4 of 7 (r = 0.63), a white room more. The tail's light is right in
// total (a ratio of bounce k), only its spread is guessed
// (shapeAsLaterBounces), and on the old light correctByChange takes out
// most of that guess, while every bounce estimated costs an update of the
// method, and the image shows the pose before until the estimate comes.
// Measured (bench dynamic, the Cornell box, auto choosing volume): every
// bounce estimated (two runs), auto's volume trial 0.88-0.92 s, the light
// back within 2% after 1.99-2.13 s against a cold start's 2.80-2.87 s, the
// block after 1.04 s against 1.23-1.52 s; three (four runs), the trial
// 0.43-0.74 s, the light after 0.50-0.62 s against 1.78-2.27 s, the block
// after 0.25-0.28 s against 1.39-1.88 s (viewer/README.md, "Fewer bounces
// estimated"). From converged direct light, three of eight leave about the
// image error of all eight (volume 1.84% against 1.74%, vpl 2.72% against
// 2.69%, lpv 5.44% against 5.56%: bench dynamic's table of the methods).
int standInBounces(const IndirectSettings& indirect);
constexpr double kStandInTailShare = 1.0 / 6;

// One method measured as "auto" measures it: its estimate from a complete
// cache's direct light against that cache's bounces.
struct StandInTrial {
    std::string method;
    double error = 0;    // standInError; infinity: nothing to compare
    double seconds = 0;  // the estimator made and every bounce estimated, on the estimate's thread (and its helpers)
};

// How far `estimate` (a method's bounces on bounce 1's base mesh) is from
// `cache` (the cache's complete bounces of the same scene, refined or not):
// at each vertex of the estimate that every bounce of the cache also has
// (same position and normal), the luminance of the bounces summed; the sum
// over those vertices of |estimate − cache| over the sum of the cache's.
// The vertices of the base mesh weigh alike (they are spread over the
// surfaces at about the base mesh's spacing). Infinity when no vertex
// matches or the cache has no light there.
double standInError(const std::vector<IrradianceMeshCopy>& estimate, const std::vector<IrradianceMeshCopy>& cache);

// The stand-in "auto" picks from `trials` (none: -1): the one with the
// least error among those whose time is at most kStandInSlowFactor times the
// fastest's, or kStandInSlowSeconds. Why a limit: until its estimate comes
// the image shows the pose before's, so a slow method's better estimate can
// come too late to gain (bench dynamic, the Cornell box's block, an earlier
// version: volume at 2.4 s an update brought the image within 2% at 4.1 s,
// vpl at 0.7 s at 1.5 s). Why the floor: where every method takes about a
// second, the better estimate is worth its time. Measured with this rule
// (viewer/README.md, "Auto and the end of a motion"): on the office volume
// is chosen (21% in 1.2 s against vpl's 58% in 2.9 s); on the Cornell box
// too (6.9% in 1.3 s, vpl 10% in 0.5 s), and its light's move came back
// within 2% 2-4 times sooner than with vpl, its block's moves later (1.8-2.0
// s against 0.8-1.5 s).
int chooseStandIn(const std::vector<StandInTrial>& trials);
constexpr double kStandInSlowFactor = 2.5;
constexpr double kStandInSlowSeconds = 1.5;

// "vpl 58% in 2.9 s; volume 21% in 1.2 s (chosen); lpv 25% in 0.56 s"
// (two significant digits).
std::string describeTrials(const std::vector<StandInTrial>& trials, int chosen);

class RealtimeIndirect {
public:
    // Makes the estimator a method names for a scene, on the estimate's
    // thread (the scene outlives it).
    using EstimatorFactory =
        std::function<std::unique_ptr<IndirectEstimator>(const Scene& scene, const std::string& method)>;
    // `nice`: the estimate thread's niceness (0: the caller's). The viewer
    // runs it at its frames' priority (0), above the cache's workers (10):
    // the estimate is what the next frames show (bench dynamic at 5: the
    // estimates came later and the cache no sooner, viewer/README.md).
    RealtimeIndirect(const IndirectSettings& indirect, EstimatorFactory factory, const RealtimeSettings& settings,
                     int nice = 0);
    ~RealtimeIndirect();  // lets the bounce under way finish, then joins
    RealtimeIndirect(const RealtimeIndirect&) = delete;
    RealtimeIndirect& operator=(const RealtimeIndirect&) = delete;

    const RealtimeSettings& settings() const { return settings_; }
    // Another method, or live or not: the next offer asks for an estimate
    // with it; meanwhile the last estimate (of the method before) stays.
    void configure(const RealtimeSettings& settings);

    // A snapshot of the cache of `scene`, whose version the caller changes
    // whenever the scene does (the first offer of a version hands over its
    // scene, kept alive here). A complete snapshot (not live) is kept, at
    // most one a second, as the pose before the next change (the old light
    // and the baseline's direct light, above). Asks for a new estimate when there is a
    // method and the cache still needs a stand-in (or the display is live),
    // and: none was asked for this scene (and settings); or the cache's
    // bounces have gone further (not live): another bounce gathered
    // (gatheredBounces), or a quarter of the one being gathered, whose copy
    // fills the rest from gathered neighbours; the bounces after it are then
    // chained onto it (chainBounces); or, before any of bounce 1 is
    // gathered, direct light has filled in since the last one asked (its
    // sampled share up by a tenth, or complete) or its estimated error has
    // halved. Otherwise does nothing. A request replaces one still waiting,
    // and may end the one under way between two bounces (Threads, above).
    //
    // Why chained: the method's error compounds bounce after bounce from
    // its own first bounce; chained onto the cache's bounce 1 the later
    // bounces are far nearer (bench dynamic, the final poses, 160x90: every
    // bounce from converged direct light against the same chained onto the
    // converged cache's bounce 1, the image from the converged one: vpl
    // 2.7-3.2% -> 1.5-1.6%, volume 1.7% -> 0.7-0.8%, lpv 5.6% -> 2.5-2.9%).
    void offer(const CacheSnapshot& s, uint64_t sceneVersion, const std::shared_ptr<const Scene>& scene);
    // The newest estimate (null before the first).
    std::shared_ptr<const RealtimeEstimate> latest() const;
    // blendIndirect of `s` with the newest estimate (none with method off);
    // but while the newest is of an earlier scene and older than that
    // scene's complete cache (the pose before), `s`'s old light
    // (CacheSnapshot::indirectStale) until this scene's estimate comes.
    IndirectShown display(const CacheSnapshot& s, uint64_t sceneVersion) const;
    // An estimate is being made or waits to be.
    bool busy() const;
    // With "auto": the method standing in and why ("volume, chosen by its
    // error on this scene's complete cache: vpl 58% in 2.9 s; volume 21% in
    // 1.2 s (chosen); lpv 25% in 0.56 s", or "vpl until the methods are
    // measured on the first complete cache"); empty otherwise.
    std::string choice() const;
    // Blocks until no baseline (or auto's measurement) is wanted or being
    // made, or `timeoutSeconds` pass; true if so.
    bool waitBaseline(double timeoutSeconds) const;
    // With "auto": the methods as measured for the choice (empty before).
    std::vector<StandInTrial> trials() const;
    // What ended the thread, rethrown here (the estimator's failure).
    void rethrowIfFailed() const;
    // Blocks until nothing is pending or under way and the newest estimate
    // is for `sceneVersion`, or `timeoutSeconds` pass; true if so.
    bool waitIdle(uint64_t sceneVersion, double timeoutSeconds) const;

private:
    // The last complete cache offered: the scene before the next change.
    // The baseline's direct light is the first complete snapshot's of the
    // scene (the baseline is made from it once, while the thread is idle);
    // the bounces are the newest complete snapshot's, at most
    // kBeforeSeconds old (refined further, closer to exact).
    struct Before {
        std::shared_ptr<const Scene> scene;
        uint64_t sceneVersion = 0, snapshotVersion = 0;
        // Its direct light and caustics (shared by the Befores of one scene
        // version: the baseline's key).
        std::shared_ptr<const std::vector<IrradianceMeshCopy>> source;
        // Its bounces (CacheSnapshot::indirect without caustics): positions,
        // normals and irradiance only.
        std::vector<IrradianceMeshCopy> bounces;
        CacheLayout layout;
    };
    struct Request {
        std::shared_ptr<const Scene> scene;
        uint64_t sceneVersion = 0, snapshotVersion = 0;
        double directSampled = 0;
        RealtimeSettings settings;
        // What bounce 1 reflects: direct light and caustics (the source
        // when nothing is chained).
        std::vector<IrradianceMeshCopy> source;
        std::vector<IrradianceMeshCopy> known;  // the cache's gathered bounces, 1..k
        CacheLayout layout;                     // the cache's bounces' (CacheSnapshot::bounceLayout)
        int level = 0;                          // chainLevel
        // The pose before, for an estimate from direct light (level 0) of
        // a later scene; null: none (a cold start, chained, live).
        std::shared_ptr<const Before> before;
    };
    void run(int nice);
    // Keeps complete snapshot `s` as the pose before (Before), at most once
    // every kBeforeSeconds for one scene: a copy of every mesh.
    void keepBefore(const CacheSnapshot& s, uint64_t sceneVersion);
    static constexpr double kBeforeSeconds = 1.0;

    // `settings` validated, its methodBounces chosen from the scene if asked.
    RealtimeSettings resolved(RealtimeSettings settings) const;
    IndirectSettings indirect_;
    EstimatorFactory factory_;
    RealtimeSettings settings_;  // the caller's thread only

    // What the caller asked last (its thread only).
    struct Asked {
        uint64_t sceneVersion = 0;
        std::shared_ptr<const Scene> scene;
        double directSampled = 0, directError = 1;
        bool any = false;
        int chained = 0;  // the chain level it was chained onto (chainLevel in the .cpp)
    } asked_;
    std::shared_ptr<const Scene> offeredScene_;  // the scene of asked_/the last offer's version
    uint64_t offeredVersion_ = 0;
    std::shared_ptr<const Before> before_;
    double beforeTakenAt_ = 0;  // steady clock, s

    mutable std::mutex mutex_;
    mutable std::condition_variable wake_;
    std::optional<Request> pending_;
    // A baseline to make while no estimate is asked for: the pose before
    // and the settings then (the first complete snapshot of a scene).
    std::optional<std::pair<std::shared_ptr<const Before>, RealtimeSettings>> baselineWanted_;
    bool working_ = false, stopping_ = false, baselining_ = false;
    // "auto": the trials and the one chosen (-1: not measured yet; a
    // measurement a request interrupts is made again at the next scene's
    // complete cache).
    std::vector<StandInTrial> trials_;
    int chosen_ = -1;
    // The method a request of `settings` uses (auto resolved).
    std::string methodFor(const RealtimeSettings& settings) const;
    std::shared_ptr<const RealtimeEstimate> latest_;
    std::exception_ptr failure_;
    uint64_t serial_ = 0;
    std::thread thread_;
};

}  // namespace ml
