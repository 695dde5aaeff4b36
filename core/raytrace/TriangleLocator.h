// Point location on a triangle mesh: the triangle nearest a point among
// those facing a given side, within a tolerance, through an Embree BVH's
// point query (rtcPointQuery). A cache mesh read where a gather's ray lands
// (MeshIrradianceLookup) asks this for every ray and every mesh it sums: a
// bounce-1 gather in an office with 12 panels asks 5,200 times. A uniform
// grid of bins was measured at 2.9 ms a gather there (its bins hold
// hundreds of faces where shadows refined the mesh); the BVH visits only the
// few faces whose bounds the query's small sphere touches, whatever the
// mesh's density.
//
// Embree stays inside TriangleLocator.cpp. Its float coordinates are made
// relative to the mesh's centre, and its query sphere is widened by a float
// ulp margin; the distances that decide are computed in double from the
// mesh's own corners, so the result is the exact nearest face, as a linear
// scan would find it. Ties (a point on an edge two faces share) go to the
// higher triangle index, whatever order the BVH visits them in, so the
// result does not depend on how Embree built its tree.
#pragma once

#include "core/Math.h"

#include <memory>
#include <optional>
#include <vector>

namespace ml {

class TriangleLocator {
public:
    // `positions` and `triangles` must outlive the locator. Faces without
    // area are never found. Throws std::runtime_error if Embree fails.
    TriangleLocator(const std::vector<Vec3>& positions, const std::vector<glm::uvec3>& triangles, double tolerance);
    ~TriangleLocator();
    TriangleLocator(const TriangleLocator&) = delete;
    TriangleLocator& operator=(const TriangleLocator&) = delete;
    TriangleLocator(TriangleLocator&&) noexcept;
    TriangleLocator& operator=(TriangleLocator&&) noexcept;

    struct Location {
        uint32_t triangle = 0;
        Vec3 barycentric{0.0};  // of the triangle's corners, for its point closest to the query
    };
    // The face nearest to p whose unit normal makes at most 60° with unit n
    // (dot ≥ 0.5), if one lies within the tolerance.
    std::optional<Location> locate(const Vec3& p, const Vec3& n) const;

    size_t memoryBytes() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The point of triangle (a, b, c) closest to p, as barycentrics.
Vec3 closestBarycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace ml
