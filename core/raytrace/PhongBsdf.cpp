#include "PhongBsdf.h"

#include <cmath>

namespace ml {

namespace {

double mean(const Rgb& c) { return (c.r + c.g + c.b) / 3.0; }

Vec3 mirror(const Vec3& wo, const Vec3& n) { return 2.0 * glm::dot(wo, n) * n - wo; }

}  // namespace

PhongBsdf::PhongBsdf(const Material& material, const Vec3& n, const Rgb& kd)
    // A mirror's or glass's Ks is its smooth layer's business
    // (SmoothSpecularBsdf), not a Phong lobe's: glossy() leaves it out.
    : n_(n), kd_(kd), ks_(material.glossy() ? material.ks : Rgb(0.0)), exponent_(std::max(material.ns, 0.0)) {
    orthonormalBasis(n_, t_, b_);
    const double wd = std::max(mean(kd_), 0.0), ws = std::max(mean(ks_), 0.0);
    const double sum = wd + ws;
    diffuseWeight_ = sum > 0 ? wd / sum : 0.0;
    glossyWeight_ = sum > 0 ? ws / sum : 0.0;
}

Rgb PhongBsdf::eval(const Vec3& wo, const Vec3& wi) const {
    if (glm::dot(wi, n_) <= 0 || glm::dot(wo, n_) <= 0) return Rgb(0.0);
    Rgb f = kd_ * (1.0 / kPi);
    if (glossyWeight_ > 0) {
        const double c = glm::dot(wi, mirror(wo, n_));
        if (c > 0) f += ks_ * ((exponent_ + 2.0) / (2.0 * kPi) * std::pow(c, exponent_));
    }
    return f;
}

double PhongBsdf::pdf(const Vec3& wo, const Vec3& wi) const {
    const double cosTheta = glm::dot(wi, n_);
    if (cosTheta <= 0 || glm::dot(wo, n_) <= 0) return 0.0;
    double p = diffuseWeight_ * cosTheta / kPi;
    if (glossyWeight_ > 0) {
        const double c = glm::dot(wi, mirror(wo, n_));
        if (c > 0) p += glossyWeight_ * (exponent_ + 1.0) / (2.0 * kPi) * std::pow(c, exponent_);
    }
    return p;
}

bool PhongBsdf::sample(const Vec3& wo, double uLobe, double u1, double u2, Vec3& wi) const {
    if (black() || glm::dot(wo, n_) <= 0) return false;
    const double phi = 2.0 * kPi * u2;
    if (uLobe < diffuseWeight_) {
        // Cosine-weighted (Malley): a uniform point of the unit disc lifted
        // onto the hemisphere.
        const double r = std::sqrt(u1);
        const double z = std::sqrt(std::max(0.0, 1.0 - u1));
        wi = r * std::cos(phi) * t_ + r * std::sin(phi) * b_ + z * n_;
    } else {
        const Vec3 axis = mirror(wo, n_);
        Vec3 t, b;
        orthonormalBasis(axis, t, b);
        const double cosAlpha = std::pow(u1, 1.0 / (exponent_ + 1.0));
        const double sinAlpha = std::sqrt(std::max(0.0, 1.0 - cosAlpha * cosAlpha));
        wi = sinAlpha * std::cos(phi) * t + sinAlpha * std::sin(phi) * b + cosAlpha * axis;
    }
    wi = glm::normalize(wi);
    return glm::dot(wi, n_) > 0;
}

}  // namespace ml
