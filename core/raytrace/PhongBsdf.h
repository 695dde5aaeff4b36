// The reflectance model of a Material (core/Scene.h) for the path tracer:
// Lambertian Kd plus the normalised modified Phong lobe of Ks and Ns
// (Lafortune & Willems 1994):
//   f(wo, wi) = Kd/π + Ks·(Ns + 2)/(2π)·cosⁿα,   n = Ns,
// α being the angle between wi and the mirror direction of wo. The
// (n + 2)/(2π) factor makes the lobe's albedo at normal incidence exactly
// Ks, and less at grazing incidence (part of the lobe falls below the
// horizon), so with Kd + Ks ≤ 1 the model never creates energy.
//
// Sampling picks a lobe with probability proportional to its weight
// (the mean of Kd's, respectively Ks's, channels), then a direction:
// cosine-weighted for the diffuse lobe, cosⁿα around the mirror direction
// (pdf (n + 1)/(2π)·cosⁿα) for the glossy one. pdf() is the mixture's
// density, so the estimate f·cosθ/pdf is unbiased whichever lobe was drawn;
// directions drawn below the surface are rejected (f is zero there).
#pragma once

#include "core/Scene.h"

namespace ml {

class PhongBsdf {
public:
    // `n`: unit shading normal on the side of the incoming light's hemisphere
    // (the integrator flips it towards wo).
    PhongBsdf(const Material& material, const Vec3& n) : PhongBsdf(material, n, material.kd) {}
    // With the diffuse reflectance at the point (a texture's, Material::kdMap).
    PhongBsdf(const Material& material, const Vec3& n, const Rgb& kd);

    // True when the surface reflects nothing (Kd = Ks = 0): paths end there.
    bool black() const { return diffuseWeight_ + glossyWeight_ <= 0; }

    // f(wo, wi) per channel, sr⁻¹; wo and wi unit, pointing away from the
    // surface. Zero when either lies below the shading normal's horizon.
    Rgb eval(const Vec3& wo, const Vec3& wi) const;
    // Solid-angle density of sample() drawing wi (0 below the horizon).
    double pdf(const Vec3& wo, const Vec3& wi) const;
    // Draws wi from three uniform numbers in [0, 1); returns false when the
    // draw lies below the horizon (or the surface is black).
    bool sample(const Vec3& wo, double uLobe, double u1, double u2, Vec3& wi) const;

private:
    Vec3 n_, t_, b_;  // shading frame
    Rgb kd_, ks_;
    double exponent_;
    double diffuseWeight_, glossyWeight_;  // lobe selection probabilities (sum 1 unless black)
};

}  // namespace ml
