// A textured area light as the direct samplers see it: how much brighter or
// darker than its mean the light is at a point, L(y) / L̄ per channel.
//
// Light::radiance is the material's Ke, the factor × the emission texture's
// area-weighted mean (Scene.h): right for the light's power and its coverage
// bound, wrong for a receiver that sees the bright half of a light nearer
// than its dark half. A sampler that draws points y of the light multiplies
// each one's weight by weight(y), so its estimate of ∫ L(y) cosθ dω stays
// unbiased; Light::radiance × weight(y) is the material's keMap.value(uv),
// the value the path tracer and the compositor show at y.
#pragma once

#include "Scene.h"

#include <vector>

namespace ml {

class EmitterTexture {
public:
    // An untextured light: weight() is 1 everywhere.
    EmitterTexture() = default;
    // `light` of `scene` (an area light); textured when its material has an
    // emission map and its mesh has texture coordinates.
    EmitterTexture(const Scene& scene, const Light& light);
    // One per light of `scene`, in Scene::lights order (punctual lights untextured).
    static std::vector<EmitterTexture> forLights(const Scene& scene);

    bool textured() const { return map_ != nullptr; }

    // L / L̄ per channel at barycentric coordinates (b1, b2) of triangle `t`
    // (an index into Light::geometry, whose corners are p0, p1, p2: the
    // point p0 + b1 (p1 − p0) + b2 (p2 − p0)). 1 for an untextured light; 0
    // in a channel whose mean is 0.
    Rgb weight(size_t t, double b1, double b2) const;

    // weight() where the ray eye + s·dir (s > 0) meets the light's nearest
    // emitting face, for a direction the caller already knows meets the
    // light (a sample the sampler counted as on it). A ray that passes a
    // hair outside every face (a sample on the light's outline, decided in
    // another precision) takes the face it misses least, clamped onto it.
    // Costs a ray–triangle test per face of the light: textured lights of a
    // few faces (panels, quads) are what this is for.
    Rgb weightAlong(const Vec3& eye, const Vec3& dir) const;

private:
    const TextureMap* map_ = nullptr;  // the material's keMap (the scene outlives this)
    Rgb inverseMean{0.0};              // 1 / Ke per channel, 0 where Ke is 0
    struct Face {
        Vec3 p0, e1, e2;               // corner and edges of Light::geometry[t]
        Vec2 uv0, uv1, uv2;            // its corners' texture coordinates
    };
    std::vector<Face> faces_;
};

}  // namespace ml
