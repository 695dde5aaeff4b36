// Union-find with path halving: groups connected faces (lights, occluder
// pieces).
#pragma once

#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace ml {

struct DisjointSets {
    std::vector<uint32_t> parent;
    explicit DisjointSets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
    uint32_t find(uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    }
    void unite(uint32_t a, uint32_t b) { parent[find(a)] = find(b); }
};

}  // namespace ml
