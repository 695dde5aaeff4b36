// Direct irradiance from an area light at a point, sampled by rasterising
// the light and its potential occluders from that point (§4 of Fournier &
// Péroche): every scheme of the paper, selectable, so their accuracy and cost
// can be compared.
#pragma once

#include "cache/DirectSampler.h"  // DirectPhaseTimes
#include "core/Scene.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace ml {

class GlContext;

enum class DirectMethod {
    OcclusionQuery,  // §4.1.1: count unoccluded light pixels, all weighted alike
    Regular,         // §4.1.2: one test at each pixel centre, per-pixel weights (eq. 3)
    Jittered,        // §4.2: N jittered tests per pixel, one bit each (eq. 4-5)
};
DirectMethod parseDirectMethod(const std::string& name);  // "query", "regular", "jittered"
const char* directMethodName(DirectMethod);

// How pixel samples become an irradiance.
enum class DirectEstimator {
    // Σ over visible samples of L·cosθ·dω: the paper's estimator.
    Plain,
    // Exact unoccluded irradiance (Lambert's closed form) minus the sampled
    // occluded part: unbiased like Plain, but exact wherever nothing occludes
    // and with error only along occluder edges. As the light's projection is
    // known exactly, only the occluders are rasterised; which of their
    // jittered samples lie on the light is decided on the CPU. Planar lights
    // only; others fall back to Plain.
    ControlVariate,
};
DirectEstimator parseDirectEstimator(const std::string& name);  // "plain", "cv"
const char* directEstimatorName(DirectEstimator);

struct DirectSamplerSettings {
    DirectMethod method = DirectMethod::Jittered;
    DirectEstimator estimator = DirectEstimator::ControlVariate;
    int imageSize = 64;          // pixels per side of a sampling image, typical 32..64
    // Jittered tests per pixel: 1, 4, 8, 16 or 32. 8 has the lowest error² ×
    // time on the bench (bench direct), what progressive averaging needs.
    int bits = 8;
    double maxHalfAngleDegrees = 60;  // wider lights are split among cube faces
    // The sampling camera sits this far above the shading point, along its
    // normal, as a fraction of the scene's bounding diagonal: 1e-6 is 16× the
    // float rounding of vertex positions, so a receiver never shadows itself.
    // Next to a light the lift is at most 1e-4 of the distance to it, so the
    // lift changes the answer by no more than about 1e-4 there.
    double eyeOffset = 1e-6;
    // Occluder parts closer to a planar light's plane than this (same unit
    // as eyeOffset) do not occlude it: geometry coplanar with the light.
    double planeTolerance = 1e-6;
    bool cullOccluders = true;   // draw only triangles in the frustum (BVH)
    // With the control variate on a planar light (jittered or regular), a
    // pair whose frusta hold no occluder after culling is answered on the
    // CPU, with no GL call: the estimate is then Lambert's closed form, the
    // same value the GPU would return (DirectPath::Unoccluded); and a pair
    // whose light lies wholly behind one occluder polygon is zero, as every
    // sample the GPU would test is occluded (DirectPath::Occluded,
    // OccluderPolygons.h). Needs cullOccluders (culling makes the
    // decision); off: every pair is rasterised, as before (for comparisons).
    bool cpuUnoccludedPairs = true;
    // With cpuUnoccludedPairs, a pair of an analytic light whose frusta
    // hold at most this many occluder triangles with a part in them (and
    // none with a cut-out) has its occluded samples decided on the CPU
    // (CpuCoverage.h), with no GL call: DirectPath::CpuRasterised, 10-100x
    // cheaper than a sampling image on llvmpipe. 0: such pairs are
    // rasterised, the paper's sampler; the default here, so that what
    // tests of the GL path sample stays on it. The commands' default is
    // DirectChoice's (SamplerFactory.h).
    int cpuCoverageTriangles = 0;

    void validate() const;       // throws InputError on a bad value
};

// Which way a sample was answered.
enum class DirectPath {
    // The light is wholly below the receiver's horizon or seen from behind
    // (or edge-on): zero, with no frustum, culling or GL call.
    Unlit,
    // No occluder in any frustum (cpuUnoccludedPairs): Lambert's closed form
    // on the CPU, no GL call.
    Unoccluded,
    // Rasterised with GL: some frustum holds potential occluders, the
    // estimator needs the light itself rasterised (plain, occlusion query,
    // a non-planar light), or cpuUnoccludedPairs is off.
    Rasterised,
    // The light wholly behind one occluder polygon (cpuUnoccludedPairs):
    // zero, no GL call. No sample is tested (lightSamples = 0).
    Occluded,
    // Few occluders (cpuCoverageTriangles): their samples decided on the
    // CPU at the same jittered points, weighed as a rasterised image is.
    CpuRasterised,
};
// "unlit", "unoccluded", "rasterised", "occluded", "cpu-rasterised"
const char* directPathName(DirectPath);

