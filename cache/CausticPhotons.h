// Photons for caustics: light that reaches a diffuse surface through or off
// mirrors and glass (L S+ D paths). The direct sampler treats smooth layers
// as opaque (SmoothSpecular.h), so this is the only carrier of that light;
// CausticCache turns the photons into irradiance at cache vertices.
//
// Emission is aimed: each light sends photons only into the cones that
// subtend the bounding spheres of the specular objects it sees (its
// targets), with the cones' mixture pdf, so no photon is spent on the room.
// Every L S+ D path starts inside some cone (the spheres contain the
// objects), so nothing is lost by aiming. Per photon:
//   area light:   a triangle by area, a point uniform on it, a direction from
//                 the cone mixture; power L cosθ A / pdf(ω);
//   point light:  a direction from the cone mixture; power I(ω) / pdf(ω) / s²
//                 (s = metres per unit, as punctualIncidence divides by);
//   directional:  a point on the disc that covers a target sphere, across
//                 the light's direction; power E / pdf(disc point).
// A light is drawn by its share of the lights' power, the power divided by
// that probability. Each photon follows the specular chain
// (followSpecularChain: one branch per interface by its Fresnel share, no
// Russian roulette, at most SpecularChainSettings::maxDepth layers) and is
// kept where it first meets a diffuse surface after at least one layer.
// Powers are per photon emitted: a deposit's power summed over a region and
// divided by the photons emitted (kept or not) is the flux it receives, in
// W·(scene unit)²·m⁻² like Light::power, so divided by an area in scene
// units² it is W·m⁻².
#pragma once

#include "core/Scene.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace ml {

class EmbreeScene;

// A photon where it came to rest.
struct CausticPhoton {
    Vec3 position{0.0};
    Vec3 normal{0.0};  // unit geometric normal on the side it arrived from
    Rgb power{0.0};    // see above: flux × photons emitted
};

// A specular object a light sees, as the sphere photons are aimed at.
struct CausticTarget {
    uint32_t mesh = 0;  // index into Scene::meshes
    Vec3 centre{0.0};
    double radius = 0;
};

class CausticPhotons {
public:
    // Finds, for each light, the specular objects it sees (some of 64 rays
    // from the light to points on the object meets a smooth layer first).
    // `rays` must be built on `scene`; both must outlive this object.
    CausticPhotons(const Scene& scene, const EmbreeScene& rays);

    // Some light sees some specular object: there are caustics to trace.
    bool active() const { return !lightPick_.empty(); }
    // "2 specular objects (Sphere, Glass) seen by 1 of 1 lights"; why none otherwise.
    std::string describe() const;
    const std::vector<CausticTarget>& targets(size_t light) const { return targets_.at(light); }

    // Emits photons first, first+1, ..., first+count−1 (each drawn from its
    // own seed, so any split into calls and threads gives the same photons)
    // and appends the ones that land to `out`, in photon order.
    void trace(uint64_t first, size_t count, uint32_t seed, std::vector<CausticPhoton>& out) const;

private:
    void traceOne(uint64_t index, uint32_t seed, std::vector<CausticPhoton>& out) const;

    const Scene& scene_;
    const EmbreeScene& rays_;
    std::vector<char> closed_;                         // per mesh, for the chain
    std::vector<std::vector<CausticTarget>> targets_;  // per light
    std::vector<std::vector<double>> targetCdf_;       // per light, over its targets
    std::vector<std::vector<double>> triangleCdf_;     // per area light, over its triangles by area
    std::vector<uint32_t> lightPick_;                  // lights with targets...
    std::vector<double> lightCdf_;                     // ...drawn by power
    std::vector<double> lightProbability_;             // per light (0: never drawn)
};

}  // namespace ml
