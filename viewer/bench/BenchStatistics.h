// The statistics the benches share: medians of timings (other processes
// disturb single timings; medians shrug them off) and even subsets of
// points.
#pragma once

#include <cstddef>
#include <vector>

namespace ml {

// The median of `values`: the middle one, or the mean of the two middle
// ones when there is an even number; 0 when there are none.
double median(std::vector<double> values);

// `count` items spread evenly through `items` (all of them when there are
// no more), so that a subset still covers the whole floor, penumbra or mesh.
template <typename T>
std::vector<T> spread(const std::vector<T>& items, size_t count) {
    if (items.size() <= count) return items;
    std::vector<T> out;
    out.reserve(count);
    for (size_t k = 0; k < count; ++k) out.push_back(items[k * items.size() / count]);
    return out;
}

}  // namespace ml
