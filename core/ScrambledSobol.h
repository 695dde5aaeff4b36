// Points of a 2D (0,2)-sequence in base 2 (the first two dimensions of
// Sobol's sequence: the van der Corput sequence and its Pascal-matrix
// partner) under a hash-based nested uniform ("Owen") scrambling, after
// Burley, "Practical Hash-based Owen Scrambling" (JCGT 9(4), 2020).
//
// Why: an estimate made again and again at the same point (a cache vertex
// gathered once per round) converges as 1/√(estimates) when each draws
// independent jitter, however well each is stratified on its own. Drawn as
// consecutive blocks of one scrambled sequence instead, every estimate is
// still stratified (a block of 2^m points is a (0,m,2)-net), and the blocks
// together stratify ever finer: for the piecewise-smooth radiance a
// hemisphere sees, the error of their mean falls nearer (points)^-0.75.
// Owen scrambling leaves every point uniform on [0,1)², so any estimate
// that is unbiased with uniform points stays unbiased.
#pragma once

#include "Random.h"

#include <array>
#include <cstdint>

namespace ml {

class ScrambledSobol2D {
public:
    // `seed` chooses the scrambling: two seeds give independent sequences.
    explicit ScrambledSobol2D(uint32_t seed) : seedX_(hash32(seed ^ 0x3c6ef372u)), seedY_(hash32(seed ^ 0xa54ff53au)) {}

    // Point `index` of the sequence, in [0, 1)².
    std::array<double, 2> operator()(uint32_t index) const {
        constexpr double kUnit = 1.0 / 4294967296.0;
        return {scramble(reverseBits(index), seedX_) * kUnit, scramble(pascal(index), seedY_) * kUnit};
    }

    // Its first dimension's digits, most significant first, are the index's
    // bits read backwards (van der Corput).
    static uint32_t reverseBits(uint32_t x) {
        x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
        x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
        x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
        x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
        return (x >> 16) | (x << 16);
    }

    // The second dimension: the index's bits through Sobol's second
    // generator matrix (Pascal's triangle mod 2), column k being the
    // direction number v_k = v_{k-1} ^ (v_{k-1} >> 1) from v_0 = 2^31.
    static uint32_t pascal(uint32_t index) {
        uint32_t v = 1u << 31, x = 0;
        for (; index != 0; index >>= 1, v ^= v >> 1)
            if (index & 1u) x ^= v;
        return x;
    }

private:
    // Nested uniform scrambling of a 32-bit fraction: each digit flipped by
    // a hash of the digits above it. Done as Burley does, by a permutation
    // whose every output bit depends only on the input bits below it
    // (Laine and Karras's), applied to the bits reversed.
    static uint32_t scramble(uint32_t x, uint32_t seed) {
        x = reverseBits(x);
        x += seed;
        x ^= x * 0x6c50b47cu;
        x ^= x * 0xb82f1e52u;
        x ^= x * 0xc7afe638u;
        x ^= x * 0x8d22f6e6u;
        return reverseBits(x);
    }

    uint32_t seedX_, seedY_;
};

}  // namespace ml
