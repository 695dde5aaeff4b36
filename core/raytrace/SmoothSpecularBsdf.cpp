#include "SmoothSpecularBsdf.h"

#include <cmath>

namespace ml {

namespace {

double mean(const Rgb& c) { return std::max((c.r + c.g + c.b) / 3.0, 0.0); }

}  // namespace

SmoothSpecularBsdf::SmoothSpecularBsdf(const Material& material, const Vec3& ns, const Vec3& ng, const Vec3& wo,
                                       bool front, const Rgb& kd)
    : ns_(ns), ng_(ng), wo_(wo), kd_(kd) {
    const SmoothSpecular& layer = material.smooth;
    // A shading normal tilted so far that wo is below its horizon cannot
    // orient the layer: the flat triangle does.
    n_ = glm::dot(wo, ns) > 0 ? ns : ng;
    eta_ = front ? layer.ior : 1.0 / layer.ior;
    response_ = specularResponse(layer, glm::dot(wo, n_), front);
    reflectWeight_ = mean(response_.reflected);
    transmitWeight_ = mean(response_.transmitted);
    diffuseWeight_ = mean(kd_);
    weightSum_ = reflectWeight_ + transmitWeight_ + diffuseWeight_;
}

Rgb SmoothSpecularBsdf::evalDiffuse(const Vec3& wi) const {
    if (glm::dot(wi, ns_) <= 0 || glm::dot(wo_, ns_) <= 0) return Rgb(0.0);
    return kd_ * (1.0 / kPi);
}

double SmoothSpecularBsdf::pdfDiffuse(const Vec3& wi) const {
    const double cosTheta = glm::dot(wi, ns_);
    if (cosTheta <= 0 || glm::dot(wo_, ns_) <= 0 || black()) return 0.0;
    return diffuseWeight_ / weightSum_ * cosTheta / kPi;
}

bool SmoothSpecularBsdf::sample(double uLobe, double u1, double u2, Sample& out) const {
    if (black()) return false;
    const double u = uLobe * weightSum_;
    if (u < reflectWeight_) {
        out.wi = glm::normalize(reflectDirection(wo_, n_));
        if (glm::dot(out.wi, ng_) <= 0) return false;
        out.weight = response_.reflected * (weightSum_ / reflectWeight_);
        out.pdf = 0;
        out.delta = true;
        return true;
    }
    if (u < reflectWeight_ + transmitWeight_) {
        // T > 0 only where refraction exists (no total internal reflection).
        Vec3 wt;
        if (!refractDirection(wo_, n_, eta_, wt)) return false;
        out.wi = glm::normalize(wt);
        if (glm::dot(out.wi, ng_) >= 0) return false;
        out.weight = response_.transmitted * (weightSum_ / transmitWeight_);
        out.pdf = 0;
        out.delta = true;
        return true;
    }
    if (glm::dot(wo_, ns_) <= 0) return false;
    // Cosine-weighted (Malley), as PhongBsdf's diffuse lobe.
    Vec3 t, b;
    orthonormalBasis(ns_, t, b);
    const double r = std::sqrt(u1), phi = 2.0 * kPi * u2;
    out.wi = glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0, 1.0 - u1)) * ns_);
    if (glm::dot(out.wi, ns_) <= 0) return false;
    out.weight = kd_ * (weightSum_ / diffuseWeight_);
    out.pdf = pdfDiffuse(out.wi);
    out.delta = false;
    return true;
}

}  // namespace ml
