// Indirect irradiance, bounce by bounce (§5.1), each bounce in a cache mesh
// of its own laid over the scene like the direct ones.
//
// Bounce n is sampled with gathers from a source built from bounce n−1's
// mesh (bounce 1 gathers from the direct meshes). Work goes in two passes,
// so that every bounce's light shows early:
//  1. bounce after bounce, every vertex of the bounce's base mesh is
//     gathered once, then the next bounce's source is built from it;
//  2. each bounce is refined until it converges, from a source rebuilt from
//     its predecessor's refined mesh (again each time the predecessor's
//     samples double). Round by round, the bounce refined is the one whose
//     share of the image's error was largest when last measured, not one
//     bounce after the other: in the office bounce 1 took most of a minute
//     to converge, and bounces 2-7, which carry more light than bounce 1
//     there, kept their first pass's single gathers all that time.
// A bounce's first-pass samples came from its predecessor's base mesh;
// refinement adds detail, not light, so they stay in its means. Each bounce carries about ā
// (the albedo light meets) of the light of the one before, so bounce n's
// split and noise tolerances are bounce 1's divided by ā^(n−1) (up to 0.5):
// an error in a weak bounce shows less in the image; each bounce is
// smoother than the one before, so later bounces are split at most once; and
// the estimator is told each source's share (it may gather more cheaply). Once every bounce has
// converged, only bounce 1 keeps refining for new views (it holds the
// indirect light's detail: contact shadows, colour bleeding); the sources of
// later bounces are released.
//
// The direct meshes bounce 1 reflects are taken when it starts, early in
// direct light's first pass (IndirectSettings::startFraction), so that a
// coarse first bounce is in the first complete image; bounce 1 is gathered
// again once direct light's first pass is complete (restart), and its source
// is taken again, refined, when its own refinement starts (pass 2).
#pragma once

#include "IndirectEstimator.h"
#include "IrradianceCache.h"

#include <algorithm>
#include <array>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

