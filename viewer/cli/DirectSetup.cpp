#include "DirectSetup.h"

#include "core/Error.h"
#include "core/reference/ExactIrradiance.h"

#include <algorithm>

namespace ml {

void declareDirectOptions(Options& o) {
    o.value("method", "NAME", "direct light: jittered, regular, query or exact", std::string("jittered"));
    o.value("estimator", "NAME", "cv (exact unoccluded minus sampled occlusion) or plain", std::string("cv"));
    o.value("image-size", "N", "sampling image side, pixels", std::string("64"));
    o.value("bits", "N", "jittered tests per pixel: 1, 4, 8, 16 or 32", std::string("8"));
    o.value("passes", "K", "estimates averaged per point", std::string("1"));
    o.value("seed", "N", "random seed; the same seed repeats bit for bit", std::string("1"));
    o.value("gl", "BACKEND", "OpenGL back end: auto, osmesa or egl", std::string("auto"));
}

DirectChoice readDirectOptions(const Options& o) {
    DirectChoice c;
    const std::string method = o.str("method");
    c.exact = method == "exact";
    if (!c.exact) c.sampler.method = parseDirectMethod(method);
    c.sampler.estimator = parseDirectEstimator(o.str("estimator"));
    c.sampler.imageSize = o.integer("image-size", 4, 1024);
    c.sampler.bits = o.integer("bits", 1, 32);
    c.sampler.validate();
    c.passes = o.integer("passes", 1, 1 << 20);
    c.seed = o.seed("seed");
    c.backend = parseGlBackend(o.str("gl"));
    if (c.backend == GlBackend::Glfw) throw InputError("--gl glfw opens a window: use osmesa, egl or auto");
    return c;
}

std::string DirectChoice::describe() const {
    if (exact) return "exact (visible light polygon from CGAL, Lambert's closed form)";
    const bool jittered = sampler.method == DirectMethod::Jittered;
    return concat(directMethodName(sampler.method), " ", sampler.imageSize, "x", sampler.imageSize,
                  jittered ? concat(", ", sampler.bits, " bits/pixel") : std::string(),
                  sampler.method == DirectMethod::OcclusionQuery ? std::string()
                                                                 : concat(", ", directEstimatorName(sampler.estimator), " estimator"),
                  ", ", passes, passes == 1 ? " pass" : " passes");
}

DirectEstimators::DirectEstimators(const Scene& scene, const DirectChoice& choice, bool glNeeded)
    : scene_(scene), choice_(choice) {
    if (choice.exact) exact_ = std::make_unique<ExactDirect>(scene);
    if (glNeeded || !choice.exact) context_ = createHeadlessContext(choice.backend);
    if (!choice.exact) sampler_ = std::make_unique<DirectLightSampler>(*context_, scene, choice.sampler);
}

DirectEstimators::~DirectEstimators() = default;

DirectEstimateFn DirectEstimators::estimate() {
    return [this](size_t light, const Vec3& x, const Vec3& n, uint32_t seed) {
        return sampleOne(light, x, n, seed).irradiance;
    };
}

DirectSampleFn DirectEstimators::sample() {
    return [this](size_t light, const Vec3& x, const Vec3& n, uint32_t seed) { return sampleOne(light, x, n, seed); };
}

VertexSample DirectEstimators::sampleOne(size_t light, const Vec3& x, const Vec3& n, uint32_t seed) {
    // Visible fraction of the light's cosine-weighted solid angle; a point
    // that sees none of the light (behind it) counts as fully visible: no
    // shadow boundary passes there.
    auto fraction = [](double visible, double unoccluded) {
        return unoccluded > 0 ? std::clamp(visible / unoccluded, 0.0, 1.0) : 1.0;
    };
    if (exact_) {
        const double unoccluded = exact_->unoccludedCosineSolidAngle(light, x, n);
        const double visible = exact_->cosineSolidAngle(light, x, n);
        const double v = fraction(visible, unoccluded);
        return {visible * scene_.lights[light].radiance, v, v > 1e-9 && v < 1 - 1e-9};
    }
    const DirectSample s = sampler_->sample(light, x, n, seed);
    const DirectPhaseTimes& t = sampler_->lastTimes();
    totals_.setup += t.setup;
    totals_.draw += t.draw;
    totals_.readback += t.readback;
    totals_.weighting += t.weighting;
    return {s.irradiance, fraction(s.cosineSolidAngle, s.unoccluded), s.partiallyVisible()};
}

CacheWorker::SamplerFactory directSamplerFactory(const Scene& scene, const DirectChoice& choice,
                                                 std::shared_ptr<DirectPhaseTimes> totals) {
    return [&scene, choice, totals]() -> DirectSampleFn {
        auto estimators = std::make_shared<DirectEstimators>(scene, choice, false);
        return [estimators, totals](size_t light, const Vec3& x, const Vec3& n, uint32_t seed) {
            const VertexSample s = estimators->sampleOne(light, x, n, seed);
            *totals = estimators->totals();
            return s;
        };
    };
}

}  // namespace ml
