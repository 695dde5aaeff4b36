// A uniform grid over a scene's bounds in which items (edges, triangles) are
// listed in every cell their bounds touch: what lies near a point or a box,
// without a hierarchy. Cells are cubes, about cbrt(n) along the bounds'
// longest side (at most `maxCells`), so that a scene of n small items puts a
// few in each cell; an item as long as the scene (a wall) is listed in a
// slab of cells, which for the few such items of a room stays small.
//
// Used where the question is asked many times of a fixed set: the edges near
// a receiver triangle (ContactCuts), the surfaces through a cache vertex
// (EdgeOnSurfaces).
#pragma once

#include "Math.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace ml {

class BoundsGrid {
public:
    BoundsGrid() = default;
    // items[i]: item i's bounds (already padded by what the queries need).
    // Empty bounds are listed nowhere.
    BoundsGrid(const Bounds3& domain, const std::vector<Bounds3>& items, double maxCells = 48)
        : lo_(domain.lo), cell_(cellSize(domain, items.size(), maxCells)) {
        const Vec3 extent = glm::max(domain.extent(), Vec3(1e-12));
        for (int k = 0; k < 3; ++k) n_[k] = std::max(1, int(std::ceil(extent[k] / cell_)));
        cells_.resize(size_t(n_[0]) * n_[1] * n_[2]);
        for (size_t i = 0; i < items.size(); ++i)
            if (!items[i].empty()) forCells(items[i], [&](size_t c) { cells_[c].push_back(uint32_t(i)); });
    }

    // The side of the cells a grid of `count` items over `domain` gets (for
    // padding the items' bounds by a share of it before they are listed).
    static double cellSize(const Bounds3& domain, size_t count, double maxCells = 48) {
        const Vec3 extent = glm::max(domain.extent(), Vec3(1e-12));
        const double cells = std::clamp(std::cbrt(double(count)), 1.0, std::max(1.0, maxCells));
        return std::max({extent.x, extent.y, extent.z}) / cells;
    }

    // The items whose bounds may meet `b`, ascending, each once.
    void query(const Bounds3& b, std::vector<uint32_t>& out) const {
        out.clear();
        forCells(b, [&](size_t c) { out.insert(out.end(), cells_[c].begin(), cells_[c].end()); });
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    }

    // The items listed in the cell holding p (points outside the domain go
    // to the nearest cell); f(i) returns true to stop.
    template <class F>
    bool anyAt(const Vec3& p, F f) const {
        if (cells_.empty()) return false;
        const std::vector<uint32_t>& cell = cells_[cellOf(p)];
        return std::any_of(cell.begin(), cell.end(), f);
    }

private:
    int axisCell(double x, int k) const { return std::clamp(int(std::floor((x - lo_[k]) / cell_)), 0, n_[k] - 1); }
    size_t cellOf(const Vec3& p) const {
        return (size_t(axisCell(p.z, 2)) * n_[1] + axisCell(p.y, 1)) * n_[0] + axisCell(p.x, 0);
    }
    template <class F>
    void forCells(const Bounds3& b, F f) const {
        int lo[3], hi[3];
        for (int k = 0; k < 3; ++k) lo[k] = axisCell(b.lo[k], k), hi[k] = axisCell(b.hi[k], k);
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x) f((size_t(z) * n_[1] + y) * n_[0] + x);
    }

    Vec3 lo_{0.0};
    double cell_ = 1;
    int n_[3] = {1, 1, 1};
    std::vector<std::vector<uint32_t>> cells_;
};

}  // namespace ml
