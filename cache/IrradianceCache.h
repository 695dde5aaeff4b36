// The multi-mesh irradiance cache (§3.2): one mesh per light for its direct
// irradiance, laid over every object of the scene, with samples stored at
// the mesh vertices and Gouraud-interpolated in between when drawn.
//
// Each mesh starts as the objects' triangles split by longest-edge bisection
// down to a maximum edge length, and is then refined on its own, in rounds
// (refine()): edges are split where the irradiance, as it will be displayed,
// is not linear between their ends or where light visibility is partial,
// and vertices whose mean is still noisy are sampled again with fresh
// jitter. Every split is a conforming longest-edge bisection (Rivara's
// LEPP), so a cache mesh never has T-vertices inside an object.
//
// OpenMesh stays inside cache/: the public types are Meshlight's own.
#pragma once

#include "ContactCuts.h"
#include "VertexSampler.h"
#include "core/Camera.h"
#include "core/Scene.h"
#include "core/SceneChange.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ml {

class LightCoverage;
namespace detail {
struct NoiseModel;
}

struct CacheSettings {
    // Base mesh: triangles are bisected until no edge is longer than this
    // fraction of the scene's bounding diagonal, typical 1/16..1/128. The
    // geometry drawn in the image is never changed.
    double maxEdgeFraction = 1.0 / 32.0;
    // Refinement never splits an edge shorter than this fraction of the
    // scene's diagonal (1/4096 of the Cornell box: 0.2 mm)...
    double minEdgeFraction = 1.0 / 4096.0;
    // ...nor, when a view is given, one shorter than this many pixels on
    // screen: finer detail cannot be seen.
    double minEdgePixels = 1.0;
    // An edge is split while the interpolation error predicted at its
    // midpoint exceeds this fraction of the local displayed level (Weber
    // contrast: 1% is about the smallest step people see in a smooth ramp).
    double splitTolerance = 0.01;
    // Edges longer than this fraction of the diagonal are split whatever
    // their predicted error (0: none), after the splits and resamples that
    // score higher: the bounce meshes, whose noisy gathers hide the
    // curvature the predicted error is read from, while linear
    // interpolation of indirect light, which falls towards corners and
    // edges, reads it dark (IndirectSolver.cpp, bounceCacheSettings).
    double uniformEdgeFraction = 0;
    // A vertex is sampled again while the standard error of its mean exceeds
    // this fraction of its displayed level...
    double noiseTolerance = 0.005;
    // ...up to this many samples.
    uint32_t maxSamplesPerVertex = 64;
    // The error of one sample in a penumbra, relative to the light's
    // unoccluded irradiance there, assumed until a second sample measures
    // it: 0.2% is the largest error of one jittered 64×64, 8-bit estimate
    // over the bench scene's 10,000 receivers (bench direct: 0.15%).
    double singleSampleNoise = 0.002;
    // The relative error of any one sample, for samplers that cannot tell a
    // noisy sample from an exact one (indirect gathers): > 0 makes every
    // vertex with a single sample count as that noisy, until the cache's
    // resampled vertices measure it (sampleNoise()). 0 for direct light.
    double sampleNoise = 0;
    // Budgets over all meshes: refinement stops splitting at either.
    // Lights share: a light keeps a mesh of its own only where it gives at
    // least this share of the direct light (by a bound from its power,
    // distance and orientation; LightCoverage.h), typical 0.05..0.2; the rest of
    // its light goes to one shared mesh. 0: every light's mesh everywhere.
    // Used when the layout asks for it (CacheLayout::coverage).
    double lightShare = 0.1;
    // The shared mesh's occluded light is estimated from this many shadow
    // rays, each to a point on a light drawn by its share (SharedLightSampler),
    // where more lights are left to draw than the light sampler's pairs
    // would take; 0: always by the light sampler's pairs (--method).
    int sharedRays = 256;
    // Base meshes are cut along the edges of surfaces hanging close in
    // front of them (ContactCuts.h): an edge within this fraction of its
    // length of a surface, typical 0.1 (a panel 2 cm under a ceiling, 0.6 m
    // wide: 0.033); 0: no cuts (direct light's default; the bounces' is 0.1,
    // IndirectSettings::defaultCache).
    double contactCloseness = 0;
    // Base meshes are cut where they cross the plane of a planar light near
    // it, and where that light bends in front of it (lightCutPlanes,
    // ContactCuts.h): direct light has a kink there that no split finds.
    // The surfaces near a plane are bisected to the base's edges before the
    // cut, so it adds the line's vertices alone (cache/README.md, "Lights'
    // planes"). The bounces' meshes are never cut
    // (IndirectSettings::defaultCache).
    bool lightPlaneCuts = true;
    size_t maxVertices = 4'000'000;
    size_t maxMemoryBytes = size_t(1) << 30;