namespace ml {

struct IndirectSettings {
    int bounces = 1;          // from countBounces (or --bounces)
    double albedo = 0.5;      // ā, from countBounces: relaxes later bounces' tolerances
    // The ratio of each bounce still to come to the one before, for the
    // image while bounces are missing (displayMeshes): countBounces's
    // areaAlbedo.
    double tailAlbedo = 0.5;
    // Bounce 1's cache: coarser and smoother than direct light's, since
    // indirect light has no sharp shadows of its own and each sample is a
    // whole hemispherical gather.
    CacheSettings cache = defaultCache();
    // Indirect light starts once direct light's first pass is complete or,
    // when what is left of it would take longer than `startSeconds` at the
    // last round's rate, once this fraction of it is done (its copies fill the
    // rest from sampled neighbours), so that a coarse first bounce is in the
    // first complete image; bounce 1 is then gathered again when direct
    // light's first pass completes (restart). Early starts cost that second
    // gather, so short first passes are waited for. Under a sample budget
    // (WorkerSettings::maxSamples) the start never depends on a rate, so
    // that the budget makes the same cache on any machine: indirect light
    // waits for the first pass.
    double startFraction = 0.1;
    double startSeconds = 2.0;
    // A bounce's first pass (its base mesh gathered once: the first
    // complete image) spends at most this many full gathers: with more base
    // vertices than that, each first-pass gather spends this over their
    // number (the estimator's `importance` is scaled by it,
    // IndirectEstimator::setSource: the ray gather casts that share of its
    // rays); later passes spend the full amount. On this machine the
    // office's base (9,941 vertices, 100 rays, 13 meshes looked up per ray)
    // took 2.6 s to gather once. Measured with render office --width 320
    // --height 180 against the 2,048-spp reference (raw relative RMSE): at
    // 5 s, 8.0% and 18.9% (two runs, the second before bounce 2 was shown)
    // at full effort, 6.0% and 6.7% at half (49 rays); at 15 s the same
    // (4.4-4.5%); at 60 s 2.52% and 2.81% net of the reference's noise (the
    // first pass's samples stay in the vertices' means). Every gather at 49
    // rays gave 2.87% at 60 s. The Cornell box's base (fewer vertices) is
    // gathered at full effort: half cost it 0.05% at 3 and 10 s.
    double firstPassGathers = 5000;
    // Per scene light, 1 when bounce 1's gather reads its emission where its
    // rays land instead of the direct sampler sampling it (GatheredLights.h;
    // empty: none). The direct meshes then leave it out (LightCoverage), so
    // the gather must be one that reads it (RayGather).
    std::vector<char> gatheredLights;
    static CacheSettings defaultCache();
    void validate() const;
};

// Bounce `bounce`'s cache settings (bounce 1's tolerances relaxed by
// ā^(n−1), see above) and the layout of every bounce's one mesh: how the
// solver lays its bounces, and RealtimeIndirect the same base mesh. The
// layout depends on the gather: its border inset and whether it keeps a
// thin surface's sides apart (IndirectEstimator::borderInset,
// separatesSides), which the second form takes from `estimator`.
CacheSettings bounceCacheSettings(const IndirectSettings& settings, int bounce);
CacheLayout bounceCacheLayout();
CacheLayout bounceCacheLayout(const IndirectEstimator& estimator);

// A vertex that sees almost no indirect light where its neighbours see
// plenty is hidden: boxed in (the ceiling behind a light hung a hair below
// it, the floor under a block). It is never seen, but the mesh would
// interpolate its darkness into the visible surface around it (a base
// triangle spans a fair part of a wall). Such vertices (below 5% of both
// their neighbours' mean and the mesh's) take their visible neighbours'
// mean, two rings deep. A dark corner, dark like its neighbours, is kept.
void fillHiddenVertices(IrradianceMeshCopy& mesh);

// `mesh` (bounce k's light) reshaped as the bounces after it are guessed,
// each a ratio of the one before. After bounce 1 or 2, with `seenAlbedo`
// (one value per vertex, seenAlbedoOver): its area-weighted mean times the
// albedo each vertex sees over that albedo's area-weighted mean, channel
// by channel (the mean is kept: the tail's ratio says how much light is
// left); after bounce 1 without it, half its own shape and half its mean;
// otherwise its own shape. Bounce 1 carries direct light's pattern (an
// office's ceiling, which no panel lights, holds the most of it, its floor
// little), and the bounces after it tend, as a power iteration does, to
// the transport's dominant shape, near uniform where surfaces see each
// other (progressive radiosity's ambient term, Cohen et al. 1988). A
// uniform light over the room reaches a point as the albedo it sees times
// that light: the ceiling, which sees the grey carpet, gets about 0.6 of
// what the floor under the white ceiling gets (the path tracer, 12-panel
// office: bounces 2-8 over bounce 1 are 0.7 on the ceiling, 1.9-2.0 on the
// floor, 1.6-1.9 on the walls). Measured (before bounce 2 is shown, net of
// the reference's noise): the 12-panel office (320x180, --samples 84000)
// 13.5% relative RMSE half and half, 8.9% by the albedo seen (the ceiling
// 36% too bright before); the Cornell box (256x256, --samples 8000) 8.1%
// and 4.5%. Earlier, at 3 s: bounce 1's shape 19.9% and 10.4%, uniform
// 13.1% and 9.5%. After bounce 2, its own shape (Cornell 2.9%) beats half
// its mean (3.1%) and the mean (4.6%), but not the albedo seen: with bounce
// 2 shown and bounce 3 not, the Cornell box (256x256, --samples 12000 and
// 14000) 2.63% and 2.49% with its own shape, 2.17% and 2.14% so; the office
// (--samples 100000 and 115000) 6.58% and 6.25%, 5.88% and 5.84%. After
// bounce 3 and later the albedo seen was worse (Cornell at 16000-24000
// samples 1.45% against 1.34%, the office at 130000 3.58% against 3.47%).
void shapeAsLaterBounces(IrradianceMeshCopy& mesh, int bounce, const std::vector<Rgb>& seenAlbedo = {});

// Rays per vertex for the albedo bounce 1's vertices see
// (IndirectEstimator::seenAlbedo).
constexpr int kSeenAlbedoRays = 16;
// IndirectEstimator::seenAlbedo at `mesh`'s vertices, each averaged with
// its one ring (the rays are few, and the later bounces' shape is smooth);
// nullopt where the estimator has no cheap rays.
std::optional<std::vector<Rgb>> seenAlbedoOver(IndirectEstimator& estimator, const IrradianceMeshCopy& mesh,
                                               uint32_t seed);

class IndirectSolver {
public:
    IndirectSolver(const Scene& scene, const IndirectSettings& settings);
    ~IndirectSolver();

    const IndirectSettings& settings() const { return settings_; }
    int bounces() const { return settings_.bounces; }
    // Bounces whose cache exists (started: sampled in the first pass), and
    // of those, refined until converged in the second.
    int started() const { return int(caches_.size()); }
    int finished() const { return int(std::count(converged_.begin(), converged_.end(), char(1))); }
    bool firstPassDone() const { return int(caches_.size()) == settings_.bounces && firstPassBounce() == 0; }
    bool allFinished() const { return finished() >= settings_.bounces; }

