// Deterministic integer hashing for seeds: the same inputs give the same
// samples on every run and thread count.
#pragma once

#include <cstdint>

namespace ml {

// "lowbias32" integer hash (C. Wellons): good avalanche, two multiplies.
// gpu_sampling/shaders/common_jitter.glsl has its GLSL twin.
inline uint32_t hash32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// Mixes a user seed with a sample's identity (vertex, light, pass) into one
// 32-bit seed, so every repeat draws fresh jitter and runs are reproducible.
inline uint32_t seedFor(uint32_t userSeed, uint32_t a, uint32_t b = 0, uint32_t c = 0) {
    return hash32(hash32(hash32(userSeed ^ 0x51ed270bu) ^ a) + 0x68e31da4u * b + 0x1b56c4e9u * c);
}

}  // namespace ml
