#include "SharedLightSampler.h"

#include "core/EmitterTexture.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/raytrace/PunctualShadow.h"
#include "core/reference/Lambert.h"

#include <algorithm>
#include <functional>

namespace ml {

Rgb unoccludedIrradiance(const Light& light, const Vec3& x, const Vec3& n) {
    if (light.punctual()) return punctualIncidence(light, x, n).irradiance;
    return light.radiance * unoccludedCosineSolidAngle(light, x, n);
}

SharedLightSampler::SharedLightSampler(const Scene& scene, std::shared_ptr<const LightCoverage> coverage,
                                       std::unique_ptr<DirectSampler> perLight, int lights, int firstLights,
                                       int rayDraws)
    : scene_(scene), coverage_(std::move(coverage)), perLight_(std::move(perLight)), draws_(lights),
      firstDraws_(firstLights), rayDraws_(rayDraws) {
    ML_ASSERT(coverage_ && perLight_ && draws_ >= 1 && firstDraws_ >= 1,
              "a shared-light sampler needs its coverage and sampler, and a light to draw");
    emitters_ = EmitterTexture::forLights(scene_);
    for (const Light& l : scene_.lights) {
        std::vector<double> cdf;
        double area = 0;
        for (const Triangle3& t : l.geometry)
            cdf.push_back(area += 0.5 * glm::length(glm::cross(t[1] - t[0], t[2] - t[0])));
        areaCdf_.push_back(std::move(cdf));
    }
}

SharedLightSampler::~SharedLightSampler() = default;

std::string SharedLightSampler::name() const {
    const std::string rays =
        rayDraws_ > 0 ? concat(", or ", rayDraws_, " shadow rays to points on them where more are left") : "";
    return concat(perLight_->name(), "; lights share a mesh where they give under ", 100 * coverage_->share(),
                  "% of the light, ", draws_, " lights drawn per shared estimate (", firstDraws_,
                  " in the first pass) from those of the ", kAskedLights,
                  " brightest the sampler cannot answer without the GPU, and the rest", rays);
}

template <class Take>
bool SharedLightSampler::estimate(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed, Take take,
                                  VertexSample& out) {
    const size_t lights = scene_.lights.size();
    if (mesh >= lights) return estimateShared(x, n, seed, take, out);
    const double w = coverage_->weight(mesh, x);
    if (w <= 0) {  // the shared mesh carries all of this light here
        out = {};
        return true;
    }
    VertexSample s;
    if (!take(mesh, seed, s)) return false;
    s.irradiance *= w;
    out = s;
    return true;
}

VertexSample SharedLightSampler::sample(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed) {
    VertexSample out;
    estimate(mesh, x, n, seed,
             [&](size_t l, uint32_t s, VertexSample& e) {
                 e = perLight_->sample(l, x, n, s);
                 return true;
             },
             out);
    return out;
}

bool SharedLightSampler::sampleWithoutGpu(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed,
                                          VertexSample& out) {
    return estimate(mesh, x, n, seed,
                    [&](size_t l, uint32_t s, VertexSample& e) { return perLight_->sampleWithoutGpu(l, x, n, s, e); },
                    out);
}

// (1 − w_l) U_l of each light reaching x that the shared mesh carries, in
// light order, into reaching_; their sums.
void SharedLightSampler::reaching(const Vec3& x, const Vec3& n, Rgb& total, double& all) {
    const size_t lights = scene_.lights.size();
    coverage_->weights(x, weights_);
    reaching_.clear();
    total = Rgb(0.0);
    all = 0;
    size_t next = 0;
    for (size_t l = 0; l < lights; ++l) {
        double w = 0;
        if (next < weights_.size() && weights_[next].first == l) w = weights_[next++].second;
        if (w >= 1 || coverage_->gathered(l)) continue;  // its own mesh, or the gather, carries it
        const Rgb full = unoccludedIrradiance(scene_.lights[l], x, n);
        const double y = (1 - w) * luminance(full);
        if (!(y > 0)) continue;
        total += (1 - w) * full;
        all += y;
        reaching_.push_back({uint32_t(l), 1 - w, y, full});
    }
}

const SharedLightSampler::Known& SharedLightSampler::known(const Vec3& x, const Vec3& n, uint32_t seed) {
    const Key key{bits(x.x), bits(x.y), bits(x.z), bits(n.x), bits(n.y), bits(n.z)};
    if (const auto it = known_.find(key); it != known_.end()) return it->second;
    if (known_.size() >= kMaxKnown) known_.clear();  // a bound on memory; made again as needed
    Known& k = known_[key];
    // Only the brightest are asked (a few microseconds each): the draws'
    // variance grows with the square of the light left to them. Ties go to
    // the lower index, so the choice depends on the point alone.
    double least = 0;
    if (reaching_.size() > size_t(kAskedLights)) {
        order_.clear();
        for (const Reaching& r : reaching_) order_.push_back(r.y);
        std::nth_element(order_.begin(), order_.begin() + (kAskedLights - 1), order_.end(), std::greater<double>());
        least = order_[size_t(kAskedLights - 1)];
    }
    int asked = 0;
    for (const Reaching& r : reaching_) {
        if (r.y < least || asked >= kAskedLights) continue;
        ++asked;
        VertexSample e;
        // A uniform light answered without the GPU is exact whatever the seed.
        if (emitters_[r.light].textured() ||
            !perLight_->sampleWithoutGpu(r.light, x, n, seedFor(seed, 0xc1a55u, r.light), e))
            continue;
        k.lights.push_back(r.light);
        k.occluded += r.shared * glm::max(r.unoccluded - e.irradiance, Rgb(0.0));
        k.visible += r.y * e.visibility;
    }
    return k;
}

// A shadow ray from x to a point y drawn on light l, uniform over its area:
// whether it is blocked, g(y) = A·cos θx·cos θy / r², whose mean over the
// light is U_l / L̄_l (0 where y is below x's horizon or x behind the
// light), and τ(y) = L(y) / L̄_l (EmitterTexture; 1 untextured). To a
// punctual light, its one ray (exact), g = 1 and τ = 1.
bool SharedLightSampler::shadowRay(uint32_t l, const Vec3& x, const Vec3& n, uint32_t seed, double& g,
                                   Rgb& tau) const {
    const Light& light = scene_.lights[l];
    tau = Rgb(1.0);
    if (light.punctual()) {
        g = 1;
        return !punctualIrradiance(*rays_, l, x, n).visible;
    }
    const std::vector<double>& cdf = areaCdf_[l];
    const double u = double(hash32(seed) >> 8) / 16777216.0 * cdf.back();
    const size_t t = std::min(size_t(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()), cdf.size() - 1);
    const Triangle3& tri = light.geometry[t];
    double a = double(hash32(seed ^ 0x9e3779b9u) >> 8) / 16777216.0,
           b = double(hash32(seed + 0x7f4a7c15u) >> 8) / 16777216.0;
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const Vec3 y = tri[0] + a * (tri[1] - tri[0]) + b * (tri[2] - tri[0]);
    const Vec3 d = y - x;
    const double r2 = glm::dot(d, d);
    const Vec3 normal = glm::cross(tri[1] - tri[0], tri[2] - tri[0]);
    const double nl = glm::length(normal), cosX = glm::dot(n, d), cosY = -glm::dot(normal, d);
    g = 0;
    if (!(r2 > 0 && nl > 0 && cosX > 0 && cosY > 0)) return false;  // gives nothing: its weight is 0
    g = cdf.back() * (cosX / std::sqrt(r2)) * (cosY / (nl * std::sqrt(r2))) / r2;
    if (emitters_[l].textured()) tau = emitters_[l].weight(t, a, b);
    // From x lifted off its surface to y, less the offset at the light's
    // end, nearer hits (what x touches) ignored: as punctualIrradiance.
    const Vec3 origin = rays_->spawnPoint(x, n, d);
    const Vec3 to = y - origin;
    const double length = glm::length(to);
    const double tNear = rays_->rayOffset(x) / length, tFar = 1 - rays_->rayOffset(y) / length;
    RayFilter filter;
    filter.skipLight = int(l);
    return tFar > tNear && rays_->occluded(origin, to, tNear, tFar, filter);
}

bool SharedLightSampler::rayDrawn(uint32_t l) const {
    const Light& light = scene_.lights[l];
    return rayDraws_ > 0 && (light.punctual() || (light.planar && !light.geometry.empty()));
}

std::pair<size_t, double> SharedLightSampler::DrawCdf::pick(uint32_t s, size_t d, size_t count) const {
    const double u = (double(d) + double(hash32(s) >> 8) / 16777216.0) / double(count) * total();
    const size_t j = std::min(size_t(std::upper_bound(steps.begin(), steps.end(), u) - steps.begin()), size() - 1);
    return {j, total() / ((steps[j] - (j ? steps[j - 1] : 0.0)) * double(count))};
}

template <class Take>
bool SharedLightSampler::estimateShared(const Vec3& x, const Vec3& n, uint32_t seed, Take take, VertexSample& out) {
    // Every light's (1 − w_l) U_l, the total exactly; the draws' CDF, by
    // luminance, over the lights not known. A first pass draws from every
    // light, asking none (firstSamples).
    Rgb total;
    double all;
    reaching(x, n, total, all);
    static const Known kNone;
    const Known& k = firstSamples_ ? kNone : known(x, n, seed);
    const size_t draws = size_t(firstSamples_ ? firstDraws_ : draws_);
    if (!(all > 0)) {  // nothing shared reaches this point
        out = {};
        out.ownVariance = 0;  // exactly
        out.work = double(draws);
        return true;
    }
    // The lights left to draw (the known ones were asked among these):
    // where more than K, those rays can reach (rayDrawn) are drawn by rays,
    // the rest by the wrapped sampler's pairs.
    const bool byRays = reaching_.size() - k.lights.size() > draws && rayDraws_ > 0;
    if (byRays && !rays_) rays_ = std::make_unique<EmbreeScene>(scene_);
    pairCdf_.clear(), rayCdf_.clear();
    size_t next = 0;
    for (size_t i = 0; i < reaching_.size(); ++i) {
        while (next < k.lights.size() && k.lights[next] < reaching_[i].light) ++next;
        if (next < k.lights.size() && k.lights[next] == reaching_[i].light) continue;
        (byRays && rayDrawn(reaching_[i].light) ? rayCdf_ : pairCdf_).add(i, reaching_[i].y);
    }
    Rgb occluded = k.occluded;
    double drawnShare = 0;  // Σ (1 − w_l) Y(U_l) · visibility over the drawn, weighted as they are
    bool partial = false;
    double variance = 0;
    // R rays, each to a light drawn by (1 − w_l) Y(U_l) and a point on it:
    // (1 − w_l) L_l g(y) (1 − V) / (R p_l), whose mean over the light is
    // (1 − w_l) O_l / (R p_l): unbiased, and 0 for a light in full view.
    if (rayCdf_.total() > 0) {
        const size_t count = size_t(rayDraws_);
        double drawSum = 0, drawSquares = 0;
        size_t blocked = 0;
        for (size_t d = 0; d < count; ++d) {
            const auto [j, weight] = rayCdf_.pick(seedFor(seed, 0x4a75u, uint32_t(d)), d, count);
            const Reaching& r = reaching_[rayCdf_.entries[j]];
            double g = 0;
            Rgb tau;
            const bool hidden = shadowRay(r.light, x, n, seedFor(seed, 0x5e7u + uint32_t(d), r.light), g, tau);
            const Light& light = scene_.lights[r.light];
            // L̄ g − L(y) g V: U_l − E_l at y. A textured light's may be
            // negative where y is brighter than the mean and in view.
            const Rgb part = hidden ? Rgb(1.0) : Rgb(1.0) - tau;
            const Rgb o = (light.punctual() ? r.unoccluded : light.radiance * g) * part * r.shared * weight;
            occluded += o;
            blocked += hidden;
            const double y = luminance(o) * double(count);
            drawSum += y, drawSquares += y * y;
            if (!hidden) drawnShare += weight * r.y;
        }
        partial = blocked > 0 && blocked < count;
        variance += varianceOfMean(drawSum, drawSquares, double(count));
    }
    // K pair draws, or each light once (weight 1, exact) where no more than
    // K are left to draw.
    const bool every = pairCdf_.size() <= draws;
    const size_t count = every ? pairCdf_.size() : draws;
    double drawSum = 0, drawSquares = 0;  // Σ and Σ² of the draws' luminance, for ownVariance
    for (size_t d = 0; d < count && pairCdf_.total() > 0; ++d) {
        // 1/(K p_l) for a draw, p_l its share of the CDF.
        const auto [j, weight] =
            every ? std::pair<size_t, double>(d, 1.0) : pairCdf_.pick(seedFor(seed, 0x5a1e5u, uint32_t(d)), d, draws);
        const Reaching& r = reaching_[pairCdf_.entries[j]];
        const uint32_t l = r.light;
        VertexSample e;
        if (!take(l, seedFor(seed, uint32_t(d), l), e)) return false;
        // (1 − w_l) O_l / (K p_l), O_l = U_l − E_l, never negative for a
        // uniform light; a textured one's may be (see the header).
        const Rgb difference = r.unoccluded - e.irradiance;
        const Rgb o = (emitters_[l].textured() ? difference : glm::max(difference, Rgb(0.0))) * r.shared * weight;
        occluded += o;
        const double y = luminance(o) * double(count);  // this draw's estimate of the drawn lights' Σ
        drawSum += y, drawSquares += y * y;
        drawnShare += weight * r.y * e.visibility;
        partial = partial || e.partial;
    }
    // The draws as independent: their scatter over K(K − 1) is the variance
    // of their mean, the estimate's only noise but the wrapped sampler's own
    // (small: its jittered tests). Stratified draws scatter less than that;
    // the cache measures by how much where it resamples (detail::NoiseModel).
    // Each light taken once is exact.
    if (!every && count >= 2) variance += varianceOfMean(drawSum, drawSquares, double(count));
    out.irradiance = glm::max(total - occluded, Rgb(0.0));
    // The visible share of the shared light: exact for the lights answered
    // without the GPU and for lights taken each once, the draws' estimate
    // for the rest.
    out.visibility = std::clamp((k.visible + drawnShare) / all, 0.0, 1.0);
    out.partial = partial;
    // Its work: a first pass's few pair draws weigh less in a vertex's mean
    // than a later estimate's many (VertexStats); an exact estimate, or one
    // by rays, as a full one.
    out.work = byRays ? double(draws_) : double(draws);
    out.ownVariance = variance;
    return true;
}

}  // namespace ml
