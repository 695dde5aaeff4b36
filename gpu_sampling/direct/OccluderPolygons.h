// Pairs in umbra answered without rasterising: the light wholly hidden
// behind one convex occluder polygon.
//
// In a furnished room most (receiver, light) pairs with an occluder in their
// frustum see none of the light: the floor under a desk, a cabinet's side
// facing away from the panel beside it. In the office of `bench lights` 82%
// of the rasterised pairs had not one visible sample. Each of them costs a
// sampling image (~0.5 ms on llvmpipe) to learn that the answer is zero.
//
// Here every occluder triangle is a convex polygon: the triangle itself or,
// where it and a neighbour across an edge lie in one plane and together
// make a convex quadrilateral (a box's face, a desk's top), that quad. The
// light is hidden when, for one such polygon, every corner of every visible
// piece of the light (the pieces above the receiver's horizon, convex) is
// seen from the eye through the polygon's interior: the pieces' central
// projections onto the polygon's plane are convex, so they then lie inside
// the convex polygon, and every ray from the eye to the light meets it.
// What the sampler would do with such a pair, sample by sample, is then
// certain: every sample occluded, irradiance exactly zero. The test is
// conservative (margins below), never the other way: a pair it cannot
// decide is rasterised as before.
#pragma once

#include "LightFrustum.h"  // Polygon3
#include "OccluderBvh.h"
#include "core/Math.h"
#include "core/Scene.h"

#include <cstdint>
#include <vector>

namespace ml {

class OccluderPolygons {
public:
    // `triangles` in the BVH's leaf order, `lightId[i]` 1 + the light
    // triangle i belongs to (0: none), as the sampler keeps them, or kHoled.
    OccluderPolygons(const std::vector<Triangle3>& triangles, const std::vector<uint32_t>& lightId);

    // What the sampler ignores of an occluder, in world units: nothing
    // nearer the eye than `nearDistance`, nothing within `planeTolerance`
    // of a planar light's plane (`lightNormal`, `lightPoint`: its emitting
    // side faces the eye).
    struct Rules {
        Vec3 eye{0.0};
        double nearDistance = 0;
        Vec3 lightNormal{0.0}, lightPoint{0.0};
        double planeTolerance = 0;
        uint32_t skipLightId = 0;  // 1 + the sampled light: its own triangles do not occlude it
    };

    // The lightId of a face with a cut-out (Material::alphaMap): it may have
    // holes anywhere, so it hides nothing here (nor joins a quad with a
    // face that does).
    static constexpr uint32_t kHoled = 0xffffffffu;

    // True when one polygon of a triangle in `ranges` hides every piece.
    bool hideAll(const std::vector<Polygon3>& pieces, const std::vector<OccluderBvh::Range>& ranges,
                 const Rules& rules) const;

    // Triangles that joined a neighbour into a convex quad (for tests and the plan).
    size_t quadCount() const;

private:
    bool hides(const Vec3* corners, int count, const std::vector<Polygon3>& pieces, const Rules& rules) const;

    std::vector<Triangle3> triangles_;
    std::vector<uint32_t> lightId_;
    // Per triangle, its quad's fourth corner (the neighbour's far corner),
    // inserted after corner `quadAfter` (-1: no quad).
    std::vector<Vec3> quadCorner_;
    std::vector<int8_t> quadAfter_;
};

}  // namespace ml
