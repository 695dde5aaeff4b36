// Radiance through mirrors and glass, read from the cache where a path
// ends: the display-time specular pass of issue 16. A ray that meets a
// smooth specular layer (core/SmoothSpecular.h) is followed, reflected and
// refracted with specularResponse's weights, until it reaches a surface the
// cache shades; there it reads
//   Lo(y) = Kd(y)/π × Σ_m w_m E_m(y) + w_l Le(y) + a Phong highlight,
// the cached irradiance E_m interpolated at y on the side the ray arrives
// from (MeshIrradianceLookup), exactly what the compositor shows there.
//
// Glass splits into both branches, each followed while its weight (the
// product of the reflectances and transmittances on the way) is at least
// SpecularSplitSettings::minWeight: deterministic, with no noise, where
// choosing one branch by probability would need many paths per pixel. A
// path still on a specular surface after maxSpecularBounces contributes
// black there (its Kd under the layer is still shaded).
//
// Phong highlights (Material::glossy, the paper's §3 pass): each light l
// whose own direct mesh is read gives
//   L_s = Ks × (Ns + 2)/(2π) × cosⁿα × E_l,
// the normalised modified Phong BRDF of core/raytrace/PhongBsdf.h for light
// arriving from one direction ω_l (∫ f L cos θ dω = f(ω_l) E_l when f is
// constant over the light; E_l holds the cosine, so there is no 1/cos θ_l,
// which would belong to a lobe without the cosine, not the path tracer's):
// towards the area light's centroid, a point light's position, against a
// directional light's direction. α is the angle between ω_l's mirror and the
// view. Exact for a light small against the lobe; a large light
// (solid angle comparable to the lobe's, about 2π/(Ns + 1)) is blurred
// towards its centroid. The mesh many lights share (IrradianceCache::
// hasSharedMesh) has no one direction and gives no highlight.
//
// The display's chain: the photons and the indirect gather follow one
// branch at random instead (core/raytrace/SpecularChain.h, the same normals
// and the same rule for a branch sent to the wrong side of the surface),
// since they average many rays anyway. Any caller with an EmbreeScene and
// the cache's lookups can call these (a gather reading glossy highlights).
//
// Glass: the diffuse Kd under a smooth layer is shaded by the cache like any
// surface; the layer's reflection and transmission are added to it.
#pragma once

#include "core/Scene.h"
#include "core/raytrace/EmbreeScene.h"

#include <vector>

namespace ml {

class MeshIrradianceLookup;

// One cache mesh read where a path ends, times its weight (LightWeights).
struct WeightedLookup {
    const MeshIrradianceLookup* lookup = nullptr;
    Rgb weight{1.0};
    // The scene light whose own direct mesh this is, for its highlight;
    // −1 for the shared mesh and indirect meshes.
    int light = -1;
};

struct SpecularSplitSettings {
    // Specular surfaces a path may cross before it is cut (black), typical 8:
    // a ray through a glass sphere uses 2, a mirror facing a mirror more.
    int maxSpecularBounces = 8;
    // A branch whose weight (max over channels) falls below this is not
    // traced, typical 1e-3: the error it leaves is at most this share of the
    // brightest radiance it could have reached.
    double minWeight = 1e-3;
    void validate() const;  // InputError unless 0 <= bounces <= 64 and 0 <= minWeight < 1
};

// What a path reads where it ends. References must outlive it.
struct CachedRadiance {
    const Scene& scene;
    const EmbreeScene& rays;
    const std::vector<char>& closedMeshes;  // closedMeshesOf(scene): a closed mesh's inside is black
    std::vector<WeightedLookup> meshes;     // Σ_m w_m E_m is the irradiance a surface is shaded by
    // Per scene light, the factor of the radiance its emitting faces show;
    // empty: emitters show nothing (a gather whose direct light the direct
    // meshes already hold).
    std::vector<Rgb> emission;
    bool highlights = true;  // Phong highlights of glossy surfaces from the lights' own meshes
    SpecularSplitSettings settings;
};

// Radiance arriving at `origin` from unit `direction`: what the surface hit
// sends back, through any mirrors and glass on the way (black on a miss).
Rgb cachedRadianceAlong(const CachedRadiance& cache, const Vec3& origin, const Vec3& direction);

// The part of the radiance leaving hit y towards unit `wo` that no cache
// mesh holds: the Phong highlight of a glossy material, or what a mirror or
// glass reflects and transmits; black for a Lambertian one. The compositor
// adds this to its Kd/π × E; a gather adds it to what it reads at y.
Rgb specularRadiance(const CachedRadiance& cache, const SurfacePoint& y, const Vec3& wo);

// What the cache shades y with, seen from unit `wo`: Kd(y)/π × Σ w_m E_m(y)
// on wo's side (black on the inside of a closed mesh) plus the light's
// emission on an emitting face's front.
Rgb cachedDiffuseRadiance(const CachedRadiance& cache, const RayHit& hit, const SurfacePoint& y, const Vec3& wo);

}  // namespace ml
