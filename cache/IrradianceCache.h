// The multi-mesh irradiance cache (§3.2): one mesh per light for its direct
// irradiance, laid over every object of the scene, with samples stored at
// the mesh vertices and Gouraud-interpolated in between when drawn.
//
// This is cache v0: the meshes are the objects' triangles split by
// longest-edge bisection down to a maximum edge length, sampled uniformly.
// Adaptive refinement, the indirect mesh and grid caches build on it.
// OpenMesh stays inside cache/: the public types are Meshlight's own.
#pragma once

#include "core/Scene.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace ml {

struct CacheSettings {
    // Cache triangles are bisected until no edge is longer than this
    // fraction of the scene's bounding diagonal, typical 1/32..1/128. The
    // geometry drawn in the image is never changed.
    double maxEdgeFraction = 1.0 / 64.0;
    void validate() const;
};

// An immutable copy of one cache mesh, for drawing and for tests.
struct IrradianceMeshView {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;             // unit, the side that was sampled
    std::vector<glm::uvec3> triangles;
    std::vector<Rgb> irradiance;           // W·m⁻², mean of the samples
    std::vector<uint32_t> samples;         // samples averaged at each vertex
};

class IrradianceCache {
public:
    IrradianceCache(const Scene& scene, const CacheSettings& settings = {});
    ~IrradianceCache();
    IrradianceCache(const IrradianceCache&) = delete;
    IrradianceCache& operator=(const IrradianceCache&) = delete;

    size_t lightCount() const;
    size_t vertexCount(size_t light) const;
    size_t triangleCount(size_t light) const;
    // The shading point of a vertex: where and facing where it is sampled.
    Vec3 position(size_t light, size_t vertex) const;
    Vec3 normal(size_t light, size_t vertex) const;

    // Adds one irradiance estimate at a vertex (running mean).
    void addSample(size_t light, size_t vertex, const Rgb& irradiance);
    IrradianceMeshView view(size_t light) const;

    // Bytes held by the meshes and their properties.
    size_t memoryBytes() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// An irradiance estimate of light `light` at x (unit normal n), drawing its
// randomness from `seed`: the GPU sampler, the exact reference, ...
using DirectEstimateFn = std::function<Rgb(size_t light, const Vec3& x, const Vec3& n, uint32_t seed)>;

// Adds `passes` estimates at every vertex of every light's mesh. Seeds come
// from (seed, light, vertex, pass), so a run repeats bit for bit. The
// callback, if any, gets (vertices done, vertices in all) now and then.
// Errors are rethrown with the light, vertex and pass where they happened.
void sampleEveryVertex(IrradianceCache& cache, const DirectEstimateFn& estimate, int passes, uint32_t seed,
                       const std::function<void(size_t, size_t)>& progress = {});

}  // namespace ml