// One estimate; repeats with fresh seeds are independent and their mean
// converges to the exact irradiance.
struct DirectSample {
    Rgb irradiance{0.0};           // W·m⁻² at the point
    double cosineSolidAngle = 0;   // irradiance / radiance: ∫ vis·cosθ dω (sr)
    double unoccluded = 0;         // the same without occluders (sr)
    // Jittered tests that fell on the light, and of those, the ones not
    // occluded. Unoccluded and Occluded pairs test none (they are answered
    // on the CPU): both 0 there, so partiallyVisible() is false and the
    // visible fraction, cosineSolidAngle / unoccluded, is 1 and 0.
    uint32_t lightSamples = 0;
    uint32_t visibleSamples = 0;
    // Sampling images (> 1: light split), rasterised or, where no occluder
    // lies in one, weighed on the CPU alone.
    uint32_t frusta = 0;
    uint32_t trianglesDrawn = 0;   // occluder triangles submitted to GL after culling
    // How it was answered. RayTracedLightSampler does not set it: Rasterised
    // there, unlit pairs included.
    DirectPath path = DirectPath::Rasterised;

    // A penumbra: some but not all of the light's samples are visible.
    bool partiallyVisible() const { return visibleSamples > 0 && visibleSamples < lightSamples; }
};

// How far above a receiver at x the sampling camera sits, along its normal:
// `eyeOffset` × `sceneSize`, so the receiver's own surface never shadows it,
// but at most 1e-4 of the distance to the light (a lower bound of it: box
// and plane distance), so next to a light the lift changes the answer by no
// more than about 1e-4 of it.
double samplingEyeLift(const Light& light, const Vec3& x, double eyeOffset, double sceneSize);

// The irradiance of a textured light (EmitterTexture.h) from one pair's
// sums, shared by the raster and ray-traced samplers. Each sample's weight
// w = cosθ·dω is multiplied by τ = L / L̄ where its ray meets the light:
// `texturedLight` = Σ w·τ over the samples on the light, `texturedOccluded`
// over those occluded (or unbiased estimates of them: the raster sampler
// reads τ at one sample in 16 × bits, its textureCorrection, at the same
// samples for both, so that they cancel where a block is all in shadow;
// reading τ at every occluded sample was 57% of the back rooms' direct
// light, whose ceiling grids are textured and mostly hidden),
// `lightWeight` = Σ w over the samples on the light.
//   plain             L̄ (Σ_light w·τ − Σ_occluded w·τ)
//   control variate   L̄ (U + Σ_light w (τ − 1) − Σ_occluded w·τ), U the
//                     exact unoccluded value (Lambert's form), which assumes
//                     the mean radiance everywhere: the samples on the light
//                     correct it by the texture's departure from its mean.
//                     Unbiased; exact only where the texture is uniform.
//                     Zero when no sample is visible, as for untextured lights.
// Clamped at 0 per channel.
Rgb texturedIrradiance(const Rgb& radiance, bool controlVariate, double exactUnoccluded, double lightWeight,
                       const Rgb& texturedLight, const Rgb& texturedOccluded, bool anyVisible);

class DirectLightSampler {
public:
    // `scene` must outlive the sampler; `context` must be current on the
    // calling thread for construction and every call.
    DirectLightSampler(GlContext& context, const Scene& scene, const DirectSamplerSettings& settings);
    ~DirectLightSampler();
    DirectLightSampler(const DirectLightSampler&) = delete;
    DirectLightSampler& operator=(const DirectLightSampler&) = delete;

    // Direct irradiance of light `lightIndex` at `x` with unit normal `n`.
    // `seed` selects the jitter: derive it from (user seed, vertex, light,
    // pass) with jitter::seedFor so runs repeat bit for bit.
    DirectSample sample(size_t lightIndex, const Vec3& x, const Vec3& n, uint32_t seed);
    // sample() for every request (`mesh` is the light's index), results[i]
    // for requests[i], bit for bit what sample() returns for it. Pairs that
    // need GL have their sampling images drawn into up to 16 targets before
    // the first is read back: a driver that queues draws is waited for once
    // per 16 images. (llvmpipe in Mesa 22.3 rasterises each target when the
    // next is bound, so there the wait only moves from readback to draw:
    // about the same time per pair.) A failure throws SampleBatchError naming the
    // request (the first of those drawn, for a failure in reading back);
    // InputError passes through. lastTimes() then holds the whole batch's.
    void sampleBatch(const std::vector<SampleRequest>& requests, std::vector<DirectSample>& results);

    // sample()'s answer, bit for bit, where it takes microseconds and no
    // GL call: an Unlit, Unoccluded or Occluded pair (DirectPath); false,
    // `out` untouched, otherwise. (A CpuRasterised pair takes no GL call
    // either, but weighs a sampling image: it is left to sample() and
    // sampleBatch(), after the cheap pairs, as rasterised pairs are.)
    // Makes no GL call, but like sample() needs the context current.
    bool sampleWithoutGl(size_t lightIndex, const Vec3& x, const Vec3& n, uint32_t seed, DirectSample& out);

    const DirectSamplerSettings& settings() const;
    // With phase timing on, the sampler waits for the GPU between phases
    // (glFinish) so each phase is timed alone; slightly slower overall.
    void setPhaseTiming(bool on);
    // The last sample's (or batch's) phases; an Unlit or Unoccluded pair's whole time is
    // setup (it has no draw, readback or weighting).
    const DirectPhaseTimes& lastTimes() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ml
