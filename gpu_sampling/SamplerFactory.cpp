#include "SamplerFactory.h"

#include "core/Error.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PunctualShadow.h"
#include "core/reference/ExactIrradiance.h"
#include "cache/GatheredLights.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/indirect/IrradianceVolume.h"
#include "gpu_sampling/indirect/PropagationVolume.h"
#include "gpu_sampling/indirect/RayGather.h"
#include "gpu_sampling/indirect/SliceGather.h"
#include "gpu_sampling/indirect/TriangleGather.h"
#include "gpu_sampling/indirect/VirtualPointLights.h"
#include "gpu_sampling/indirect/VoxelMarchGather.h"

#include <algorithm>
#include <thread>

namespace ml {

namespace {

// --gather-size N: N² pixels for the image gathers, N²/4 rays for the ray
// gather (40 → 400: about the error of a 40×40 fish-eye on the walls).
RayGatherSettings rayGatherSettings(const IndirectChoice& choice) {
    RayGatherSettings r;
    r.rays = std::max(4, choice.gather.imageSize * choice.gather.imageSize / 4);
    r.gatheredLights = choice.solver.gatheredLights;
    return r;
}

}  // namespace

// --- Choices -----------------------------------------------------------------

DirectSamplerSettings DirectChoice::commandSampler() {
    DirectSamplerSettings s;
    s.cpuCoverageTriangles = kCpuCoverageTriangles;
    return s;
}

std::string DirectChoice::describe() const {
    if (exact) return "exact (visible light polygon from CGAL, Lambert's closed form)";
    const bool jittered = sampler.method == DirectMethod::Jittered;
    return concat(directMethodName(sampler.method), " ", sampler.imageSize, "x", sampler.imageSize,
                  jittered ? concat(", ", sampler.bits, " bits/pixel") : std::string(),
                  sampler.method == DirectMethod::OcclusionQuery ? std::string()
                                                                 : concat(", ", directEstimatorName(sampler.estimator), " estimator"),
                  ", ", passes, passes == 1 ? " pass" : " passes",
                  sampler.cpuCoverageTriangles > 0 && sampler.estimator == DirectEstimator::ControlVariate &&
                          sampler.method != DirectMethod::OcclusionQuery
                      ? concat(", up to ", sampler.cpuCoverageTriangles, " occluder triangles on the CPU")
                      : std::string());
}

std::vector<std::string> indirectMethodNames() {
    return {"slices", "slice-quads", "raymarch", "fisheye-triangles", "perspective", "hemicube", "raytrace", "volume", "lpv", "vpl"};
}

std::string chooseIndirectMethod(const Scene& scene, std::string& reason) {
    reason = concat("auto: the ray gather is consistent (its mean is the exact one-bounce irradiance of what the "
                    "cache holds, so resampling converges to it), where the voxel gathers keep a bias of a voxel; "
                    "rays cost the log of the scene's ", scene.triangleCount(), " triangles");
    // Only rays follow mirrors and glass to the surfaces behind them.
    if (std::any_of(scene.materials.begin(), scene.materials.end(), [](const Material& m) { return m.specular(); }))
        reason += "; its rays follow the scene's mirrors and glass to what they show (the proxy gathers see only "
                  "their Kd)";
    return "raytrace";
}

IndirectChoice IndirectChoice::resolved(const Scene& scene) const {
    IndirectChoice c = *this;
    if (c.method == "auto") c.method = chooseIndirectMethod(scene, c.methodReason);
    return c;
}

void IndirectChoice::decide(const Scene& scene) {
    if (method == "auto") method = chooseIndirectMethod(scene, methodReason);
    else if (methodReason.empty()) methodReason = "as asked (--indirect-method)";
    if (method != "raytrace" &&
        std::any_of(scene.materials.begin(), scene.materials.end(), [](const Material& m) { return m.specular(); }))
        methodReason += concat("; ", method, " sees mirrors and glass as their Kd alone: light reflected through "
                               "them is left out of indirect light (raytrace follows it)");
    if (method == "raytrace") {
        // The voxel gathers see the scene at their voxels, so finer indirect
        // meshes would only resolve the voxels' steps (1/8 and 1/64 of the
        // scene); the ray gather sees it exactly, and a base edge of 1/8
        // interpolates a room's ceiling, concave in indirect light, 3-5% too
        // dark: 1/16 and 1/128.
        solver.cache.maxEdgeFraction = 1.0 / 16;
        solver.cache.minEdgeFraction = 1.0 / 128;
    }
    // A finer base resolves a large room's indirect light, which falls
    // towards its corners and which noisy gathers never split for (the
    // office of bench lights: 1/32 with 196 rays, 2.4% against 3.8% at 60 s;
    // cache/README.md); refinement may then split down to the finer of the
    // gather's least edge and an eighth of the base.
    double base = baseEdge;
    baseReason = base > 0 ? "as asked (--indirect-edge)" : "the gather's own";
    if (base == 0 && method == "raytrace") {
        const double diagonal = scene.bounds.diagonal(), path = scene.meanFreePath();
        const double ratio = diagonal > 0 ? path / diagonal : 0;
        // Indirect light curves over the distance between surfaces: the
        // mean free path 4V/S, 0.23 of the diagonal in the office, 0.37 in
        // the Cornell box. The base is that over kFreePathsPerBase, within
        // 1/16..1/32 (the ray gather's least edge is 1/128); the rays
        // shrink as the vertices grow, so that a bounce's first pass costs
        // what it does at 1/16 with 400 rays (at least 100 rays).
        base = std::clamp(ratio / kFreePathsPerBase, 1.0 / 32, 1.0 / 16);
        baseReason = concat("the mean free path 4V/S over ", kFreePathsPerBase, ", 4V/S being ",
                            std::lround(ratio * 1000) / 1000.0, " of the diagonal; within 1/16..1/32");
        if (!gatherSizeSet && base < 1.0 / 16) {
            const double shrink = base * 16;
            // From the default, not the current size: decide() may run twice.
            gather.imageSize = std::max(20, int(std::lround(GatherSettings().imageSize * shrink)));
            baseReason += concat("; ", rayGatherSettings(*this).rays,
                                 " rays per gather, fewer as the vertices are more (--gather-size keeps them)");
        }
    }
    if (base > 0) {
        solver.cache.maxEdgeFraction = base;
        solver.cache.minEdgeFraction = std::min(solver.cache.minEdgeFraction, base / 8);
    }
    bounceCount = countBounces(scene, bounces);
    solver.bounces = enabled ? bounceCount.bounces : 0;
    solver.albedo = bounceCount.meanAlbedo;
    // The bounces not gathered yet, in the image, each this times the one
    // before: the ratio measured by rays where some surface is lit (it sees
    // light leave an open room), else the area-weighted albedo.
    solver.tailAlbedo = bounceCount.bounceRatio > 0 ? bounceCount.bounceRatio : bounceCount.areaAlbedo;
    // Dim, broad emitters come through bounce 1's rays, which read emission
    // where they land (GatheredLights.h); the proxy gathers read none.
    solver.gatheredLights.clear();
    gatheredReason = solver.bounces > 0 ? "every light is sampled directly (the proxy gathers read no emission)"
                                        : "every light is sampled directly (no indirect light)";
    if (solver.bounces > 0 && method == "raytrace") {
        GatheredLights g = chooseGatheredLights(scene, glowRatio);
        solver.gatheredLights = std::move(g.gathered);
        gatheredReason = std::move(g.reason);
    }
    solver.validate();
}

std::string IndirectChoice::describe() const {
    if (method == "auto") return "auto (chosen from the scene when it is known)";
    if (method == "slices" || method == "slice-quads" || method == "raymarch")
        return concat(method, ": ", gather.imageSize, "x", gather.imageSize, " fish-eye gathers over ", gather.resolution,
                      " voxels along the longest side (slices ", gather.sliceSupersample,
                      "x supersampled), and the proxy's triangles near the point (",
                      gather.nearVoxels == 0 ? std::string("its own voxel")
                                             : concat("its voxel and ", gather.nearVoxels, " more each way"),
                      ")");
    if (method == "raytrace")
        return concat("raytrace: ", rayGatherSettings(*this).rays,
                      " stratified cosine-weighted rays (Embree) per gather, reading the cache meshes' radiance where "
                      "they land (consistent: no proxy)");
    if (method == "volume")
        return concat("volume: order-2 SH probes, ", volume.probes, " along the scene's longest side, each from ",
                      6 * volume.faceSize * volume.faceSize, " cube-map rays (Embree) reading the cache; 8 probes "
                      "blended per point", volume.visibility ? ", weighted by a ray test to each" : "",
                      volume.skipInside ? ", those inside objects left out" : "");
    if (method == "lpv")
        return concat("lpv: the source injected as virtual point lights into ", lpv.cells,
                      " cells along the scene's longest side (order-2 SH), propagated to neighbours",
                      lpv.occlusion ? " through a geometry volume of occlusion" : " without occlusion", ", ",
                      lpv.iterations > 0 ? concat(lpv.iterations, " steps") : std::string("steps across the grid"));
    if (method == "vpl")
        return concat("vpl: ", vpl.lights, " virtual point lights placed by a Halton sequence over the source's "
                      "reflected power", vpl.visibility ? concat(", ", std::lround(vpl.negativeShare * vpl.lights),
                                                                 " negative lights for their occlusion")
                                                          : std::string(", no visibility"),
                      vpl.nearRays > 0 ? concat(", the clamp near a point compensated by ", vpl.nearRays,
                                                " rays (Embree) reading the cache")
                                       : std::string());
    return concat(method, ": the radiance proxy's triangles (", gather.resolution,
                  " voxels along the longest side set its size), gathered at image size ", gather.imageSize);
}

// --- The direct sampler ----------------------------------------------------------

struct ConfiguredDirectSampler::Impl {
    const Scene& scene;
    DirectChoice choice;
    std::unique_ptr<GlContext> context;
    std::unique_ptr<DirectLightSampler> sampler;
    std::unique_ptr<ExactDirect> exact;
    // Punctual lights' shadow rays, whatever the method (PunctualShadow.h):
    // made only when the scene has such a light.
    std::unique_ptr<EmbreeScene> rays;
    DirectPhaseTimes totals;
    Impl(const Scene& s, const DirectChoice& c) : scene(s), choice(c) {
        for (const Light& l : s.lights)
            if (l.punctual()) {
                rays = std::make_unique<EmbreeScene>(s);
                break;
            }
    }
    bool punctual(size_t light) const { return scene.lights[light].punctual(); }
    // One shadow ray: exact, so every method answers a punctual light alike.
    VertexSample samplePunctual(size_t light, const Vec3& x, const Vec3& n) const {
        const PunctualSample p = punctualIrradiance(*rays, light, x, n);
        // Visibility 1 where the light does not reach x at all (no shadow
        // boundary passes there), as for area lights.
        return {p.irradiance, p.lit && !p.visible ? 0.0 : 1.0, false};
    }
};

ConfiguredDirectSampler::ConfiguredDirectSampler(const Scene& scene, const DirectChoice& choice)
    : impl_(std::make_unique<Impl>(scene, choice)) {
    if (choice.exact) impl_->exact = std::make_unique<ExactDirect>(scene);
    else impl_->context = createHeadlessContext(choice.backend);
    if (!choice.exact) impl_->sampler = std::make_unique<DirectLightSampler>(*impl_->context, scene, choice.sampler);
}

ConfiguredDirectSampler::~ConfiguredDirectSampler() {
    if (impl_->context) impl_->context->use();  // the sampler's GL objects go while their context is current
}

std::string ConfiguredDirectSampler::name() const { return impl_->choice.describe(); }
DirectPhaseTimes ConfiguredDirectSampler::phaseTimes() const { return impl_->totals; }
GlContext* ConfiguredDirectSampler::context() const { return impl_->context.get(); }

namespace {

// The visible fraction of the light's cosine-weighted solid angle: 1 where
// the point sees none of the light (no shadow boundary passes there).
double visibleFraction(double visible, double unoccluded) {
    return unoccluded > 0 ? std::clamp(visible / unoccluded, 0.0, 1.0) : 1.0;
}

VertexSample vertexSample(const DirectSample& s) {
    return {s.irradiance, visibleFraction(s.cosineSolidAngle, s.unoccluded), s.partiallyVisible()};
}

}  // namespace

VertexSample ConfiguredDirectSampler::sample(size_t light, const Vec3& x, const Vec3& n, uint32_t seed) {
    if (impl_->punctual(light)) return impl_->samplePunctual(light, x, n);
    if (impl_->exact) {
        const double unoccluded = impl_->exact->unoccludedCosineSolidAngle(light, x, n);
        const double visible = impl_->exact->cosineSolidAngle(light, x, n);
        const double v = visibleFraction(visible, unoccluded);
        return {visible * impl_->scene.lights[light].radiance, v, v > 1e-9 && v < 1 - 1e-9};
    }
    impl_->context->use();
    const DirectSample s = impl_->sampler->sample(light, x, n, seed);
    impl_->totals += impl_->sampler->lastTimes();
    return vertexSample(s);
}

bool ConfiguredDirectSampler::sampleWithoutGpu(size_t light, const Vec3& x, const Vec3& n, uint32_t seed,
                                               VertexSample& out) {
    if (impl_->punctual(light)) {
        out = impl_->samplePunctual(light, x, n);
        return true;
    }
    if (impl_->exact) return false;  // every pair costs CGAL's exact visibility
    impl_->context->use();
    DirectSample s;
    const bool answered = impl_->sampler->sampleWithoutGl(light, x, n, seed, s);
    impl_->totals += impl_->sampler->lastTimes();
    if (answered) out = vertexSample(s);
    return answered;
}

void ConfiguredDirectSampler::sampleBatch(const std::vector<SampleRequest>& requests,
                                          std::vector<VertexSample>& results) {
    if (impl_->exact) {
        DirectSampler::sampleBatch(requests, results);
        return;
    }
    // The GPU sampler answers CPU and unlit pairs at once and draws the
    // others' images several at a time (DirectLightSampler::sampleBatch).
    // Punctual lights' pairs take their shadow ray here; the rest go to the
    // GPU sampler together.
    results.resize(requests.size());
    std::vector<SampleRequest> area;
    std::vector<size_t> areaIndex;
    for (size_t i = 0; i < requests.size(); ++i) {
        const SampleRequest& r = requests[i];
        if (impl_->punctual(r.mesh))
            asBatchRequest(i, [&] { results[i] = impl_->samplePunctual(r.mesh, r.x, r.n); });
        else {
            area.push_back(r);
            areaIndex.push_back(i);
        }
    }
    if (area.empty()) return;
    impl_->context->use();
    std::vector<DirectSample> samples;
    try {
        impl_->sampler->sampleBatch(area, samples);
    } catch (const SampleBatchError& e) {
        throw SampleBatchError(areaIndex[e.index()], e.what());
    }
    impl_->totals += impl_->sampler->lastTimes();
    for (size_t k = 0; k < area.size(); ++k) results[areaIndex[k]] = vertexSample(samples[k]);
}

// --- The indirect gather -----------------------------------------------------------

std::unique_ptr<IndirectEstimator> makeCpuIndirectEstimator(const Scene& scene, const IndirectChoice& given) {
    const IndirectChoice choice = given.resolved(scene);
    if (choice.method == "raytrace") return std::make_unique<RayGather>(scene, rayGatherSettings(choice));
    if (choice.method == "volume") return std::make_unique<IrradianceVolume>(scene, choice.volume);
    if (choice.method == "lpv") return std::make_unique<PropagationVolume>(scene, choice.lpv);
    if (choice.method == "vpl") return std::make_unique<VirtualPointLights>(scene, choice.vpl);
    return nullptr;
}

std::unique_ptr<IndirectEstimator> makeIndirectEstimator(GlContext& context, const Scene& scene,
                                                         const IndirectChoice& given) {
    const IndirectChoice choice = given.resolved(scene);
    if (choice.method == "slices") return std::make_unique<SliceGather>(context, scene, choice.gather);
    // The comparisons of `bench indirect`: the same proxy, gathered otherwise.
    if (choice.method == "slice-quads") {
        GatherSettings g = choice.gather;
        g.quadPerFace = true;
        return std::make_unique<SliceGather>(context, scene, g);
    }
    if (choice.method == "raymarch") return std::make_unique<VoxelMarchGather>(context, scene, choice.gather);
    if (std::unique_ptr<IndirectEstimator> e = makeCpuIndirectEstimator(scene, choice)) return e;
    for (TriangleProjection p : {TriangleProjection::Fisheye, TriangleProjection::Perspective, TriangleProjection::Hemicube})
        if (choice.method == triangleProjectionName(p)) {
            TriangleGatherSettings t;
            t.projection = p;
            t.imageSize = choice.gather.imageSize;
            t.resolution = choice.gather.resolution;
            return std::make_unique<TriangleGather>(context, scene, t);
        }
    throw InputError(concat("indirect method '", choice.method, "' is unknown"));
}

// --- The real-time stand-in ------------------------------------------------------------

const std::vector<std::string>& realtimeMethodNames() {
    static const std::vector<std::string> names = {"volume", "vpl", "lpv"};
    return names;
}

void RealtimeChoice::validate() const {
    const std::vector<std::string>& m = realtimeMethodNames();
    const auto known = [&](const std::string& name) { return std::find(m.begin(), m.end(), name) != m.end(); };
    if (realtime != "off" && realtime != "auto" && !known(realtime))
        throw InputError(concat("--realtime '", realtime, "': unknown (auto, volume, vpl, lpv or off)"));
    if (display != "cache" && !known(display))
        throw InputError(concat("--indirect-display '", display, "': unknown (cache, volume, vpl or lpv)"));
    if (methodBounces != RealtimeSettings::kBouncesFromScene && (methodBounces < 0 || methodBounces > 256))
        throw InputError(concat("--realtime-bounces ", methodBounces, " is not in 0..256"));
}

int RealtimeChoice::parseBounces(const std::string& text) {
    if (text == "auto") return RealtimeSettings::kBouncesFromScene;
    size_t end = 0;
    int n = -1;
    try {
        n = std::stoi(text, &end);
    } catch (const std::exception&) {
        end = 0;
    }
    if (end == 0 || end != text.size() || n < 0 || n > 256)
        throw InputError(concat("--realtime-bounces '", text, "': not auto or a whole number in 0..256"));
    return n;
}

std::string RealtimeChoice::bouncesText() const {
    return methodBounces == RealtimeSettings::kBouncesFromScene ? std::string("auto") : concat(methodBounces);
}

RealtimeSettings RealtimeChoice::settings(uint32_t seed) const {
    RealtimeSettings s;
    s.live = display != "cache";
    s.method = s.live ? display : realtime;
    s.methodBounces = methodBounces;
    s.seed = seed;
    // vpl first: it stands in until auto has measured the methods (the
    // fastest update on the Cornell box, where it was the default).
    s.candidates = {"vpl", "volume", "lpv"};
    return s;
}

std::string RealtimeChoice::describe() const {
    if (display != "cache") return concat("indirect light shown: ", display, " alone, live");
    if (realtime == "off") return "indirect light shown: the cache (its old bounces while it catches up)";
    return concat("indirect light shown: the cache, ",
                  realtime == "auto" ? std::string("the real-time method chosen by its error on the scene's complete "
                                                   "cache (vpl until then)")
                                     : realtime,
                  " standing in while it catches up (",
                  methodBounces == RealtimeSettings::kBouncesFromScene
                      ? std::string("bounces estimated until the rest carry at most a sixth of the light, by the "
                                    "scene's albedo, the rest a tail")
                  : methodBounces > 0 ? concat(methodBounces, " bounces estimated, the rest a tail")
                                      : std::string("every bounce estimated"),
                  ")");
}

RealtimeIndirect::EstimatorFactory realtimeEstimatorFactory(const IndirectChoice& indirect) {
    return [indirect](const Scene& scene, const std::string& method) {
        IndirectChoice c = indirect;
        c.method = method;
        // The volume's probes and the lights' sums on every core: the
        // stand-in runs at the frames' priority, above the cache's workers,
        // and its estimate is what the next frames show
        // (IrradianceVolumeSettings::threads, VirtualPointLightSettings::threads).
        c.volume.threads = c.vpl.threads = int(std::max(1u, std::thread::hardware_concurrency()));
        std::unique_ptr<IndirectEstimator> e = makeCpuIndirectEstimator(scene, c);
        if (!e) throw InputError(concat("'", method, "' cannot stand in for the cache's indirect light"));
        return e;
    };
}

// --- For the worker ------------------------------------------------------------------

namespace {

// A gather with a GL context of its own, made current before each call. Not
// the direct sampler's: GL state one pass leaves could otherwise reach the
// other, and a thread's results would depend on which samples it took
// before, so a batch spread over threads would not repeat bit for bit.
class OwnContextGather final : public IndirectEstimator {
public:
    OwnContextGather(const Scene& scene, const IndirectChoice& choice, GlBackend backend)
        : context_(createHeadlessContext(backend)), inner_(makeIndirectEstimator(*context_, scene, choice)) {}
    ~OwnContextGather() override {
        context_->use();
        inner_.reset();  // its GL objects go while their context is current
    }
    std::string name() const override { return inner_->name(); }
    void setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance) override {
        context_->use();
        inner_->setSource(slot, irradiance, importance);
    }
    void releaseSource(size_t slot) override {
        context_->use();
        inner_->releaseSource(slot);
    }
    Rgb estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override {
        context_->use();
        return inner_->estimate(slot, x, n, seed);
    }
    VertexSample estimateSample(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override {
        context_->use();
        return inner_->estimateSample(slot, x, n, seed);
    }
    VertexSample estimateRequest(size_t slot, const SampleRequest& r) override {
        context_->use();
        return inner_->estimateRequest(slot, r);
    }
    IndirectStats stats() const override { return inner_->stats(); }
    double borderInset() const override { return inner_->borderInset(); }
    bool separatesSides() const override { return inner_->separatesSides(); }
    std::optional<std::vector<Rgb>> seenAlbedo(const IrradianceMeshCopy& mesh, size_t begin, size_t end, int rays,
                                               uint32_t seed) override {
        context_->use();
        return inner_->seenAlbedo(mesh, begin, end, rays, seed);
    }

private:
    std::unique_ptr<GlContext> context_;
    std::unique_ptr<IndirectEstimator> inner_;
};

}  // namespace

SamplerFactory samplerFactory(const Scene& scene, const DirectChoice& direct, const IndirectChoice& indirect) {
    return [&scene, direct, indirect]() {
        WorkerSamplers samplers;
        samplers.direct = std::make_unique<ConfiguredDirectSampler>(scene, direct);
        if (indirect.active()) {
            // The ray gather and the volumes draw nothing: no GL context of their own.
            const IndirectChoice resolved = indirect.resolved(scene);
            samplers.indirect = makeCpuIndirectEstimator(scene, resolved);
            if (!samplers.indirect) samplers.indirect = std::make_unique<OwnContextGather>(scene, resolved, direct.backend);
        }
        return samplers;
    };
}

}  // namespace ml
