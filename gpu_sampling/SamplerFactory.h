// The wiring between the cache and the samplers: which direct sampler and
// which indirect gather a run uses (DirectChoice, IndirectChoice, read from
// the command line by viewer/cli), and the factories that make them on the
// thread that will use them.
//
// GL contexts. A headless context belongs to the thread that made it
// (Filament's driver-thread rule; destroying an OSMesa context elsewhere
// unbinds the calling thread's current context). So the cache worker calls
// samplerFactory() on its own thread: the direct sampler makes and owns the
// context, the indirect gather draws with that same context, and both are
// destroyed on that thread, the gather first (WorkerSamplers).
#pragma once

#include "cache/CacheWorker.h"
#include "cache/DirectSampler.h"
#include "cache/IndirectEstimator.h"
#include "cache/IndirectSolver.h"
#include "core/raytrace/BounceCount.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/indirect/GatherSettings.h"

#include <memory>
#include <string>
#include <vector>

namespace ml {

class GlContext;
enum class GlBackend;

// How direct light is sampled.
struct DirectChoice {
    bool exact = false;                 // --method exact: closed form, CPU
    DirectSamplerSettings sampler;      // otherwise the GPU scheme
    int passes = 1;                     // estimates averaged per point (probe)
    uint32_t seed = 1;
    GlBackend backend{};                // GlBackend::Auto

    std::string describe() const;       // "jittered 64x64, 8 bits/pixel, cv estimator, 1 pass"
};

// How indirect light is gathered, and how many bounces.
struct IndirectChoice {
    bool enabled = true;               // false with --direct-only
    std::string method = "slices";     // the gather: see indirectMethodNames()
    GatherSettings gather;
    BounceCountSettings bounces;
    IndirectSettings solver;           // bounces and albedo come from decide()
    BounceCount bounceCount;            // filled by decide()

    // Decides the bounce count from the scene (or --bounces) and fills
    // `solver` with it.
    void decide(const Scene& scene);
    // Some bounce is to be gathered.
    bool active() const { return enabled && solver.bounces > 0; }
    std::string describe() const;      // "slices: 40x40 fish-eye gathers over 64 voxels ..."
};

// "slices" (the paper's), and the comparisons of `bench indirect`.
std::vector<std::string> indirectMethodNames();

// The direct sampler a DirectChoice names: the GPU light sampler on a
// headless GL context of its own, made current on the calling thread, or the
// exact closed form (with a context too when `needContext`, for a gather to
// share). Use and destroy it on the thread that made it.
class ConfiguredDirectSampler final : public DirectSampler {
public:
    ConfiguredDirectSampler(const Scene& scene, const DirectChoice& choice, bool needContext = false);
    ~ConfiguredDirectSampler() override;

    std::string name() const override;
    // Visibility is the visible fraction of the light's cosine-weighted
    // solid angle (1 where the point sees none of the light: no shadow
    // boundary passes there).
    VertexSample sample(size_t light, const Vec3& x, const Vec3& n, uint32_t seed) override;
    DirectPhaseTimes phaseTimes() const override;
    // The context it draws with; null for the exact method without one.
    GlContext* context() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The gather `choice.method` names, drawing with `context` (current on this
// thread for the estimator's lifetime).
std::unique_ptr<IndirectEstimator> makeIndirectEstimator(GlContext& context, const Scene& scene,
                                                         const IndirectChoice& choice);

// For the cache worker: on its thread, a ConfiguredDirectSampler and, if
// indirect light is active, the chosen gather on the same context. `scene`
// must outlive every worker the factory serves.
SamplerFactory samplerFactory(const Scene& scene, const DirectChoice& direct, const IndirectChoice& indirect);

}  // namespace ml
