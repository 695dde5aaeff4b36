// The propagation volume's steps as a GL compute shader (propagate_step.comp),
// to measure whether the GPU path beats the CPU loops on this machine's GL
// (llvmpipe: the same 2 cores), and to check that both compute the same thing.
// `bench indirect` times both on the same injected light; the estimator
// itself (PropagationVolume) propagates on the CPU, which the bench found
// faster here.
#pragma once

#include "core/SphericalHarmonics.h"
#include "gpu_sampling/indirect/PropagationVolume.h"

#include <array>
#include <memory>
#include <vector>

namespace ml {

class GlContext;

class PropagationCompute {
public:
    // The volume's grid, geometry volume (unless its occlusion is off) and
    // the transfer, uploaded once; `context` must be current on this
    // thread and outlive this object.
    PropagationCompute(GlContext& context, const PropagationVolume& volume);
    ~PropagationCompute();

    struct Result {
        // Per side (PropagationVolume::absorbed), per cell: the flux absorbed.
        std::array<std::vector<Rgb>, 6> absorbed;
        double uploadSeconds = 0;     // the injected field to the GPU
        double propagateSeconds = 0;  // the steps' dispatches, to glFinish
        double readbackSeconds = 0;   // the tallies back
    };
    // `steps` steps from `injected` (one field per cell), in float.
    Result propagate(const std::vector<ShRgb>& injected, int steps);

private:
    struct Gpu;
    GlContext& context_;
    PropagationGrid grid_;
    std::unique_ptr<Gpu> gpu_;
};

}  // namespace ml