    void validate() const;  // InputError on a bad value
};

// The relative error assumed for light a copy shows but no sample has
// measured: a vertex filled from its sampled neighbours, a bounce
// reflecting a direct light still partly filled (the missing bounces' tail
// has its own, IndirectSolver::displayMeshes).
// Measured (test_image_error): with 0.25 the image's estimate is 0.78x the
// path tracer's error on the Cornell box with bounce 1 shown early (3.7%)
// and 0.97x on a small office in its first pass (10.8%); 0.5 made them
// 1.4x and 1.8x, 0.15 made them 0.56x and 0.63x.
constexpr double kGuessedLightError = 0.25;

// An immutable copy of one cache mesh, for drawing and for tests.
struct IrradianceMeshCopy {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;             // unit, the side that was sampled
    std::vector<glm::uvec3> triangles;
    std::vector<Rgb> irradiance;           // W·m⁻², mean of the samples
    std::vector<uint32_t> samples;         // samples averaged at each vertex
    // The standard error of each vertex's mean, W·m⁻²: the relative spread of
    // its samples' luminance, pooled with their own variance where they
    // measured it (a ray gather's rays), applied to its RGB mean; 0 where
    // its noise is not measured (fewer than two samples that did not
    // measure their own). Empty in copies made elsewhere (tests, sources
    // built by hand): read as 0.
    std::vector<Rgb> standardError;
    // The error each vertex predicts for the irradiance shown around it,
    // W·m⁻², as an RMS over its faces: its noise and its edges'
    // interpolation error (detail::predictedErrors), as RGB of its mean's
    // colour. What the image's error estimate composites
    // (viewer/compositor/ImageErrorEstimate.h). Empty where not made: read
    // as 0.
    std::vector<Rgb> predictedError;
    // The part of predictedError that is the vertex's own sampling noise
    // (≤ it, W·m⁻²): independent of every other mesh's and of the next
    // vertex's, unlike the interpolation error (a corner is read dark by
    // every bounce) or a guess. The image's estimate adds the noise of
    // different meshes in quadrature and the rest linearly
    // (viewer/compositor/ImageErrorEstimate.h). Empty: none of it is noise.
    std::vector<Rgb> predictedNoise;
};

// A camera the refinement should serve: what it sees is refined first and
// no finer than `CacheSettings::minEdgePixels` of its image.
struct RefinementCamera {
    Camera camera;
    int width = 512;
    int height = 512;
};

// What one refinement round did.
struct RefineReport {
    size_t splits = 0;        // vertices added
    size_t resamples = 0;     // extra samples at existing vertices
    size_t estimates = 0;     // calls of the sampler
    size_t candidates = 0;    // actions that were wanted (≥ what the budget allowed)
    double estimatedError = 0;  // before the round; see IrradianceCache::estimatedError
    bool converged() const { return candidates == 0; }
};

// The scene's meshes as a cache with `settings` lays its base meshes over
// them: cut along the surfaces hanging close in front of them where
// settings.contactCloseness asks (ContactCuts.h), objects with a grid cache
// (decideGridCache) left as they are; `report`, when given, says what was cut.
std::vector<Mesh> cacheSurfaces(const Scene& scene, const CacheSettings& settings,
                                ContactCutReport* report = nullptr);

// Which meshes a cache holds, and which faces of open objects get a reversed
// copy so that each side keeps its own irradiance.
struct CacheLayout {
    enum class BackFaces {
        // Faces a light shines on from behind: direct light.
        LitFromBehind,
        // Those, and faces whose back looks out at the scene beyond their
        // own object (BackFaceReach.h): light reflected by any surface may
        // arrive there. Not the insides of open objects.
        ReachedByScene,
    };
    size_t meshes = 0;  // 0: one per light
    BackFaces backFaces = BackFaces::LitFromBehind;
    // How far a border vertex in the plane of a surface meeting it there
    // (EdgeOnSurfaces) is sampled inside its faces, in its shortest edge,
    // and every border vertex's by default.
    static constexpr double kDefaultInset = 1e-3;
    // Sample every vertex on an object's border `borderInset` of its
    // shortest edge inside its faces, not only those in the plane of a
    // surface meeting them (kDefaultInset; see position()): for gathers, to which
    // a floor's edge under a wall would otherwise see both rooms, and a
    // block's foot only the sliver of floor beside it
    // (IndirectEstimator::borderInset).
    bool insetBorders = false;
    double borderInset = kDefaultInset;
    // Direct light with lights sharing (LightCoverage.h): when it shares,
    // mesh l < L keeps only the faces where light l has weight, and one more
    // mesh, the shared one, covers the whole scene. Null: a mesh per light
    // (or `meshes`) over the whole scene.
    std::shared_ptr<const LightCoverage> coverage;
    // The scene's surfaces as the cache lays them, cacheSurfaces(scene,
    // settings) for this very scene and settings, made once for several
    // caches (the indirect solver's bounces: cutting along contacts takes a
    // few hundredths of a second each time). Null: made here.
    std::shared_ptr<const std::vector<Mesh>> surfaces;
};

