// The direct-light options shared by `render` and `probe`, read in one place,
// and the estimator they select: the GPU sampler or the exact reference.
#pragma once

#include "Options.h"
#include "cache/CacheWorker.h"
#include "cache/IrradianceCache.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/gl/GlContext.h"

#include <memory>
#include <string>

namespace ml {

class ExactDirect;

struct DirectChoice {
    bool exact = false;                 // --method exact: closed form, CPU
    DirectSamplerSettings sampler;      // otherwise the GPU scheme
    int passes = 1;                     // estimates averaged per point
    uint32_t seed = 1;
    GlBackend backend = GlBackend::Auto;

    std::string describe() const;       // "jittered 64x64, 4 bits/pixel, cv estimator, 1 pass"
};

void declareDirectOptions(Options& options);
DirectChoice readDirectOptions(const Options& options);

// Owns what the chosen estimator needs (GL context and sampler, or the exact
// reference) and exposes it as a DirectEstimateFn.
class DirectEstimators {
public:
    // Creates the GL context when `glNeeded` or the method is not exact.
    DirectEstimators(const Scene& scene, const DirectChoice& choice, bool glNeeded);
    ~DirectEstimators();

    DirectEstimateFn estimate();
    // The same estimates with what the sampler saw of the light (visible
    // fraction, penumbra), for the cache's refinement.
    DirectSampleFn sample();
    GlContext* context() const { return context_.get(); }
    // Seconds spent per phase over every call so far (GPU methods).
    const DirectPhaseTimes& totals() const { return totals_; }

    VertexSample sampleOne(size_t light, const Vec3& x, const Vec3& n, uint32_t seed);

private:

    const Scene& scene_;
    DirectChoice choice_;
    std::unique_ptr<GlContext> context_;
    std::unique_ptr<DirectLightSampler> sampler_;
    std::unique_ptr<ExactDirect> exact_;
    DirectPhaseTimes totals_;
};

// Makes, on the thread that calls it (the cache worker), a GL context and
// sampler of its own, or the exact reference, and returns its estimates.
// Phase times are added to `totals` on that thread; read them after the
// worker has been joined.
CacheWorker::SamplerFactory directSamplerFactory(const Scene& scene, const DirectChoice& choice,
                                                 std::shared_ptr<DirectPhaseTimes> totals);

}  // namespace ml
