// A perfectly smooth layer over a material's diffuse Kd: mirrors (MTL illum
// 3 and 5, glTF metallic = 1 with roughness 0) and glass or water (MTL
// illum 7, glTF KHR_materials_transmission). It reflects and refracts
// without scattering (a delta BSDF), so no cache can hold what it sends
// towards the eye: the compositor and the path tracer follow its rays, and
// light that reaches a diffuse surface through it (a caustic) is carried by
// photons, never by the direct sampler (for which glass casts a shadow).
//
// One model for every consumer (path tracer, compositor, photon tracer), so
// that they agree exactly:
//   Mirror: reflects R(θ) = F0 (Ks), or with Schlick's rise to 1 at grazing
//           incidence, F0 + (1 − F0)(1 − cos θ)⁵, when `schlick` (illum 5);
//           transmits nothing.
//   Glass:  reflects F(θ), the unpolarised dielectric Fresnel reflectance of
//           the relative index `ior` (MTL Ni), and transmits (1 − F(θ))·Tf
//           (the MTL transmission filter), refracted by Snell's law; total
//           internal reflection reflects everything. Radiance crossing the
//           interface is not rescaled by η² (paths that enter a closed
//           object leave it again, and both sides of the scene's renderers
//           follow the same convention).
// The diffuse Kd under the layer is kept as it is (the cache shades it), so
// the McGuire spheres' Kd 0.01 still shows.
#pragma once

#include "Math.h"

namespace ml {

enum class SpecularKind { None, Mirror, Glass };

struct SmoothSpecular {
    SpecularKind kind = SpecularKind::None;
    Rgb reflectance{1.0};   // Mirror: F0 per channel, in [0, 1]
    bool schlick = false;   // Mirror: F0 rises to 1 at grazing incidence
    double ior = 1.5;       // Glass: index inside / outside (> 0, ≠ 1 for a visible interface)
    Rgb transmission{1.0};  // Glass: the transmission filter Tf, in [0, 1]

    bool active() const { return kind != SpecularKind::None; }
};

// The mirror direction of unit wo (pointing away from the surface) about n.
inline Vec3 reflectDirection(const Vec3& wo, const Vec3& n) { return 2.0 * glm::dot(wo, n) * n - wo; }

// Unpolarised Fresnel reflectance of a dielectric interface. cosI: cosine
// between the incident direction and the normal on the incident side (> 0);
// eta: index of the far side / index of the incident side. 1 under total
// internal reflection.
inline double fresnelDielectric(double cosI, double eta) {
    cosI = std::clamp(cosI, 0.0, 1.0);
    const double sin2T = (1.0 - cosI * cosI) / (eta * eta);
    if (sin2T >= 1.0) return 1.0;
    const double cosT = std::sqrt(1.0 - sin2T);
    const double rs = (cosI - eta * cosT) / (cosI + eta * cosT);
    const double rp = (eta * cosI - cosT) / (eta * cosI + cosT);
    return 0.5 * (rs * rs + rp * rp);
}

// Refracts unit wo (pointing away from the surface, on n's side) into the
// far side of an interface of relative index eta (far / near): true and the
// transmitted direction wt (pointing away from the surface, on −n's side),
// or false under total internal reflection.
inline bool refractDirection(const Vec3& wo, const Vec3& n, double eta, Vec3& wt) {
    const double cosI = glm::dot(wo, n);
    const double sin2T = std::max(0.0, 1.0 - cosI * cosI) / (eta * eta);
    if (sin2T >= 1.0) return false;
    const double cosT = std::sqrt(1.0 - sin2T);
    wt = -wo / eta + (cosI / eta - cosT) * n;
    return true;
}

// What the layer does to light arriving along −wo's reverse: the reflected
// and the transmitted weight per channel. `n` is the geometric normal on
// wo's side; `entering` is true when wo is on the front (outside) side, so
// the interface's index is ior (else 1/ior).
struct SpecularResponse {
    Rgb reflected{0.0};
    Rgb transmitted{0.0};
};

inline SpecularResponse specularResponse(const SmoothSpecular& s, double cosI, bool entering) {
    SpecularResponse r;
    cosI = std::clamp(cosI, 0.0, 1.0);
    if (s.kind == SpecularKind::Mirror) {
        if (!s.schlick) {
            r.reflected = s.reflectance;
        } else {
            const double m = 1.0 - cosI;
            const double m5 = (m * m) * (m * m) * m;
            r.reflected = s.reflectance + (Rgb(1.0) - s.reflectance) * m5;
        }
    } else if (s.kind == SpecularKind::Glass) {
        const double f = fresnelDielectric(cosI, entering ? s.ior : 1.0 / s.ior);
        r.reflected = Rgb(f);
        r.transmitted = (1.0 - f) * s.transmission;
    }
    return r;
}

}  // namespace ml
