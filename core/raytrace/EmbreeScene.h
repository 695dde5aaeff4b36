// Ray queries on a Scene: an Embree 3 BVH over every triangle, closest hits
// and occlusion tests, for the reference path tracer and the ray-traced
// direct-light sampler. Embree stays inside EmbreeScene.cpp; this header
// speaks Meshlight types only.
//
// Precision. Embree traverses in float. Every position is first made
// relative to the centre of the scene's bounds (as the GPU buffers are), so a
// scene far from the world origin keeps its digits; hit points are then
// recomputed in double from the hit triangle's double corners and Embree's
// barycentrics, so they lie on the triangle's plane to double precision.
// What is left is the float traversal's own error, a few float ulps of the
// coordinates (at most ~1e-7 of the scene's size after centring). A ray that
// leaves a surface therefore starts from a point lifted off it by
// rayOffset(p) along the geometric normal (spawnPoint), see below.
//
// Cut-outs. Where a material's cut-out removes the surface (glTF alphaMode
// MASK, MTL map_d: Material::cutAway at the hit's texture coordinate), every
// query passes through: closest hits and occlusion alike, so the path
// tracer, the ray-traced samplers, punctual shadows and the ray gather all
// see the holes. The test runs in Embree's filter, per candidate hit, on
// meshes with such a material only.
#pragma once

#include "core/Scene.h"

#include <cstdint>
#include <memory>

namespace ml {

// A closest hit. Barycentrics follow Embree's convention:
// p = (1 − b1 − b2)·p0 + b1·p1 + b2·p2 for the triangle's corners p0, p1, p2.
struct RayHit {
    uint32_t mesh = 0;      // index into Scene::meshes
    uint32_t triangle = 0;  // index into that mesh's triangles
    double t = 0;           // ray parameter of the hit (units of the ray's direction)
    double b1 = 0, b2 = 0;  // barycentrics of corners 1 and 2
};

// Which triangles a query may hit (light indices are Scene::lights indices).
struct RayFilter {
    int skipLight = -1;     // >= 0: the triangles of this light are transparent
    int onlyLight = -1;     // >= 0: only the triangles of this light can be hit
    bool frontOnly = false; // only faces whose front (CCW) side faces the ray's origin
    bool any() const { return skipLight >= 0 || onlyLight >= 0 || frontOnly; }
};

// The geometry of a hit, in double.
struct SurfacePoint {
    Vec3 position{0.0};
    Vec3 geometricNormal{0.0};  // unit, front (CCW) side
    Vec3 shadingNormal{0.0};    // unit, interpolated from Mesh::normals (geometric when a mesh has none)
    uint32_t material = 0;      // index into Scene::materials
    Vec2 texcoord{0.0};         // interpolated from Mesh::texcoords
    bool hasTexcoord = false;   // false when the mesh has none

    // The diffuse reflectance here: the material's Kd texture at the hit's
    // uv (clamped to [0, 1]), else its Kd.
    Rgb kd(const Scene& scene) const {
        const Material& m = scene.materials[material];
        return m.kdMap && hasTexcoord ? glm::clamp(m.kdMap.value(texcoord), Rgb(0.0), Rgb(1.0)) : m.kd;
    }
    // The radiance emitted here (front side): the material's Ke texture at
    // the hit's uv, else its Ke (EmitterTexture.h: what a light sampler
    // weighs its points by).
    Rgb ke(const Scene& scene) const {
        const Material& m = scene.materials[material];
        return m.keMap && hasTexcoord ? m.keMap.value(texcoord) : m.ke;
    }
};

class EmbreeScene {
public:
    // Builds the BVH (Embree's high-quality builder, robust traversal).
    // `scene` must be finalized and outlive this object. Throws
    // std::runtime_error if Embree cannot create its device or build.
    explicit EmbreeScene(const Scene& scene);
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    const Scene& scene() const;

    // The closest hit of origin + t·direction, t in (tNear, tFar); false when
    // nothing is hit. `direction` need not be unit (t is in its units). Of
    // faces back to back there (within rayOffset), the one facing the ray.
    // Thread-safe: any number of threads may query at once.
    bool intersect(const Vec3& origin, const Vec3& direction, double tNear, double tFar, RayHit& hit,
                   const RayFilter& filter = {}) const;
    // Whether anything lies on origin + t·direction for t in (tNear, tFar).
    bool occluded(const Vec3& origin, const Vec3& direction, double tNear, double tFar,
                  const RayFilter& filter = {}) const;

    // The hit's position (from its barycentrics, in double), normals and material.
    SurfacePoint surface(const RayHit& hit) const;
    // The area light a triangle emits as (index into Scene::lights), or -1.
    int lightOf(uint32_t mesh, uint32_t triangle) const;

    // How far a secondary ray's origin is lifted off the surface at p:
    //   kSceneOffset × the scene's bounding diagonal
    //   + kMagnitudeOffset × max |coordinate of p relative to the scene's centre|.
    // The first term is 1e-6 of the scene (as the raster sampler's eye lift,
    // DirectSamplerSettings::eyeOffset): ~30× the float rounding of a
    // centred vertex, whatever the scene's unit (1e-3 to 1e5 alike). The
    // second, 64 float ulps of p, covers points far outside the scene's
    // bounds (a probe point, a distant camera), where rounding grows with
    // the magnitude.
    double rayOffset(const Vec3& p) const;
    // p lifted by rayOffset(p) along ±n, to the side `towards` points to: the
    // origin of a ray leaving a surface at p with unit normal n.
    Vec3 spawnPoint(const Vec3& p, const Vec3& n, const Vec3& towards) const;

    static constexpr double kSceneOffset = 1e-6;
    static constexpr double kMagnitudeOffset = 64.0 / 16777216.0;  // 64 × 2⁻²⁴

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ml
