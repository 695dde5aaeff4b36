// The regular grid of cubic voxels the indirect gathers work on (§5.3):
// the scene's bounds padded by half a voxel on every side, so walls lying on
// the bounds sit in the middle of their slice rather than on a slice plane.
// The texels of slice faces, on the other hand, tile the bounds exactly
// (they start half a voxel in), so a wall that ends at the bounds covers its
// last texel whole: no ray slips out through a half-covered edge texel.
#pragma once

#include "core/Math.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace ml {

struct VoxelGrid {
    Vec3 origin{0.0};             // lower corner
    double voxel = 1;             // edge length (scene units)
    std::array<int, 3> dims{1, 1, 1};

    // `resolution` voxels along the longest side of `bounds`, cubes elsewhere.
    static VoxelGrid fit(const Bounds3& bounds, int resolution) {
        VoxelGrid g;
        const Vec3 e = bounds.extent();
        const double longest = std::max({e.x, e.y, e.z, 1e-300});
        g.voxel = longest / std::max(resolution - 1, 1);  // one voxel of padding in all
        g.origin = bounds.lo - 0.5 * g.voxel;
        for (int a = 0; a < 3; ++a) g.dims[size_t(a)] = std::max(1, int(std::ceil(e[a] / g.voxel + 1 - 1e-9)));
        return g;
    }
    double plane(int axis, int i) const { return origin[axis] + i * voxel; }  // slice i's lower face
    // Slice-face texels along `axis`: from texelOrigin(axis), voxel-sized.
    int texels(int axis) const { return std::max(1, dims[size_t(axis)] - 1); }
    double texelOrigin(int axis) const { return origin[axis] + 0.5 * voxel; }
    Vec3 upper() const { return origin + voxel * Vec3(dims[0], dims[1], dims[2]); }
    // The voxel holding p, clamped to the grid.
    std::array<int, 3> cell(const Vec3& p) const {
        std::array<int, 3> c{};
        for (int a = 0; a < 3; ++a)
            c[size_t(a)] = std::clamp(int(std::floor((p[a] - origin[a]) / voxel)), 0, dims[size_t(a)] - 1);
        return c;
    }
    size_t count() const { return size_t(dims[0]) * dims[1] * dims[2]; }
    std::string describe() const {
        return std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]);
    }
};

}  // namespace ml
