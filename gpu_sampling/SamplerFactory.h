// The wiring between the cache and the samplers: which direct sampler and
// which indirect gather a run uses (DirectChoice, IndirectChoice, read from
// the command line by viewer/cli), and the factories that make them on the
// thread that will use them.
//
// GL contexts. A headless context belongs to the thread that made it
// (Filament's driver-thread rule; destroying an OSMesa context elsewhere
// unbinds the calling thread's current context). So each sampling thread
// calls the factory itself (CacheWorker, SamplerPool): the direct sampler
// and the indirect gather each make and own a context on that thread,
// switched with GlContext::use() as they alternate, and die there. Two
// contexts, not one shared: no GL state one pass leaves can reach the
// other, so a sample's result never depends on what the thread did before
// (a batch spread over any number of threads repeats bit for bit).
#pragma once

#include "cache/CacheWorker.h"
#include "cache/DirectSampler.h"
#include "cache/IndirectEstimator.h"
#include "cache/IndirectSolver.h"
#include "cache/RealtimeIndirect.h"
#include "core/raytrace/BounceCount.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/indirect/GatherSettings.h"
#include "gpu_sampling/indirect/IrradianceVolume.h"
#include "gpu_sampling/indirect/PropagationVolume.h"
#include "gpu_sampling/indirect/VirtualPointLights.h"

#include <memory>
#include <string>
#include <vector>

namespace ml {

class GlContext;
enum class GlBackend;

// How direct light is sampled.
struct DirectChoice {
    bool exact = false;                 // --method exact: closed form, CPU
    DirectSamplerSettings sampler = commandSampler();  // otherwise the GPU scheme
    int passes = 1;                     // estimates averaged per point (probe)
    uint32_t seed = 1;
    GlBackend backend{};                // GlBackend::Auto

    std::string describe() const;       // "jittered 64x64, 8 bits/pixel, cv estimator, 1 pass"

    // The commands' sampler: DirectSamplerSettings' defaults, with pairs
    // of up to kCpuCoverageTriangles occluder triangles decided on the CPU
    // (--cpu-coverage).
    static constexpr int kCpuCoverageTriangles = 64;
    static DirectSamplerSettings commandSampler();
};

// How indirect light is gathered, and how many bounces.
struct IndirectChoice {
    bool enabled = true;               // false with --direct-only
    // The gather: one of indirectMethodNames(), or "auto", which decide()
    // replaces by the one the scene calls for (methodReason says why).
    std::string method = "auto";
    std::string methodReason;          // filled by decide(): "as asked (--indirect-method)" or why auto chose
    GatherSettings gather;
    IrradianceVolumeSettings volume;   // method "volume": the probe grid (--probes, --probe-face)
    PropagationVolumeSettings lpv;     // method "lpv": the propagation grid (--lpv-cells)
    VirtualPointLightSettings vpl;     // method "vpl": virtual point lights (--vpls)
    BounceCountSettings bounces;
    // Area lights dimmer than this fraction of the brightest one's radiance
    // are gathered by bounce 1 rather than sampled (GatheredLights.h), with
    // the ray gather only; 0: none (--glow-ratio).
    double glowRatio = 0.02;
    // The bounce meshes' base edges, at most this fraction of the scene's
    // diagonal; 0: chosen by decide() (the ray gather: the mean free path
    // over kFreePathsPerBase; the voxel gathers: 1/8) (--indirect-edge).
    double baseEdge = 0;
    // --gather-size was given: decide() keeps its rays (else the ray gather's
    // rays follow the base edge it chooses).
    bool gatherSizeSet = false;
    // The ray gather's base edge, when not asked, is the mean free path
    // (Scene::meanFreePath) over this, within 1/16..1/32 of the diagonal:
    // 1/32 with 100 rays in the office of bench lights (2.8% at 60 s,
    // against 3.3% at 1/22 with 225 rays and 3.9% at 1/16 with 400), 1/20
    // with 240 rays in the Cornell box (0.80% at 30 s against 0.83% at 1/16
    // with 400); cache/README.md.
    static constexpr double kFreePathsPerBase = 7.5;
    std::string baseReason;            // filled by decide(): how the bounce meshes' base edge was chosen
    std::string gatheredReason;        // filled by decide(): which lights are gathered and why, or why none
    IndirectSettings solver;           // bounces, albedo and gathered lights come from decide()
    BounceCount bounceCount;            // filled by decide()