    // One round of up to `budget` gathers: the first pass's next vertices
    // (starting a bounce, and building its source from `direct()` or the
    // previous bounce, when need be), or the second pass's refinement of the
    // bounce in hand, or, once all have converged, of bounce 1 for the
    // view. Converged when there is nothing left to do.
    RefineReport step(IndirectEstimator& estimator, const std::function<std::vector<IrradianceMeshCopy>()>& direct,
                      size_t budget, uint32_t seed, const std::optional<RefinementCamera>& view);

    // Gathers every started bounce again, first pass and all, bounce 1 from
    // direct light as it is now and each later one from its predecessor
    // gathered anew: for when bounce 1 started from an incomplete first pass
    // of direct light. Until a vertex is gathered again, copies show its old
    // value.
    void restart(IndirectEstimator& estimator);

    // The scene changed (CacheInvalidation.h): every bounce is stale. They
    // are made again from the changed scene's base meshes and gathered
    // bounce after bounce as at the start (a refined cache gathered again
    // costs its refined vertices, more than a fresh one: measured by bench
    // dynamic), each from a source built anew, for the worker's estimator
    // is made anew too. Until bounce 1 is shown again (firstBounceShown),
    // displayMeshes() gives what it gave before the change: the old
    // indirect light, on the old geometry, as a stand-in. `keepOld`: until
    // every bounce's first pass is done instead (a change that moved a
    // small share of the light, kKeepOldLightShare: the old light is then
    // closer than bounces partly gathered, or than a real-time method's).
    void sceneChanged(bool keepOld = false);
    // Every bounce's cache, and those made later, ends a round under way
    // when `interrupted` says so (IrradianceCache::setInterrupt); empty:
    // rounds whole.
    void setInterrupt(std::function<bool()> interrupted);
    // A new worker's estimator holds none of the sources built in the one
    // before (ProgressiveSession::start after a stop): they are built again
    // when next needed.
    void sourcesLost() { sourceBuilt_.assign(sourceBuilt_.size(), false); }
    // displayMeshes() shows the light from before a scene change.
    bool showingStale() const { return !stale_.empty() && !(keepStale_ ? firstPassDone() : firstBounceShown()); }
    // ...and keeps it until every bounce is gathered again (sceneChanged's
    // keepOld).
    bool keepingStale() const { return keepStale_ && showingStale(); }

    // Once every bounce has converged: one more refinement level for every
    // bounce's cache (IrradianceCache::tighten), and pass 2 again (every
    // bounce unconverged and unmeasured, so each has a round first), each
    // bounce's source rebuilt from its predecessor as now refined (bounce
    // 1's from the direct meshes as they are then), so the sources follow
    // refinement. False, changing nothing, while bounces are
    // still being refined or at the last level.
    bool tighten(IndirectEstimator& estimator);
    // The refinement level of bounce 1's cache (0 before any tighten()).
    int level() const;

    // One mesh per started bounce, bounce 1 first, hidden vertices filled
    // (fillHiddenVertices): what is shown and what the next bounce reflects.
    std::vector<IrradianceMeshCopy> copyMeshes() const;
    // What the image shows while bounces are missing: the bounces whose
    // first pass is complete and, for the ones still to come, one more mesh,
    // the last complete bounce k times Σ_{j=1..N−k} r^j (each bounce carries
    // about r = tailAlbedo of the one before), shaped as shapeAsLaterBounces
    // says: all the light is in the image from the
    // first bounce on, its distribution approximate until the bounces are
    // gathered. A bounce being gathered is not shown until it is complete,
    // except bounce 1 (see firstBounceShown).
    std::vector<IrradianceMeshCopy> displayMeshes() const;
    // Bounce 1 is shown once a sixteenth of its base is gathered (its first
    // pass visits vertices in a scattered order and copies fill the rest
    // from gathered neighbours, ring after ring; shownOnceGathered in
    // IndirectSolver.cpp says what was measured) or while it is gathered
    // again after restart(): a rough first bounce is much nearer the truth
    // than none, which leaves a room's ceiling black.
    bool firstBounceShown() const;
    // Bounce 1's first pass (or its regathering after restart()) is done.
    bool firstBounceGathered() const;
    IrradianceMeshCopy copyMesh(int bounce) const;
    size_t totalVertices() const;
    uint64_t totalSamples() const;
    size_t memoryBytes() const;
    // 1 until the first pass is done; then the largest of the bounces'
    // estimated errors, each scaled by its share of bounce 1's light (ā^(n−1)).
    double estimatedError(const std::optional<RefinementCamera>& view) const;
    const IrradianceCache& cache(int bounce) const { return *caches_.at(size_t(bounce - 1)); }

private:
    CacheSettings settingsFor(int bounce) const;
    // Pass 2 from the start: no bounce converged, none measured.
    void resetPass2();
    // Bounce n's share of bounce 1's light, ā^(n−1): how its error shows.
    double share(int bounce) const;
    // Pass 2's next bounce: of those not converged, the one whose share of
    // the image's error was largest when last measured (one not yet
    // measured first, lowest first).
    int nextBounce() const;
    // Releases source `slot` if it is built (nothing otherwise).
    void releaseSource(IndirectEstimator& estimator, size_t slot);
    // The first bounce whose cache has vertices without a sample (0: none).
    int firstPassBounce() const;
    // Bounce `bounce + 1` has gathered a sixteenth of its base and bounce
    // `bounce` is still that base (not refined): it may be shown, and its
    // mean over bounce `bounce`'s measures their ratio (displayMeshes).
    bool gatheredEnoughToShow(int bounce) const;
    // Makes sure source `bounce − 1` holds what bounce `bounce` gathers from.
    // A source built for a first pass (firstPassGathers) is built again for
    // the second.
    void prepareSource(IndirectEstimator& estimator, int bounce,
                       const std::function<std::vector<IrradianceMeshCopy>()>& direct, bool firstPass);

