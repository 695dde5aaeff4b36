// IrradianceCache's private half and the helpers its translation units share.
#pragma once

#include "CacheState.h"

#include <functional>

namespace ml {

struct IrradianceCache::Impl {
    detail::CacheState state;
};

namespace detail {

double edgeLength(const CacheTriMesh& mesh, CacheTriMesh::VertexHandle a, CacheTriMesh::VertexHandle b);
// Splits `e` (and both faces beside it) at its midpoint; the new vertex's
// normal is the normalised mean of the ends'. Returns the new vertex.
CacheTriMesh::VertexHandle splitAtMidpoint(CacheTriMesh& mesh, CacheTriMesh::EdgeHandle e);
// Where vertex vh is sampled: the vertex itself, or, on an object's border
// that an emitter's plane passes through, a hair inside its own faces (see
// IrradianceCache.cpp).
Vec3 samplePoint(const CacheState& s, const CacheTriMesh& mesh, CacheTriMesh::VertexHandle vh);
// One estimate at vertex v of light `light`'s mesh, seeded from (seed, v,
// light, samples so far); errors carry the light, vertex and point.
VertexSample sampleVertex(VertexSampler& sampler, const CacheState& s, size_t light, size_t v, uint32_t seed);
// The same at grid sample g (over all grid objects).
VertexSample sampleGrid(VertexSampler& sampler, const CacheState& s, size_t light, size_t g, uint32_t seed);
const GridObject& gridOf(const CacheState& s, size_t g);  // the object grid sample g belongs to
void addVertexSample(CacheState& s, size_t light, size_t v, const VertexSample& sample);
void addGridSample(CacheState& s, size_t light, size_t g, const VertexSample& sample);
// Vertices and grid samples without a sample yet, over all lights.
size_t unsampledCount(const CacheState& s);
// Samples up to `budget` of them, in (light, vertex, then grid sample)
// order; `each`, if given, after each. Returns how many.
size_t sampleUnsampled(CacheState& s, VertexSampler& sampler, uint32_t seed, size_t budget,
                       const std::function<void()>& each = {});

}  // namespace detail
}  // namespace ml