    // Decides the bounce count from the scene (or --bounces) and fills
    // `solver` with it; resolves method "auto" (chooseIndirectMethod).
    void decide(const Scene& scene);
    // Some bounce is to be gathered.
    bool active() const { return enabled && solver.bounces > 0; }
    // This choice with "auto" resolved (what decide() does to the method),
    // for the factories given a choice that was never decided.
    IndirectChoice resolved(const Scene& scene) const;
    std::string describe() const;      // "slices: 40x40 fish-eye gathers over 64 voxels ..."
};

// What an image shows of indirect light (cache/RealtimeIndirect.h): the
// cache, with a real-time method standing in while its bounces are gathered
// (after a light or an object moved, and at the start), or one method's
// estimate alone, live.
struct RealtimeChoice {
    // The stand-in while the cache catches up: one of realtimeMethodNames(),
    // "auto" (the one with the least error on the scene's first complete
    // cache among those fast enough: RealtimeIndirect, chooseStandIn), or
    // "off" (the cache's own display: its old bounces after a change).
    // Auto by measurement: no one method is best on every scene (bench
    // dynamic's table of the methods: vpl on the Cornell box, volume on the
    // office; viewer/README.md).
    std::string realtime = "auto";
    // "cache", or a method shown live whatever the cache holds.
    std::string display = "cache";
    // Bounces the method estimates, the rest following as a tail (0: all;
    // RealtimeSettings::kBouncesFromScene: standInBounces).
    int methodBounces = RealtimeSettings::kBouncesFromScene;
    // InputError for an unknown name (the options' words in the message).
    void validate() const;
    // --realtime-bounces: "auto" (from the scene) or a count, 0 for all.
    static int parseBounces(const std::string& text);
    static constexpr const char* kBouncesHelp =
        "bounces the real-time method estimates, later ones following as a tail: auto (until the rest carry at most "
        "a sixth of the light, by the scene's albedo), or a count, 0 for all";
    std::string bouncesText() const;
    // For RealtimeIndirect: the displayed method if live, else the stand-in.
    RealtimeSettings settings(uint32_t seed) const;
    std::string describe() const;  // "volume stands in while the cache catches up", "vpl, live"
};

// "volume", "vpl", "lpv": the methods that can stand in for the cache.
const std::vector<std::string>& realtimeMethodNames();

// Makes those methods' estimators with `indirect`'s settings (--probes,
// --vpls, --lpv-cells) for RealtimeIndirect.
RealtimeIndirect::EstimatorFactory realtimeEstimatorFactory(const IndirectChoice& indirect);

// "slices" (the paper's), "raytrace" (consistent), "volume" (the irradiance
// volume of SH probes), "lpv" (voxel light propagation with occlusion),
// "vpl" (virtual point lights with negative lights for their occlusion), and
// the comparisons of `bench indirect`.
std::vector<std::string> indirectMethodNames();

// The gather "auto" stands for, and why: the ray gather (RayGather.h),
// whose mean is the exact one-bounce irradiance of the cached radiance, so
// refinement converges to the right answer; the proxy gathers (slices,
// hemicube, ...) stop at their voxels' bias (bench indirect: 4-10% against
// the path tracer on the Cornell box's blocks and corners, where the ray
// gather is at the path tracer's noise). On a software rasteriser the ray
// gather is also the cheaper (0.5 ms for 400 rays against 1.1 ms for a
// 40×40 slice gather, bench indirect --quick); rays cost log(triangles),
// so a scene of many triangles does not change the choice.
std::string chooseIndirectMethod(const Scene& scene, std::string& reason);

// The direct sampler a DirectChoice names: the GPU light sampler on a
// headless GL context of its own, or the exact closed form. Use and destroy
// it on the thread that made it.
class ConfiguredDirectSampler final : public DirectSampler {
public:
    ConfiguredDirectSampler(const Scene& scene, const DirectChoice& choice);
    ~ConfiguredDirectSampler() override;

    std::string name() const override;
    // Visibility is the visible fraction of the light's cosine-weighted
    // solid angle (1 where the point sees none of the light: no shadow
    // boundary passes there).
    VertexSample sample(size_t light, const Vec3& x, const Vec3& n, uint32_t seed) override;
    // Every request at once: CPU and unlit pairs answered at once, the
    // others' images drawn several at a time (DirectLightSampler::sampleBatch).
    void sampleBatch(const std::vector<SampleRequest>& requests, std::vector<VertexSample>& results) override;
    // Unlit and unoccluded pairs (DirectLightSampler::sampleWithoutGl);
    // none with the exact method.
    bool sampleWithoutGpu(size_t light, const Vec3& x, const Vec3& n, uint32_t seed, VertexSample& out) override;
    DirectPhaseTimes phaseTimes() const override;
    // The context it draws with; null for the exact method.
    GlContext* context() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The estimators that draw nothing, on the CPU: "raytrace", "volume",
// "lpv" and "vpl" (null for the others, which need a GL context). Any
// thread may make and use one (the real-time stand-in makes them on its own).
std::unique_ptr<IndirectEstimator> makeCpuIndirectEstimator(const Scene& scene, const IndirectChoice& choice);

// The gather `choice.method` names, drawing with `context` (current on this
// thread for the estimator's lifetime).
std::unique_ptr<IndirectEstimator> makeIndirectEstimator(GlContext& context, const Scene& scene,
                                                         const IndirectChoice& choice);

// For the cache worker and each thread of its SamplerPool: on the calling
// thread, a ConfiguredDirectSampler and, if indirect light is active, the
// chosen gather on a context of its own. `scene` must outlive every worker
// the factory serves.
SamplerFactory samplerFactory(const Scene& scene, const DirectChoice& direct, const IndirectChoice& indirect);

}  // namespace ml
