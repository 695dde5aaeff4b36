#include "NearField.h"

#include <algorithm>

namespace ml {

NearField::NearField(const RadianceProxy& proxy) : proxy_(proxy), stamp_(proxy.triangles().size(), 0) {}

void NearField::gatherCandidates(const Vec3& x, int k) {
    const VoxelGrid& grid = proxy_.grid();
    const std::array<int, 3> cell = grid.cell(x);
    if (++generation_ == 0) std::fill(stamp_.begin(), stamp_.end(), 0), generation_ = 1;
    candidates_.clear();
    for (int z = std::max(cell[2] - k, 0); z <= std::min(cell[2] + k, grid.dims[2] - 1); ++z)
        for (int y = std::max(cell[1] - k, 0); y <= std::min(cell[1] + k, grid.dims[1] - 1); ++y)
            for (int xx = std::max(cell[0] - k, 0); xx <= std::min(cell[0] + k, grid.dims[0] - 1); ++xx)
                for (uint32_t t : proxy_.inVoxel(xx, y, z))
                    if (stamp_[t] != generation_) stamp_[t] = generation_, candidates_.push_back(t);
}

Vec3 NearField::eyeFromCandidates(const Vec3& x, const Vec3& n) const {
    const VoxelGrid& grid = proxy_.grid();
    const std::vector<Vec3>& positions = proxy_.positions();
    const double diagonal = glm::length(grid.upper() - grid.origin);
    const double lift = 1e-6 * diagonal, touch = 1e-4 * grid.voxel;
    Vec3 inward(0.0);
    bool edge = false;
    for (uint32_t t : candidates_) {
        const ProxyTriangle& pt = proxy_.triangles()[t];
        const double facing = glm::dot(pt.normal, n);
        if (facing < -0.5) continue;  // another surface's back, or the other side of this one
        const Vec3 &c0 = positions[pt.corners.x], &c1 = positions[pt.corners.y], &c2 = positions[pt.corners.z];
        const Vec3 w = closestBarycentric(x, c0, c1, c2);
        if (glm::length(w.x * c0 + w.y * c1 + w.z * c2 - x) > touch) continue;
        if (facing > 0.999)
            inward += (c0 + c1 + c2) / 3.0 - x;  // its own surface
        else
            edge = true;
    }
    inward -= glm::dot(inward, n) * n;
    Vec3 eye = x + lift * n;
    if (edge && glm::length(inward) > 0) eye += touch * glm::normalize(inward);
    return eye;
}

Vec3 NearField::eye(const Vec3& x, const Vec3& n) {
    gatherCandidates(x, 1);
    return eyeFromCandidates(x, n);
}

NearField::Gather NearField::collect(const std::vector<Rgb>& radiance, const Vec3& x, const Vec3& n, int nearVoxels,
                                     std::vector<NearTriangleGpu>& out) {
    out.clear();
    const VoxelGrid& grid = proxy_.grid();
    const std::vector<Vec3>& positions = proxy_.positions();
    const std::array<int, 3> cell = grid.cell(x);
    const int k = nearVoxels;
    Gather g;
    for (int a = 0; a < 3; ++a) {
        g.cellLo[size_t(a)] = cell[size_t(a)] - k;
        g.cellHi[size_t(a)] = cell[size_t(a)] + k;
        g.lo[a] = (cell[size_t(a)] - k) * grid.voxel;
        g.hi[a] = (cell[size_t(a)] + k + 1) * grid.voxel;
    }
    gatherCandidates(x, k);
    g.eye = eyeFromCandidates(x, n);
    const double lift = 1e-6 * glm::length(grid.upper() - grid.origin);
    for (uint32_t t : candidates_) {
        const ProxyTriangle& pt = proxy_.triangles()[t];
        const Vec3 &c0 = positions[pt.corners.x], &c1 = positions[pt.corners.y], &c2 = positions[pt.corners.z];
        if (glm::dot(c0 - x, n) <= lift && glm::dot(c1 - x, n) <= lift && glm::dot(c2 - x, n) <= lift) continue;
        if (!pt.closed && glm::dot(pt.normal, g.eye - c0) <= 0) continue;
        NearTriangleGpu nt;
        for (int c = 0; c < 3; ++c) {
            nt.p[c] = glm::vec4(glm::vec3(positions[pt.corners[c]] - grid.origin), 0.f);
            nt.l[c] = glm::vec4(glm::vec3(radiance[pt.corners[c]]), 0.f);
        }
        nt.p[0].w = pt.closed ? 1.f : 0.f;
        out.push_back(nt);
    }
    return g;
}

}  // namespace ml
