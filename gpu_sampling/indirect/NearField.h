// The near field of a fish-eye gather over voxels (§5.3): the eye, and the
// proxy's triangles in the voxels around the shading point (which voxels
// represent too coarsely), sent to the GPU to be intersected per pixel. The
// rules are SliceGather's (its near box, eye lift and nudge, and selection),
// so a gather that uses this (VoxelMarchGather) differs from the slice
// gather only in how it walks the voxels.
#pragma once

#include "RadianceProxy.h"

#include <glm/glm.hpp>

#include <array>
#include <vector>

namespace ml {

// std430 layout of common_near_field.glsl's NearTriangle.
struct NearTriangleGpu {
    glm::vec4 p[3];  // corners relative to the grid's origin; p[0].w: 1 if the triangle is closed
    glm::vec4 l[3];  // exitant radiance at the corners (W·sr⁻¹·m⁻²)
};

class NearField {
public:
    explicit NearField(const RadianceProxy& proxy);

    struct Gather {
        Vec3 eye{0.0};                          // world units
        std::array<int, 3> cellLo{}, cellHi{};  // the near box in voxels (inclusive; may leave the grid)
        Vec3 lo{0.0}, hi{0.0};                  // the same relative to the grid's origin
    };
    // For a gather at x with unit normal n: the near box (the voxel holding
    // x and `nearVoxels` more each way), the eye (lifted off the surface by
    // 1e-6 of the grid's diagonal and, at a point on an edge or in a corner,
    // moved 1e-4 of a voxel into its own surface, so that rays grazing past
    // it do not slip behind the surfaces meeting there), and into `out` the
    // proxy triangles touching the box that the eye may see (not wholly
    // below the tangent plane, not an open surface's copy facing away).
    // `radiance`: one per proxy position.
    Gather collect(const std::vector<Rgb>& radiance, const Vec3& x, const Vec3& n, int nearVoxels,
                   std::vector<NearTriangleGpu>& out);
    // The eye alone (lifted and nudged as above), for gathers without a near field.
    Vec3 eye(const Vec3& x, const Vec3& n);

private:
    // Every proxy triangle binned in the voxels within k of x's, once, into candidates_.
    void gatherCandidates(const Vec3& x, int k);
    // The eye from candidates_ (see collect).
    Vec3 eyeFromCandidates(const Vec3& x, const Vec3& n) const;

    const RadianceProxy& proxy_;
    std::vector<uint32_t> stamp_;  // per triangle: the generation that took it
    std::vector<uint32_t> candidates_;
    uint32_t generation_ = 0;
};

}  // namespace ml
