// CPU twin of shaders/common_jitter.glsl: the same integer hash and the same
// float conversions, so the weight of a sample is evaluated at the very point
// of the pixel the GPU tested.
#pragma once

#include "core/Random.h"

#include <cstdint>

namespace ml::jitter {

inline uint32_t hash(uint32_t x) { return hash32(x); }

// Sample `bit` of pixel `pixel` in [0,1)² from the pixel's lower-left corner.
inline void position(uint32_t pixel, uint32_t bit, uint32_t seed, int strataX, int strataY, bool jitter,
                     float& u, float& v) {
    const uint32_t cx = bit % uint32_t(strataX);
    const uint32_t cy = bit / uint32_t(strataX);
    float rx = 0.5f, ry = 0.5f;
    if (jitter) {
        const uint32_t h = hash((pixel * 32u + bit) ^ seed);
        rx = (float(h & 0xffffu) + 0.5f) * (1.0f / 65536.0f);
        ry = (float(h >> 16) + 0.5f) * (1.0f / 65536.0f);
    }
    u = (float(cx) + rx) / float(strataX);
    v = (float(cy) + ry) / float(strataY);
}

// Strata per pixel for a number of samples: 1×1, 2×2, 4×2, 4×4, 8×4.
inline void strata(int bits, int& x, int& y) {
    switch (bits) {
        case 1: x = 1; y = 1; break;
        case 4: x = 2; y = 2; break;
        case 8: x = 4; y = 2; break;
        case 16: x = 4; y = 4; break;
        default: x = 8; y = 4; break;  // 32
    }
}

using ml::seedFor;

}  // namespace ml::jitter
