// Vector types and small geometric helpers shared by every module.
//
// CPU geometry is double precision (glm::dvec3): irradiance near a light, at
// grazing angles and at scales from 1e-3 to 1e5 needs it. Only what goes to
// the GPU is converted to float, after being made relative to a nearby origin.
#pragma once

#include <glm/glm.hpp>
#include <algorithm>
#include <cmath>
#include <limits>

namespace ml {

using Vec2 = glm::dvec2;
using Vec3 = glm::dvec3;
using Vec4 = glm::dvec4;
using Mat3 = glm::dmat3;
using Mat4 = glm::dmat4;
using Rgb = glm::dvec3;  // linear RGB; radiance in W·sr⁻¹·m⁻², irradiance in W·m⁻²

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

inline bool isFinite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Axis-aligned bounding box; empty when lo > hi.
struct Bounds3 {
    Vec3 lo{kInf};
    Vec3 hi{-kInf};

    void extend(const Vec3& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
    void extend(const Bounds3& b) { lo = glm::min(lo, b.lo); hi = glm::max(hi, b.hi); }
    bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    Vec3 center() const { return 0.5 * (lo + hi); }
    Vec3 extent() const { return empty() ? Vec3(0.0) : hi - lo; }
    double diagonal() const { return glm::length(extent()); }
};

// An orthonormal basis (t, b, n) around a unit vector n (Duff et al. 2017).
inline void orthonormalBasis(const Vec3& n, Vec3& t, Vec3& b) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double c = n.x * n.y * a;
    t = Vec3(1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = Vec3(c, sign + n.y * n.y * a, -n.y);
}

// A cosine-distributed direction about unit n, (t, b, n) orthonormal, from
// two uniforms in [0, 1) by Malley's method: the disk point (√u1, 2π·u2)
// lifted onto the hemisphere.
inline Vec3 cosineDirection(const Vec3& n, const Vec3& t, const Vec3& b, double u1, double u2) {
    const double r = std::sqrt(u1), phi = 2 * kPi * u2;
    return r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0, 1 - u1)) * n;
}

// Luminance of linear Rec.709 RGB: how bright a value looks on screen (tone
// mapping, exposure, noise measures). Lux and lumens take the photometry's
// weights instead (core/image/Photometry.h).
inline double luminance(const Rgb& c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; }

// The variance of the mean of `count` independent draws, from their sum and
// their sum of squares: their scatter Σx² − (Σx)²/N over N(N − 1) (never
// below 0: rounding). 0 for fewer than two draws.
inline double varianceOfMean(double sum, double squares, double count) {
    return count > 1 ? std::max(0.0, squares - sum * sum / count) / (count * (count - 1)) : 0.0;
}

}  // namespace ml
