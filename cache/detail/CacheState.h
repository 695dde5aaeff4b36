// The state behind IrradianceCache, shared by its translation units
// (construction and views, refinement, the cache file). cache/ only.
#pragma once

#include "CacheMesh.h"
#include "cache/EdgeOnSurfaces.h"
#include "cache/GridCache.h"
#include "cache/IrradianceCache.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <cstdint>
#include <vector>

namespace ml::detail {

// The running sums of one vertex's samples, each weighed by its work w
// (VertexSample::work; 1 for samplers whose estimates all cost the same,
// where these are the plain sums). A sample's variance is σ²/w, σ² that of
// a sample of unit work; the mean weighed by w has the least variance,
// σ²/Σw, and Σ w (y − ȳ)² / (n − 1) estimates σ².
struct VertexStats {
    Rgb sum{0.0};          // Σ w·irradiance
    double sumLum = 0;     // Σ w·luminance
    double sumLumSq = 0;   // Σ w·luminance², for the standard error of the mean
    double sumVisibility = 0;
    uint32_t count = 0;
    uint32_t partial = 0;  // samples that saw the light partly occluded
    double sumInverseReach = 0;  // Σ 1/reach (0 for a sample that knows none)
    double work = 0;       // Σ w
    // Σ w·v over the samples that measured their own variance v
    // (VertexSample::ownVariance), and how many did.
    double sumOwnVariance = 0;
    uint32_t ownCount = 0;

