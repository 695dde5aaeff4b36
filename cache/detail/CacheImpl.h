// IrradianceCache's private half and the helpers its translation units share.
#pragma once

#include "CacheState.h"

#include <functional>

namespace ml {

struct IrradianceCache::Impl {
    detail::CacheState state;
    CacheLayout layout;  // as made: rebuildMesh lays a mesh again the same way
    std::function<bool()> interrupt;  // setInterrupt's (not saved, not part of the state)
};

namespace detail {

double edgeLength(const CacheTriMesh& mesh, CacheTriMesh::VertexHandle a, CacheTriMesh::VertexHandle b);
// Splits `e` (and both faces beside it) at its midpoint; the new vertex's
// normal is the normalised mean of the ends'. Returns the new vertex.
CacheTriMesh::VertexHandle splitAtMidpoint(CacheTriMesh& mesh, CacheTriMesh::EdgeHandle e);
// Where vertex vh is sampled: the vertex itself, or, on an object's border
// in the plane of a surface meeting it there (EdgeOnSurfaces), a hair inside
// its own faces (see IrradianceCache.cpp).
Vec3 samplePoint(const CacheState& s, const CacheTriMesh& mesh, CacheTriMesh::VertexHandle vh);
// A sample to take: vertex `index` of mesh `mesh`, or grid sample `index`
// (over all grid objects) of that mesh.
struct PendingSample {
    uint32_t mesh = 0;
    uint32_t index = 0;
    bool grid = false;
};
// Takes them in one batch (VertexSampler::sampleBatch, which may spread it
// over threads), each seeded from (seed, vertex, mesh, samples so far), and
// adds them in order: the same cache whatever the threads. Errors carry the
// mesh, vertex and point. With `interrupt` (IrradianceCache::setInterrupt),
// in batches of about kInterruptBatchSeconds each, asking it before each
// and stopping when it says so. Returns how many were taken.
size_t takeSamples(CacheState& s, VertexSampler& sampler, uint32_t seed, const std::vector<PendingSample>& pending,
                   const std::function<bool()>& interrupt = {});
constexpr double kInterruptBatchSeconds = 0.05;
const GridObject& gridOf(const CacheState& s, size_t g);  // the object grid sample g belongs to
void addVertexSample(CacheState& s, size_t light, size_t v, const VertexSample& sample);
void addGridSample(CacheState& s, size_t light, size_t g, const VertexSample& sample);
// Vertices and grid samples without a sample yet, over all lights.
size_t unsampledCount(const CacheState& s);
// Samples up to `budget` of them, in an order that scatters them over the
// scene and takes every mesh's sample at a vertex together (a partial first
// pass then covers every object and every light evenly), and the noise
// probes among them (IrradianceCache::setNoiseProbes). Returns how many
// samples it took.
size_t sampleUnsampled(CacheState& s, VertexSampler& sampler, uint32_t seed, size_t budget,
                       const std::function<bool()>& interrupt = {});
// The standard error of a vertex's (or grid sample's) mean luminance, W·m⁻²:
// - where its samples measured their own variance (a ray gather's), `own`
//   (a unit of work's: VertexStats::ownUnitVariance, or ringOwnVariances')
//   scaled by NoiseModel::ownScale, pooled with the samples' spread from
//   two samples on (kOwnVarianceFreedom);
// - otherwise measured from two samples on; assumed from the settings for a
//   single sample that saw a penumbra or came from a sampler whose every
//   sample is noisy, NoiseModel::sampleNoise for a sample of its fullWork (a
//   cheaper one's is larger by √(fullWork / w)); 0 otherwise (the exact
//   sampler outside penumbrae).
double meanNoise(const VertexStats& st, const NoiseModel& noise, double own);
inline double meanNoise(const VertexStats& st, const NoiseModel& noise) {
    return meanNoise(st, noise, st.ownUnitVariance());
}
// Per vertex of `lm`, the own variance its noise is judged by (meanNoise):
// the larger of its samples' (VertexStats::ownUnitVariance) and that
// averaged with its neighbours'. A vertex's own says how far its one
// gather may be off, but also leans with it: a gather whose few rays found
// a bright patch reads both bright and scattered, one whose rays missed it
// dark and uniform, so resampling by its own variance alone takes the
// bright ones back down and leaves the dark ones (the back rooms at 20 s
// read 1.1% dark against 0.5%). Its ring's mean does not lean with its
// value, but alone it misses the outliers (cache/README.md). < 0 where the
// vertex's samples did not measure theirs.
std::vector<double> ringOwnVariances(const LightMesh& lm);
// The error each vertex of mesh `l` predicts for the irradiance shown
// around it, in luminance (W·m⁻²), as an RMS over its faces: its noise and
// the interpolation error of its edges (Refine.cpp), or a guess's
// (kGuessedLightError) where not sampled yet; `lum` the luminance
// the copy shows at each vertex (sampled, or filled from neighbours);
// `noise` the cache's noiseModel and `own` the mesh's ringOwnVariances, as
// the caller has them for its standard errors. `vertexNoise`, when given,
// receives the noise part of each (its mean's standard error; 0 for a
// guess).
std::vector<double> predictedErrors(const CacheState& s, size_t l, const std::vector<double>& lum,
                                    const NoiseModel& noise, const std::vector<double>& own,
                                    std::vector<double>* vertexNoise = nullptr);

}  // namespace detail
}  // namespace ml
