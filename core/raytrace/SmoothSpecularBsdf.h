// The path tracer's model of a material with a smooth layer (a mirror or
// glass, core/SmoothSpecular.h): the layer's two delta lobes, reflection
// and transmission, over the Lambertian Kd the material keeps:
//   f(wo, wi) = R(θo)·δ(wi − mirror(wo)) / cosθi
//             + T(θo)·δ(wi − refract(wo)) / |cosθi|
//             + Kd/π   (wi on wo's side),
// R and T from specularResponse(), θo measured from the shading normal.
// The Phong lobe of Ks is not part of it (Material::glossy() is false for
// such a material: a mirror's Ks is its reflectance).
//
// Sampling chooses one of the three lobes with probability proportional to
// its weight, the mean of R's, T's and Kd's channels, and returns the
// throughput weight f·|cosθi|/p of the choice: R/p_R, T/p_T, or Kd/p_D for a
// cosine-weighted diffuse direction. The estimate is unbiased whichever lobe
// is drawn, and a lobe of weight zero is never drawn.
//
// Sides. `front` says whether wo lies on the front (counter-clockwise) side
// of the triangle, i.e. outside a closed glass object: the interface's index
// is then ior, else 1/ior. The geometric normal decides it, not the shading
// normal, so a ray inside a sphere always knows it is inside. A reflected
// direction must stay on wo's side of the geometric surface and a
// transmitted one must cross it; a shading normal that tilts one across
// loses that path (sample() returns false), as the Phong lobe's draws below
// the true surface are lost.
#pragma once

#include "core/Scene.h"

namespace ml {

class SmoothSpecularBsdf {
public:
    // `ns`, `ng`: unit shading and geometric normals, both turned to wo's
    // side; `wo`: unit, away from the surface; `front`: wo is on the
    // triangle's front side; `kd`: the diffuse reflectance here.
    SmoothSpecularBsdf(const Material& material, const Vec3& ns, const Vec3& ng, const Vec3& wo, bool front,
                       const Rgb& kd);

    // True when nothing is reflected or transmitted: paths end there.
    bool black() const { return weightSum_ <= 0; }

    // The diffuse lobe, the only one next-event estimation can reach: Kd/π
    // for wi above the shading horizon (0 below it), and its density as
    // sample() draws it (the lobe's probability × cosθ/π), for MIS.
    Rgb evalDiffuse(const Vec3& wi) const;
    double pdfDiffuse(const Vec3& wi) const;

    struct Sample {
        Vec3 wi{0.0};       // unit, away from the surface
        Rgb weight{0.0};    // f·|cosθi| / pdf
        double pdf = 0;     // solid-angle density for the diffuse lobe; 0 for a delta lobe
        bool delta = false; // reflected or transmitted by the layer
    };
    // Draws a lobe and a direction from three uniform numbers in [0, 1);
    // false when the draw is lost (below the horizon, a side crossed the
    // wrong way, or the surface is black).
    bool sample(double uLobe, double u1, double u2, Sample& out) const;

private:
    Vec3 ns_, ng_, wo_;
    Vec3 n_;              // the layer's normal: ns, or ng where wo is below ns's horizon
    double eta_;          // far index / near index for a transmitted ray
    Rgb kd_;
    SpecularResponse response_;
    double reflectWeight_, transmitWeight_, diffuseWeight_, weightSum_;
};

}  // namespace ml