class IrradianceCache {
public:
    IrradianceCache(const Scene& scene, const CacheSettings& settings = {}, const CacheLayout& layout = {});
    ~IrradianceCache();
    IrradianceCache(const IrradianceCache&) = delete;
    IrradianceCache& operator=(const IrradianceCache&) = delete;

    // The settings the cache was made with (what a cache file must match).
    const CacheSettings& settings() const;
    // Progressive refinement beyond them: one more level halves the split
    // and noise tolerances and doubles the samples a vertex may take, so a cache that
    // has converged at one level refines on toward the exact irradiance
    // (CacheWorker tightens direct light's meshes once they have all
    // converged at their level, whatever indirect light does). Returns false, changing nothing, at
    // kMaxRefinementLevel. The level is saved with the cache.
    bool tighten();
    int level() const;
    static constexpr int kMaxRefinementLevel = 6;
    // The relative error of one sample that a vertex sampled once is taken
    // to have: CacheSettings::sampleNoise as assumed, until the vertices
    // sampled more than once measure it (their spreads pooled, weighted by
    // their light, over at least 64 degrees of freedom). 0 for a sampler
    // whose samples can be exact (direct light).
    double sampleNoise() const;
    // Meshes in all: lightCount(), then the shared mesh if there is one.
    size_t meshCount() const;
    // Meshes of their own: one per light (or per CacheLayout::meshes).
    size_t lightCount() const;
    // The last mesh holds the light the lights share (CacheLayout::coverage).
    bool hasSharedMesh() const;
    size_t vertexCount(size_t light) const;
    size_t triangleCount(size_t light) const;
    size_t totalVertices() const;
    // Faces of open objects lit from behind get a reversed copy in every
    // light's mesh, so each side keeps its own irradiance: how many.
    size_t backFaceCount() const;
    // Objects sampled on a grid cache instead (decideGridCache).
    size_t gridObjectCount() const;
    uint64_t totalSamples() const;
    uint64_t rounds() const;  // refinement rounds so far
    // Rounds, level, samples and vertices: every change of the cache adds a
    // round, a level, a sample or a vertex (resetSamples aside, which those
    // who keep copies count themselves), so a copy or score made from the
    // cache stays valid while this is the same (CacheWorker's direct score,
    // IndirectSolver's bounce copies).
    std::array<uint64_t, 4> changeKey() const {
        return {rounds(), uint64_t(level()), totalSamples(), uint64_t(totalVertices())};
    }
    size_t unsampledCount() const;  // vertices (and grid samples) without a sample yet
    // The shading point of a vertex: where and facing where it is sampled
    // (on an object's border in the plane of a surface meeting it there,
    // EdgeOnSurfaces, a thousandth of its shortest edge inside its faces:
    // right on the border, samplers would see that surface edge-on, and miss
    // an emitter's light or see past a ceiling into the light above it).
    Vec3 position(size_t light, size_t vertex) const;
    Vec3 normal(size_t light, size_t vertex) const;

    // Adds one irradiance estimate at a vertex (running mean).
    void addSample(size_t light, size_t vertex, const VertexSample& sample);
    // Forgets every sample, to sample the cache again from a better source
    // (the indirect solver, once direct light is complete): every vertex is
    // unsampled again, but copies show its last mean until it has a new one.
    void resetSamples();
    // A copy of mesh `mesh` (a light's, or the one mesh of an indirect
    // bounce), and of every mesh in order.
    IrradianceMeshCopy copyMesh(size_t mesh) const;
    std::vector<IrradianceMeshCopy> copyMeshes() const;

    // Samples every vertex that has none yet, in (light, vertex) order, with
    // seeds from (seed, vertex, light, sample index): a run repeats bit for
    // bit. Returns the number of estimates. Errors are rethrown with the
    // light, vertex and point where they happened.
    size_t sampleUnsampled(VertexSampler& sampler, uint32_t seed,
                           const std::function<void(size_t, size_t)>& progress = {});