    const Scene& scene_;
    IndirectSettings settings_;
    std::vector<std::unique_ptr<IrradianceCache>> caches_;
    std::shared_ptr<const std::vector<Mesh>> surfaces_;  // what every bounce's cache lays (CacheLayout::surfaces)
    // Pass 2, by slot (bounce − 1): converged at the level in hand; the
    // share of the image's error the bounce's last round began with (its
    // estimated error × ā^(n−1); infinite until it has had a round), which
    // chooses the next bounce; and its predecessor's samples when its
    // source was built, which says when the source is built again.
    std::vector<char> converged_;
    std::vector<double> bounceError_;
    std::vector<uint64_t> sourceSamples_;
    std::vector<bool> sourceBuilt_;  // by slot (bounce − 1)
    std::vector<bool> sourceForFirstPass_;  // by slot: built for a first pass
    bool directRefreshed_ = false;   // bounce 1's source rebuilt for pass 2
    bool regathering_ = false;       // bounce 1 gathered again since restart()
    bool restarted_ = false;         // first passes gathered again since restart(), not done yet
    std::function<bool()> interrupt_;        // setInterrupt's, for every bounce's cache
    std::vector<IrradianceMeshCopy> stale_;  // shown after sceneChanged() until bounce 1 is
    bool keepStale_ = false;                 // ...or until every bounce is (sceneChanged's keepOld)

    // A bounce's copies and score as last made (copyMesh, displayMeshes,
    // estimatedError), kept while its cache is unchanged: a snapshot copied
    // and scored every bounce, though a round changes one. In the 192-panel
    // office's render --time 20 (191,000 bounce vertices) snapshots took
    // 4.3 s of the worker's 20 (21 snapshots): the bounces' display copies
    // 1.95 s, their copies while first passes run 0.69 s, their scores
    // 0.88 s. With this, 2.2 s for 26 (0.83, 0.30 and 0.25 s).
    // Kept while the cache's change key (IrradianceCache::changeKey) and
    // `epoch_` stay: epoch_ counts what the key does not see, restart()
    // resetting the samples and sceneChanged() replacing the caches.
    struct BounceMemo {
        std::array<uint64_t, 4> cache{};  // IrradianceCache::changeKey
        uint64_t epoch = 0;
        std::optional<IrradianceMeshCopy> raw, filled;  // copyMesh(0); its hidden vertices filled
        std::optional<RefinementCamera> view;           // of `error`
        std::optional<double> error;
    };
    // Bounce `bounce`'s memo, emptied if its cache changed; memoMutex_ held.
    BounceMemo& memo(int bounce) const;
    const IrradianceMeshCopy& rawCopy(int bounce) const;
    const IrradianceMeshCopy& filledCopy(int bounce) const;
    std::vector<IrradianceMeshCopy> displayMeshesLocked() const;
    mutable std::mutex memoMutex_;
    mutable std::vector<BounceMemo> memo_;
    // seenAlbedoOver bounce 1's base mesh, made as bounce 1 starts when
    // later bounces follow (empty: one bounce, or the estimator has no
    // cheap rays); memoMutex_ held.
    std::vector<Rgb> seenAlbedo_;
    uint64_t epoch_ = 0;
};

}  // namespace ml
