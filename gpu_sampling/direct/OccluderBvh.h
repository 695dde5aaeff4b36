// A bounding-volume hierarchy over the scene's triangles, used to draw only
// the potential occluders inside a sampling frustum.
//
// On llvmpipe the triangles drawn are the main cost of a sample, so culling
// is what matters; batching helps little. Triangles are stored in leaf order,
// so the survivors of a cull are a few contiguous ranges for one
// glMultiDrawArrays. (Written here rather than taken from CGAL's AABB tree or
// Embree: neither hands back leaf ranges of a reordered triangle array.)
#pragma once

#include "core/Math.h"
#include "core/Scene.h"

#include <cstdint>
#include <vector>

namespace ml {

class OccluderBvh {
public:
    // A half-space n·p + d >= 0.
    struct Plane {
        Vec3 n;
        double d;
    };
    // A run of triangles in leaf order: [first, first + count).
    struct Range {
        uint32_t first;
        uint32_t count;
    };

    // `leafSize`: triangles per leaf, typical 8..32 (smaller culls tighter
    // but makes more ranges).
    explicit OccluderBvh(const std::vector<Triangle3>& triangles, int leafSize = 16);

    // Original index of the triangle at each leaf-order position.
    const std::vector<uint32_t>& order() const { return order_; }
    size_t triangleCount() const { return order_.size(); }

    // Replaces `out` with the merged ranges of leaves that may intersect the
    // convex volume bounded by `planes`. Returns the number of triangles.
    uint32_t cull(const std::vector<Plane>& planes, std::vector<Range>& out) const;

private:
    struct Node {
        Bounds3 bounds;
        uint32_t first = 0;   // leaf-order range covered by this subtree
        uint32_t count = 0;
        int32_t left = -1;    // children; -1 for a leaf
        int32_t right = -1;
    };
    int32_t build(std::vector<Bounds3>& triBounds, std::vector<Vec3>& centroids, uint32_t first,
                  uint32_t count, int leafSize);
    void cullNode(int32_t node, const std::vector<Plane>& planes, std::vector<Range>& out,
                  uint32_t& total) const;

    std::vector<Node> nodes_;
    std::vector<uint32_t> order_;
};

}  // namespace ml
