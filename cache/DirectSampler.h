// What the cache needs from a method that estimates direct irradiance: the
// GPU light sampler (gpu_sampling/direct), its ray-traced peer, or the exact
// closed form. The cache and its worker see only this interface; the
// implementations and the factories that pick one live in gpu_sampling/
// (SamplerFactory.h).
#pragma once

#include "VertexSampler.h"

#include <string>

namespace ml {

// Wall-clock seconds per phase of direct sampling (the paper's Fig. 9).
struct DirectPhaseTimes {
    double setup = 0;      // frusta, culling, uniforms (CPU)
    double draw = 0;       // light and occluders (GPU, up to glFinish)
    double readback = 0;   // glReadPixels / query results
    double weighting = 0;  // per-sample weights (CPU)
    double total() const { return setup + draw + readback + weighting; }
    DirectPhaseTimes& operator+=(const DirectPhaseTimes& o) {
        setup += o.setup;
        draw += o.draw;
        readback += o.readback;
        weighting += o.weighting;
        return *this;
    }
};

// sample(light, x, n, seed): light `light`'s direct irradiance at x, with the
// visible fraction of its cosine-weighted solid angle and whether the point
// is in its penumbra.
class DirectSampler : public VertexSampler {
public:
    // "jittered 64x64, 8 bits/pixel, cv estimator" or "exact (...)".
    virtual std::string name() const = 0;
    // Seconds per phase over every sample so far (zero where not measured).
    virtual DirectPhaseTimes phaseTimes() const { return {}; }
};

}  // namespace ml
