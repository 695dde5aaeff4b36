#include "PunctualLight.h"

#include "CandelaTable.h"
#include "Error.h"
#include "Scene.h"

#include <algorithm>
#include <cmath>

namespace ml {

double IntensityProfile::operator()(double cosGamma, double cAngleDegrees) const {
    switch (shape) {
        case Shape::Isotropic: return 1.0;
        case Shape::Spot: {
            // glTF KHR_lights_punctual's smooth falloff: t² with t linear in
            // cos between the outer and inner cones (its reference code's
            // lightAngleScale/Offset, with the same 0.001 guard).
            const double scale = 1.0 / std::max(0.001, cosInner - cosOuter);
            const double t = std::clamp((cosGamma - cosOuter) * scale, 0.0, 1.0);
            return t * t;
        }
        case Shape::Table: {
            if (!(tablePeak > 0)) return 0.0;
            const double gamma = std::acos(std::clamp(cosGamma, -1.0, 1.0)) * 180.0 / kPi;
            return std::clamp(table->intensity(gamma, cAngleDegrees) / tablePeak, 0.0, 1.0);
        }
    }
    return 0.0;
}

double IntensityProfile::solidAngle() const {
    switch (shape) {
        case Shape::Isotropic: return 4 * kPi;
        case Shape::Spot: {
            // 2π [∫ over the inner cap + ∫ t(μ)² dμ across the falloff], t
            // linear in μ = cos γ: the falloff band gives (ci − co)/3 when
            // the guard does not bind, and in general the integral of t² up
            // to where t reaches 1.
            const double scale = 1.0 / std::max(0.001, cosInner - cosOuter);
            const double full = std::min(1.0, cosOuter + 1.0 / scale);  // where t = 1
            return 2 * kPi * ((1.0 - full) + (full - cosOuter) / 3.0);
        }
        case Shape::Table: return tablePeak > 0 ? table->flux() / tablePeak : 0.0;
    }
    return 0.0;
}

std::string IntensityProfile::describe() const {
    const auto degrees = [](double c) { return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / kPi; };
    switch (shape) {
        case Shape::Isotropic: return "isotropic";
        case Shape::Spot: return concat("spot, full to ", degrees(cosInner), "°, none past ", degrees(cosOuter), "°");
        case Shape::Table: return concat("candela table '", table->source, "'");
    }
    return {};
}

Rgb PunctualEmission::intensityToward(const Vec3& w) const {
    const double cosGamma = glm::dot(w, axis);
    double c = 0;
    if (profile.shape == IntensityProfile::Shape::Table) {
        // C around the axis from the reference half-plane, right-handed
        // about the axis: C90 is axis × reference.
        const Vec3 side = glm::cross(axis, reference);
        c = std::atan2(glm::dot(w, side), glm::dot(w, reference)) * 180.0 / kPi;
        if (c < 0) c += 360.0;
    }
    return intensity * profile(cosGamma, c);
}

PunctualIncidence punctualIncidence(const Light& light, const Vec3& x, const Vec3& n) {
    const PunctualEmission& e = light.emission;
    PunctualIncidence out;
    if (light.kind == LightKind::Directional) {
        out.toLight = -e.axis;
        out.distance = kInf;
        const double cosX = glm::dot(n, out.toLight);
        if (cosX > 0) out.irradiance = e.intensity * cosX;
        return out;
    }
    const Vec3 v = e.position - x;
    const double d = glm::length(v);
    out.distance = d;
    if (!(d > e.minDistance)) return out;  // at the light: no direction (PunctualLight.h)
    out.toLight = v / d;
    const double cosX = glm::dot(n, out.toLight);
    if (!(cosX > 0)) return out;
    const double metres = d * e.metresPerUnit;
    out.irradiance = e.intensityToward(-out.toLight) * (cosX / (metres * metres));
    return out;
}

Rgb Light::power() const {
    switch (kind) {
        case LightKind::Area: return kPi * radiance * area;
        case LightKind::Point: {
            const double s = emission.metresPerUnit;
            return emission.intensity * (emission.profile.solidAngle() / (s * s));
        }
        case LightKind::Directional: return emission.intensity * (kPi * emission.sceneRadius * emission.sceneRadius);
    }
    return Rgb(0.0);
}

}  // namespace ml