    // One refinement round. While vertices have no sample yet, a round
    // samples up to `budget` of them. After that, every mesh's edges and
    // vertices are scored, the best-scoring splits and resamples up to
    // `budget` estimates are done, and every new vertex is sampled. Deterministic: the same cache state,
    // budget, seed and view give the same result whatever happened before
    // (a cache saved and loaded refines exactly like one never saved).
    RefineReport refine(VertexSampler& sampler, size_t budget, uint32_t seed,
                        const std::optional<RefinementCamera>& view = std::nullopt);
    // While set, a round's samples are taken in batches of a few
    // hundredths of a second, `interrupted` asked before each: once it says
    // so, the round ends with what it took (a first pass's vertices not
    // reached stay unsampled, resamples not reached are not taken; the
    // vertices a round's splits made are always sampled, so that a refined
    // cache keeps an estimate of its error), and the report counts those.
    // For a worker's stop under a time limit (CacheWorker), where a round of
    // thousands of samples at milliseconds each (the back rooms) held the
    // stop for tens of seconds; never under a sample budget, whose rounds no
    // clock may decide. Empty: every round whole, in one batch.
    void setInterrupt(std::function<bool()> interrupted);
    // While vertices have no sample, every `every`-th of them (a hash of its
    // index picks it: spread over the scene like the first pass's order)
    // takes a second sample right after its first, so that the cache's
    // noise (sampleNoise(), noiseModel) is measured from the first pass on,
    // not assumed: for a noisy sampler's cheap first pass (IndirectSolver:
    // a large base gathered with a fraction of the rays), whose noise the
    // assumed level for a full sample misjudges. 0: none (the default).
    void setNoiseProbes(size_t every);

    // The error the cache itself predicts, relative to the displayed level:
    // the RMS (area-weighted over every mesh) of the interpolation error
    // predicted at the midpoints of edges that can still be split, and of
    // the relative standard error of vertex means; 1 while some vertex has
    // no sample yet. It tracks the relative RMSE of the
    // image against a converged one; compare both with `render --log`.
    // With a view, what it sees weighs 10× more than the rest.
    double estimatedError(const std::optional<RefinementCamera>& view = std::nullopt) const;

    // The luminance of every mesh's irradiance integrated over its surface
    // (W: vertex means times their areas, unsampled vertices as 0): how
    // much light the cache holds, to weigh one cache's error against
    // another's (CacheWorker: indirect light against direct light).
    double integratedLuminance() const;
    // The shared mesh's part of it (hasSharedMesh); 0 without one.
    double sharedLuminance() const;

    // --- A scene that changed (CacheInvalidation.h) ---
    // Forgets the samples of mesh `mesh`'s vertices (and grid samples) at
    // which `which(point, normal)` holds: they are unsampled again, so
    // refine() takes them first, and copies fill them from sampled
    // neighbours meanwhile (their old means are wrong now, unlike after
    // resetSamples()). Returns how many were forgotten.
    size_t forget(size_t mesh, const std::function<bool(const Vec3&, const Vec3&)>& which);
    // The faces change.triangles of mesh change.mesh of `before` moved
    // rigidly: in every mesh, each part (connected vertices) lying wholly on
    // those faces moves with them and is forgotten; a grid-cached object is
    // laid on its moved mesh again. Returns the vertices moved.
    size_t moveFaces(const Scene& before, const AppliedChange& change);
    // Lays mesh `mesh` anew on `scene`'s base mesh, unrefined and
    // unsampled, as the cache was made: a moved light's own mesh, whose
    // refinement followed shadows that are gone. Returns the vertices it had.
    size_t rebuildMesh(size_t mesh, const Scene& scene);
    // The same, keeping the samples of base vertices that still have them:
    // after a moved object, the mesh's refinement away from the base costs
    // more to sample again where it was forgotten than to refine anew
    // (bench dynamic). Returns the vertices that kept their samples.
    size_t rebuildKeepingBase(size_t mesh, const Scene& scene);
    // Follows the changed scene: its surfaces (which border vertices are
    // sampled inside their faces, EdgeOnSurfaces) and the fingerprint a
    // saved cache records.
    void sceneChanged(const Scene& after);

    // Bytes held by the meshes and their properties.
    size_t memoryBytes() const;
    // Approximate bytes per cached vertex (mesh connectivity and samples).
    static size_t bytesPerVertex();

    // Writes the whole cache to `path` (temporary file, then rename).
    void save(const std::string& path) const;
    // Replaces this cache's state with the one saved in `path`. The file must
    // have been saved for the same scene and settings: a truncated, corrupt
    // or mismatched file is refused with an InputError saying why, and this
    // cache is left unchanged.
    void load(const std::string& path);

private:
    // copyMesh with the cache's noise model, made once for all the copies
    // of copyMeshes (with many lights it passes over the shared mesh).
    IrradianceMeshCopy copyMesh(size_t mesh, const detail::NoiseModel& noise) const;

    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Adds `passes` estimates at every vertex of every mesh. Seeds come
// from (seed, light, vertex, pass), so a run repeats bit for bit. The
// callback, if any, gets (vertices done, vertices in all) now and then.
// Errors are rethrown with the light, vertex and pass where they happened.
void sampleEveryVertex(IrradianceCache& cache, VertexSampler& sampler, int passes, uint32_t seed,
                       const std::function<void(size_t, size_t)>& progress = {});

}  // namespace ml