    Rgb mean() const { return count ? sum / work : Rgb(0.0); }
    double meanLuminance() const { return count ? sumLum / work : 0.0; }
    // Σ w (y − ȳ)²: n − 1 times the estimate of σ², a unit of work's
    // variance (0 below two samples).
    double spread() const { return count >= 2 ? std::max(0.0, sumLumSq - sumLum * meanLuminance()) : 0.0; }
    // The variance of the mean, σ²/Σw, from two samples on.
    double meanVariance() const { return count >= 2 ? spread() / double(count - 1) / work : 0.0; }
    double meanVisibility() const { return count ? sumVisibility / count : 1.0; }
    // The harmonic mean of the samples' reach (VertexSample::reach): of
    // every ray they traced, as each sample's is of its rays'. Infinity
    // where none knew it.
    double reach() const {
        return sumInverseReach > 0 ? count / sumInverseReach : std::numeric_limits<double>::infinity();
    }
    // A unit of work's variance as the samples' own parts scatter (w·v,
    // averaged), where every sample measured it; < 0 otherwise.
    double ownUnitVariance() const { return count && ownCount == count ? sumOwnVariance / count : -1.0; }
    void add(const VertexSample& s) {
        const double y = luminance(s.irradiance), w = s.work;
        sum += w * s.irradiance;
        sumLum += w * y;
        sumLumSq += w * y * y;
        work += w;
        sumVisibility += s.visibility;
        count += 1;
        partial += s.partial ? 1 : 0;
        if (s.reach > 0 && s.reach < std::numeric_limits<double>::infinity()) sumInverseReach += 1 / s.reach;
        if (s.ownVariance >= 0 && std::isfinite(s.ownVariance)) sumOwnVariance += w * s.ownVariance, ownCount += 1;
    }
};

struct LightMesh {
    CacheTriMesh mesh;
    std::vector<VertexStats> stats;      // by vertex index
    // What a copy shows at a vertex without a sample yet, after
    // resetSamples(): its mean before (red < 0 or past the end: none,
    // its sampled neighbours fill in).
    std::vector<Rgb> provisional;
    std::vector<VertexStats> gridStats;  // by grid sample, every grid object's in turn
    // The first pass asked the sampler for this vertex's (grid sample's)
    // estimate without the GPU, and it needs the GPU (past the end: not
    // asked yet). Not saved: a loaded cache asks again.
    std::vector<char> needsGpu, gridNeedsGpu;
};

// An object too finely tessellated for a cache mesh: its irradiance is
// sampled on a grid (GridCache) and interpolated to its own vertices.
struct GridObject {
    uint32_t mesh = 0;                    // index into Scene::meshes
    std::vector<Vec3> positions, normals;
    std::vector<glm::uvec3> triangles;
    std::shared_ptr<const GridCache> grid;
    uint32_t firstSample = 0;             // into LightMesh::gridStats
    double area = 0;
};

// Grid samples are seeded as vertices numbered from here, apart from any
// cache mesh vertex.
constexpr uint32_t kGridSeedBase = 0x40000000u;

struct CacheState {
    CacheSettings settings;       // as made (the cache file's fingerprint); refinement uses effective()
    // Progressive refinement: each level halves the tolerances and doubles
    // the samples a vertex may take
    // (IrradianceCache::tighten). Saved in the cache file.
    int level = 0;
    double diagonal = 1;          // of the scene's bounds
    // The scene's faces, for border vertices in them (EdgeOnSurfaces::forScene,
    // shared with the scene's other caches; not saved).
    std::shared_ptr<const EdgeOnSurfaces> edgeOn;
    bool insetBorders = false;        // CacheLayout::insetBorders
    double borderInset = CacheLayout::kDefaultInset;  // CacheLayout::borderInset
    uint64_t sceneFingerprint = 0;
    // Which lights are gathered rather than cached (LightCoverage::gathered),
    // folded into the settings' fingerprint in the file: a cache made with
    // other gathered lights has other meshes, and is refused like one made
    // with other settings. 0 when none.
    uint64_t gatheredSalt = 0;
    std::vector<LightMesh> meshes;  // one per light, in the scene's order (then the shared mesh)
    bool sharedMesh = false;        // the last mesh holds the light the lights share
    std::vector<GridObject> grids;  // the same for every light
    size_t gridSamples = 0;         // over all grid objects
    uint64_t rounds = 0;
    uint64_t samples = 0;
    size_t detachedFaces = 0;     // non-manifold input faces given vertices of their own
    size_t backFaces = 0;         // reversed copies of faces lit from behind
    // The most work a sample took (VertexSample::work): a full estimate's,
    // which CacheSettings::sampleNoise and its measure speak of. Found
    // again from the sums when loaded.
    double fullWork = 0;
    // IrradianceCache::setNoiseProbes (not saved: a run's choice).
    size_t noiseProbeEvery = 0;
};

// What the cache's resampled vertices measure of its samples' noise,
// once they have kMeasuredNoiseFreedom degrees of freedom between them:
// - relative: the relative error of one full sample
//   (CacheSettings::sampleNoise), their spreads pooled; 0 before;
// - ownScale: their spreads over what their samples' own scatter said
//   (VertexStats::ownUnitVariance), pooled the same way, where every
//   sample measured its own: how much the samplers' stratification makes
//   their true noise smaller than their rays' scatter says; < 0 before.
constexpr double kMeasuredNoiseFreedom = 64;
struct MeasuredNoise {
    double relative = 0;
    double ownScale = -1;
};
MeasuredNoise measureNoise(const CacheState& s);

// How noisy a vertex's (grid sample's) mean is taken to be
// (detail::meanNoise): the settings at the cache's level, and what the
// cache measured.
struct NoiseModel {
    double singleSampleNoise = 0;  // CacheSettings::singleSampleNoise
    double sampleNoise = 0;        // effectiveSettings(s).sampleNoise
    double fullWork = 0;           // CacheState::fullWork
    // The factor that makes a unit of work's own variance its true one:
    // MeasuredNoise::ownScale once measured; until then the one that makes
    // the own variances' mean relative noise sampleNoise (the assumed
    // level, spread over the vertices by what each sample saw). For exact
    // samplers (CacheSettings::sampleNoise 0) only the mesh many lights
    // share measures its own (its draws among the lights), and until
    // measured the scale is 1. < 0 where no sample measured a variance
    // above 0.
    double ownScale = -1;
};
NoiseModel noiseModel(const CacheState& s);
// A measured own variance counts as this many degrees of freedom beside a
// vertex's own spread (its n − 1): two samples that agreed by chance do
// not make a vertex whose rays scattered widely count as exact.
constexpr double kOwnVarianceFreedom = 2;

// The settings at the cache's level: CacheState::level halvings of the
// split and noise tolerances, and as many doublings of the samples per
// vertex (at most 4096). A sampler whose every sample is noisy
// (sampleNoise > 0) has its assumed noise replaced by the measured one.
CacheSettings effectiveSettings(const CacheState& s);

// A hash of everything in the scene that the cache depends on: geometry,
// normals, materials and lights. A cache file records it.
uint64_t sceneFingerprint(const Scene& scene);
// The same for the settings that shape the meshes and their refinement.
uint64_t settingsFingerprint(const CacheSettings& settings);

}  // namespace ml::detail
