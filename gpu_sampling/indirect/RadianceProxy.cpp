#include "RadianceProxy.h"

#include "core/Error.h"
#include "core/MeshUtil.h"

#include <algorithm>
#include <cmath>

namespace ml {

MeshIrradianceLookup::MeshIrradianceLookup(const IrradianceMeshCopy& mesh, double tolerance)
    : mesh_(mesh), locator_(mesh.positions, mesh.triangles, tolerance) {}

Rgb MeshIrradianceLookup::at(const Vec3& p, const Vec3& n) const {
    const std::optional<TriangleLocator::Location> l = locator_.locate(p, n);
    if (!l) return Rgb(0.0);
    const glm::uvec3 i = mesh_.triangles[l->triangle];
    const Vec3& w = l->barycentric;
    return w.x * mesh_.irradiance[i.x] + w.y * mesh_.irradiance[i.y] + w.z * mesh_.irradiance[i.z];
}

RadianceProxy::RadianceProxy(const Scene& scene, const VoxelGrid& grid) : grid_(grid) {
    diagonal_ = scene.bounds.diagonal() > 0 ? scene.bounds.diagonal() : 1.0;
    // Uniform subdivision of each triangle into k² pieces, k from its longest
    // edge; a piece is at most about two voxels across: radiance is
    // interpolated linearly between its corners, and slices are filled at
    // twice the voxels' resolution.
    constexpr int kMaxSplit = 256;
    for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
        const Mesh& m = scene.meshes[mi];
        const bool closed = isClosedMesh(m);
        for (size_t t = 0; t < m.triangles.size(); ++t) {
            const Triangle3 p = m.triangle(t);
            const Vec3 an = m.areaNormal(t);
            if (!(glm::length(an) > 0)) continue;
            const Vec3 n = glm::normalize(an);
            const double longest = std::max({glm::length(p[1] - p[0]), glm::length(p[2] - p[1]), glm::length(p[0] - p[2])});
            const int k = std::clamp(int(std::ceil(longest / (2 * grid_.voxel))), 1, kMaxSplit);
            // The triangle's mean over its texture footprint (Mesh::albedo),
            // or its material's Kd: each piece reflects with it.
            const Rgb kd = scene.albedo(mi, t);
            // The sides to make: the front always, the back for open objects.
            for (int side = 0; side < (closed ? 1 : 2); ++side) {
                const uint32_t base = uint32_t(positions_.size());
                auto index = [&](int i, int j) { return base + uint32_t(i * (2 * k + 3 - i) / 2 + j); };
                for (int i = 0; i <= k; ++i)
                    for (int j = 0; j <= k - i; ++j) {
                        const double u = double(i) / k, v = double(j) / k;
                        positions_.push_back(p[0] + u * (p[1] - p[0]) + v * (p[2] - p[0]));
                        vertexTriangle_.push_back(uint32_t(triangles_.size()));
                    }
                auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
                    ProxyTriangle pt;
                    pt.corners = side == 0 ? glm::uvec3(a, b, c) : glm::uvec3(a, c, b);
                    pt.normal = side == 0 ? n : -n;
                    pt.kd = kd;
                    pt.closed = closed;
                    triangles_.push_back(pt);
                };
                for (int i = 0; i < k; ++i)
                    for (int j = 0; j < k - i; ++j) {
                        add(index(i, j), index(i + 1, j), index(i, j + 1));
                        if (j + 1 < k - i) add(index(i + 1, j), index(i + 1, j + 1), index(i, j + 1));
                    }
            }
        }
    }
    // Bin by voxel: every voxel the triangle's bounding box touches.
    bins_.resize(grid_.count());
    for (size_t t = 0; t < triangles_.size(); ++t) {
        const glm::uvec3 c = triangles_[t].corners;
        Bounds3 b;
        b.extend(positions_[c.x]), b.extend(positions_[c.y]), b.extend(positions_[c.z]);
        const std::array<int, 3> lo = grid_.cell(b.lo), hi = grid_.cell(b.hi);
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x)
                    bins_[(size_t(z) * grid_.dims[1] + y) * grid_.dims[0] + x].push_back(uint32_t(t));
    }
}

std::vector<Rgb> RadianceProxy::radianceFrom(const std::vector<IrradianceMeshCopy>& meshes) const {
    std::vector<Rgb> radiance(positions_.size());
    const double tolerance = 1e-5 * diagonal_;
    std::vector<MeshIrradianceLookup> lookups;
    lookups.reserve(meshes.size());
    for (const IrradianceMeshCopy& m : meshes) lookups.emplace_back(m, tolerance);
    for (size_t v = 0; v < positions_.size(); ++v) {
        const ProxyTriangle& t = triangles_[vertexTriangle_[v]];
        Rgb e(0.0);
        for (const MeshIrradianceLookup& l : lookups) e += l.at(positions_[v], t.normal);
        radiance[v] = t.kd * e / kPi;
        ML_ASSERT(isFinite(radiance[v]), "non-finite radiance at proxy vertex ", v);
    }
    return radiance;
}

size_t RadianceProxy::memoryBytes() const {
    size_t n = triangles_.size() * sizeof(ProxyTriangle) + positions_.size() * (sizeof(Vec3) + 4);
    for (const auto& b : bins_) n += b.capacity() * sizeof(uint32_t) + sizeof(b);
    return n;
}

}  // namespace ml
