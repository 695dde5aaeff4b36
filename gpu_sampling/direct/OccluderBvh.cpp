#include "OccluderBvh.h"

#include <algorithm>
#include <numeric>

namespace ml {

OccluderBvh::OccluderBvh(const std::vector<Triangle3>& triangles, int leafSize) {
    std::vector<Bounds3> bounds(triangles.size());
    std::vector<Vec3> centroids(triangles.size());
    for (size_t i = 0; i < triangles.size(); ++i) {
        for (const Vec3& p : triangles[i]) bounds[i].extend(p);
        centroids[i] = bounds[i].center();
    }
    order_.resize(triangles.size());
    std::iota(order_.begin(), order_.end(), 0u);
    if (!triangles.empty()) build(bounds, centroids, 0, uint32_t(triangles.size()), std::max(leafSize, 1));
}

int32_t OccluderBvh::build(std::vector<Bounds3>& triBounds, std::vector<Vec3>& centroids, uint32_t first,
                           uint32_t count, int leafSize) {
    const int32_t index = int32_t(nodes_.size());
    nodes_.push_back({});
    Bounds3 b, cb;
    for (uint32_t i = first; i < first + count; ++i) {
        b.extend(triBounds[order_[i]]);
        cb.extend(centroids[order_[i]]);
    }
    nodes_[index].bounds = b;
    nodes_[index].first = first;
    nodes_[index].count = count;
    if (count <= uint32_t(leafSize)) return index;

    // Median split on the longest axis of the centroids' box: balanced and
    // good enough for frustum culling (no ray traversal cost to optimise).
    const Vec3 e = cb.extent();
    const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
    const uint32_t mid = first + count / 2;
    std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count,
                     [&](uint32_t a, uint32_t c) { return centroids[a][axis] < centroids[c][axis]; });
    const int32_t l = build(triBounds, centroids, first, mid - first, leafSize);
    const int32_t r = build(triBounds, centroids, mid, first + count - mid, leafSize);
    nodes_[index].left = l;
    nodes_[index].right = r;
    return index;
}

uint32_t OccluderBvh::cull(const std::vector<Plane>& planes, std::vector<Range>& out) const {
    out.clear();
    uint32_t total = 0;
    if (!nodes_.empty()) cullNode(0, planes, out, total);
    return total;
}

void OccluderBvh::cullNode(int32_t index, const std::vector<Plane>& planes, std::vector<Range>& out,
                           uint32_t& total) const {
    const Node& node = nodes_[size_t(index)];
    bool inside = true;
    for (const Plane& p : planes) {
        // The box corner furthest along n decides whether any of it is inside;
        // the nearest one whether all of it is.
        const Vec3 far(p.n.x >= 0 ? node.bounds.hi.x : node.bounds.lo.x,
                       p.n.y >= 0 ? node.bounds.hi.y : node.bounds.lo.y,
                       p.n.z >= 0 ? node.bounds.hi.z : node.bounds.lo.z);
        if (glm::dot(p.n, far) + p.d < 0) return;
        const Vec3 near(p.n.x >= 0 ? node.bounds.lo.x : node.bounds.hi.x,
                        p.n.y >= 0 ? node.bounds.lo.y : node.bounds.hi.y,
                        p.n.z >= 0 ? node.bounds.lo.z : node.bounds.hi.z);
        if (glm::dot(p.n, near) + p.d < 0) inside = false;
    }
    if (inside || node.left < 0) {
        if (!out.empty() && out.back().first + out.back().count == node.first)
            out.back().count += node.count;
        else
            out.push_back({node.first, node.count});
        total += node.count;
        return;
    }
    cullNode(node.left, planes, out, total);
    cullNode(node.right, planes, out, total);
}

}  // namespace ml
