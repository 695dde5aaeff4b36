// Direct light for the cache meshes when lights share (LightCoverage.h):
// mesh l < L holds w_l·E_l, mesh L (the shared one) Σ_l (1 − w_l)·E_l.
//
// The shared mesh's estimator is a control variate, like the light
// sampler's own: with U_l the unoccluded irradiance of light l at the point
// (Lambert's closed form, exact) and O_l = U_l − E_l its occluded part,
//   Σ (1 − w_l) E_l = Σ (1 − w_l) U_l − Σ (1 − w_l) O_l,
// where the first sum is computed exactly and the second estimated from K
// lights drawn with probability p_l ∝ (1 − w_l) U_l, each O_l from the
// wrapped sampler (O_l = U_l − its estimate of E_l): unbiased, and exact
// wherever nothing occludes the drawn lights (the sampler answers those on
// the CPU, exactly U_l). Noise comes only from occlusion, where refinement
// resamples it away.
//
// A textured light (EmitterTexture.h): U_l is still Lambert's form at the
// light's mean radiance, now only a control for the textured E_l the wrapped
// sampler estimates, so O_l = U_l − E_l may be negative (the point sees the
// light's brighter part) and is not clamped; such a light's shared estimate
// is unbiased but no longer exact where nothing occludes.
#pragma once

#include "DirectSampler.h"
#include "LightCoverage.h"

#include <memory>

namespace ml {

class SharedLightSampler final : public DirectSampler {
public:
    // `lights`: K, the lights drawn per shared estimate (typical 4).
    SharedLightSampler(const Scene& scene, std::shared_ptr<const LightCoverage> coverage,
                       std::unique_ptr<DirectSampler> perLight, int lights = 4);

    std::string name() const override;
    VertexSample sample(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed) override;
    // Where the wrapped sampler answers every pair it needs without the GPU
    // (for the shared mesh: every light drawn).
    bool sampleWithoutGpu(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed, VertexSample& out) override;
    DirectPhaseTimes phaseTimes() const override { return perLight_->phaseTimes(); }

private:
    // The estimate of mesh `mesh`, each light's sample from
    // `take(light, seed, sample)`, which may decline (false): then false.
    template <class Take>
    bool estimate(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed, Take take, VertexSample& out);
    template <class Take>
    bool estimateShared(const Vec3& x, const Vec3& n, uint32_t seed, Take take, VertexSample& out);

    const Scene& scene_;
    std::shared_ptr<const LightCoverage> coverage_;
    std::unique_ptr<DirectSampler> perLight_;
    int draws_;
    std::vector<std::pair<uint32_t, double>> weights_;  // scratch
    std::vector<double> cdf_;
    std::vector<Rgb> unoccluded_;  // U_l of each candidate
    std::vector<double> shared_;   // 1 − w_l of each candidate
    std::vector<uint32_t> candidates_;
    std::vector<bool> textured_;   // per light: its emission has a texture (EmitterTexture)
};

// U_l at x: light l's irradiance with nothing in the way, from the light's
// triangles whose emitting side faces x, Lambert's formula at x itself (as
// the light sampler's control variate computes it).
Rgb unoccludedIrradiance(const Light& light, const Vec3& x, const Vec3& n);

}  // namespace ml
