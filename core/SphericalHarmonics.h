// Real spherical harmonics up to order 2 (9 coefficients), for radiance
// fields captured at a point and the irradiance they give a surface.
//
// The basis is the real, orthonormal one: ∫ Y_i Y_j dω = δ_ij over the
// sphere, Y_i(d) a polynomial of degree l in the unit vector d's
// coordinates (Ramamoorthi & Hanrahan 2001, eq. 3; the complex functions
// of Nijasure et al.'s appendix, combined into real ones). A radiance
// field L(ω) projects onto L_i = ∫ L(ω) Y_i(ω) dω. Irradiance is L
// convolved with the clamped cosine max(0, n·ω), which is diagonal in this
// basis: E(n) = Σ_l Â_l Σ_m L_lm Y_lm(n), Â_0 = π, Â_1 = 2π/3, Â_2 = π/4
// (Ramamoorthi & Hanrahan 2001, eq. 8). Order 2 keeps the bands of the
// clamped cosine that carry 99% of its energy, so irradiance is off by a few
// per cent at most (under 3% on average for any lighting, their §3): a
// cosine-lobe radiance max(0, a·ω) gives 127π/192 at n = a instead of
// 2π/3, 0.75% low.
#pragma once

#include "Math.h"

#include <array>

namespace ml {

constexpr int kShCoefficients = 9;

// The nine basis functions at unit vector d, in the order (l, m) = (0, 0),
// (1, −1), (1, 0), (1, 1), (2, −2), (2, −1), (2, 0), (2, 1), (2, 2).
inline std::array<double, kShCoefficients> shBasis(const Vec3& d) {
    // √(1/4π), √(3/4π), √(15/4π), √(5/16π), √(15/16π).
    const double c0 = 0.5 * std::sqrt(1 / kPi), c1 = std::sqrt(3 / (4 * kPi)), c2 = std::sqrt(15 / (4 * kPi)),
                 c20 = std::sqrt(5 / (16 * kPi)), c22 = std::sqrt(15 / (16 * kPi));
    return {c0,
            c1 * d.y,
            c1 * d.z,
            c1 * d.x,
            c2 * d.x * d.y,
            c2 * d.y * d.z,
            c20 * (3 * d.z * d.z - 1),
            c2 * d.x * d.z,
            c22 * (d.x * d.x - d.y * d.y)};
}

// The band l of coefficient i.
constexpr int shBand(int i) { return i == 0 ? 0 : i < 4 ? 1 : 2; }

// Â_l: the clamped cosine's coefficients scaled for convolution, π, 2π/3, π/4.
inline double shCosineLobe(int band) { return band == 0 ? kPi : band == 1 ? 2 * kPi / 3 : kPi / 4; }

// An RGB radiance field's coefficients (W·sr⁻¹·m⁻² times the basis' sr⁻½).
struct ShRgb {
    std::array<Rgb, kShCoefficients> c{};

    // Adds a radiance seen along unit direction d over solid angle dω: one
    // term of the projection's quadrature.
    void add(const Vec3& d, const Rgb& radiance, double solidAngle) {
        const std::array<double, kShCoefficients> y = shBasis(d);
        for (int i = 0; i < kShCoefficients; ++i) c[size_t(i)] += (solidAngle * y[size_t(i)]) * radiance;
    }
    ShRgb& operator+=(const ShRgb& o) {
        for (size_t i = 0; i < c.size(); ++i) c[i] += o.c[i];
        return *this;
    }
    ShRgb operator*(double s) const {
        ShRgb r = *this;
        for (Rgb& v : r.c) v *= s;
        return r;
    }
    // The radiance the order-2 field gives along unit direction d.
    Rgb radiance(const Vec3& d) const {
        const std::array<double, kShCoefficients> y = shBasis(d);
        Rgb r(0.0);
        for (int i = 0; i < kShCoefficients; ++i) r += y[size_t(i)] * c[size_t(i)];
        return r;
    }
    // Irradiance (W·m⁻²) on a surface of unit normal n: the field convolved
    // with the clamped cosine. Not clamped: order 2 rings, and a field lit
    // from one side only gives a slightly negative value on its far side
    // (−π/192 of a cosine lobe's axis value); callers clamp what they show.
    Rgb irradiance(const Vec3& n) const {
        const std::array<double, kShCoefficients> y = shBasis(n);
        Rgb e(0.0);
        for (int i = 0; i < kShCoefficients; ++i) e += (shCosineLobe(shBand(i)) * y[size_t(i)]) * c[size_t(i)];
        return e;
    }
};

}  // namespace ml
