// Direct irradiance from an area light by shadow rays (Embree, CPU) through
// exactly the sample points the raster sampler tests: the peer the
// hardware sampler (DirectLightSampler.h) is measured against.
//
// Same as the raster sampler, step for step: the eye lifted off the receiver
// (samplingEyeLift), the light's pieces above the receiver's horizon
// (visibleLightPieces), the same frusta (fitFrusta, rows along the same light
// edge), the same per-frustum seed (jitter::hash(seed + k·0x9E3779B9)) and
// the same stratified jitter per pixel (Jitter.h), so sample `bit` of pixel
// (i, j) is the very window point (u, v) the GPU tests; the same weight
// cosθ·dω = (n·s)/|s|⁴ per unit window area; the same estimators (plain:
// Σ visible weights; cv: Lambert's closed form at the receiver minus the
// occluded weights, planar lights only). What differs is only how a sample
// is decided:
//   on the light   planar light: inside the light's pieces projected onto
//                  the window, in double (the raster cv path does the same;
//                  its plain path rasterises the light in float); other
//                  lights: a ray meets one of the light's front faces
//   occluded       an occlusion ray from the eye towards (u, v, 1) meets a
//                  triangle not of this light, at a depth beyond the near
//                  plane and (planar light) at least planeTolerance × the
//                  scene's size in front of the light's plane, or (other
//                  lights) in front of the light's nearest front face: the
//                  raster sampler's rules, per sample, instead of rasterised
//                  occluders with jittered membership tests.
// A textured light's samples are weighed by its texture where their rays
// meet it, as the raster sampler does (texturedIrradiance).
// The occlusion-query scheme has no ray-traced peer (it counts pixels).
#pragma once

#include "DirectLightSampler.h"
#include "core/EmitterTexture.h"

namespace ml {

class EmbreeScene;

class RayTracedLightSampler {
public:
    // `rays` (and its scene) must outlive the sampler. Settings as for the
    // raster sampler; method jittered or regular (InputError for query or a
    // bad value).
    RayTracedLightSampler(const EmbreeScene& rays, const DirectSamplerSettings& settings);

    // As DirectLightSampler::sample, with the same seed semantics (derive
    // it with jitter::seedFor from user seed, vertex, light, pass).
    // trianglesDrawn is 0 (nothing is drawn); frusta as for the raster
    // sampler. Thread-safe: no state changes between calls.
    DirectSample sample(size_t lightIndex, const Vec3& x, const Vec3& n, uint32_t seed) const;

    const DirectSamplerSettings& settings() const { return settings_; }

private:
    const EmbreeScene& rays_;
    DirectSamplerSettings settings_;
    double sceneSize_;
    std::vector<EmitterTexture> emitters_;  // per light
};

}  // namespace ml
