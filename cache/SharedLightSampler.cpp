#include "SharedLightSampler.h"

#include "core/EmitterTexture.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/reference/Lambert.h"

#include <algorithm>
#include <functional>

namespace ml {

Rgb unoccludedIrradiance(const Light& light, const Vec3& x, const Vec3& n) {
    if (light.punctual()) return punctualIncidence(light, x, n).irradiance;
    return light.radiance * unoccludedCosineSolidAngle(light, x, n);
}

SharedLightSampler::SharedLightSampler(const Scene& scene, std::shared_ptr<const LightCoverage> coverage,
                                       std::unique_ptr<DirectSampler> perLight, int lights, int firstLights)
    : scene_(scene), coverage_(std::move(coverage)), perLight_(std::move(perLight)), draws_(lights),
      firstDraws_(firstLights) {
    ML_ASSERT(coverage_ && perLight_ && draws_ >= 1 && firstDraws_ >= 1,
              "a shared-light sampler needs its coverage and sampler, and a light to draw");
    for (const Light& l : scene_.lights) textured_.push_back(EmitterTexture(scene_, l).textured());
}

std::string SharedLightSampler::name() const {
    return concat(perLight_->name(), "; lights share a mesh where they give under ", 100 * coverage_->share(),
                  "% of the light, ", draws_, " lights drawn per shared estimate (", firstDraws_,
                  " in the first pass) from those of the ", kAskedLights,
                  " brightest the sampler cannot answer without the GPU, and the rest");
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
        if (textured_[r.light] || !perLight_->sampleWithoutGpu(r.light, x, n, seedFor(seed, 0xc1a55u, r.light), e))
            continue;
        k.lights.push_back(r.light);
        k.occluded += r.shared * glm::max(r.unoccluded - e.irradiance, Rgb(0.0));
        k.visible += r.y * e.visibility;
    }
    return k;
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
    cdf_.clear();
    drawable_.clear();
    double sum = 0;
    size_t next = 0;
    for (size_t i = 0; i < reaching_.size(); ++i) {
        while (next < k.lights.size() && k.lights[next] < reaching_[i].light) ++next;
        if (next < k.lights.size() && k.lights[next] == reaching_[i].light) continue;
        sum += reaching_[i].y;
        cdf_.push_back(sum);
        drawable_.push_back(i);
    }
    Rgb occluded = k.occluded;
    double drawnShare = 0;  // Σ (1 − w_l) Y(U_l) · visibility over the drawn, weighted as they are
    bool partial = false;
    double drawSum = 0, drawSquares = 0;  // Σ and Σ² of the draws' luminance, for ownVariance
    // K draws, or each light once (weight 1, exact) where no more than K
    // are left to draw.
    const bool every = drawable_.size() <= draws;
    const size_t count = every ? drawable_.size() : draws;
    for (size_t d = 0; d < count && sum > 0; ++d) {
        size_t j = d;
        if (!every) {
            // Stratified over [0, 1): draw d in [d/K, (d+1)/K).
            const double u =
                (double(d) + double(hash32(seedFor(seed, 0x5a1e5u, uint32_t(d))) >> 8) / 16777216.0) /
                double(draws) * sum;
            j = std::min(size_t(std::upper_bound(cdf_.begin(), cdf_.end(), u) - cdf_.begin()), cdf_.size() - 1);
        }
        const Reaching& r = reaching_[drawable_[j]];
        const uint32_t l = r.light;
        // 1/(K p_l) for a draw, p_l its share of the CDF.
        const double weight = every ? 1.0 : sum / ((cdf_[j] - (j ? cdf_[j - 1] : 0.0)) * double(draws));
        VertexSample e;
        if (!take(l, seedFor(seed, uint32_t(d), l), e)) return false;
        // (1 − w_l) O_l / (K p_l), O_l = U_l − E_l, never negative for a
        // uniform light; a textured one's may be (see the header).
        const Rgb difference = r.unoccluded - e.irradiance;
        const Rgb o = (textured_[l] ? difference : glm::max(difference, Rgb(0.0))) * r.shared * weight;
        occluded += o;
        const double y = luminance(o) * double(count);  // this draw's estimate of the drawn lights' Σ
        drawSum += y, drawSquares += y * y;
        drawnShare += weight * r.y * e.visibility;
        partial = partial || e.partial;
    }
    out.irradiance = glm::max(total - occluded, Rgb(0.0));
    // The visible share of the shared light: exact for the lights answered
    // without the GPU and for lights taken each once, the draws' estimate
    // for the rest.
    out.visibility = std::clamp((k.visible + drawnShare) / all, 0.0, 1.0);
    out.partial = partial;
    // Its work, the draws it had: a first pass's few weigh less in a
    // vertex's mean than a later estimate's many (VertexStats), and an
    // exact one (each light taken once, or none left to draw) as a full one.
    out.work = double(draws);
    // The draws as independent: their scatter over K(K − 1) is the variance
    // of their mean, the estimate's only noise but the wrapped sampler's own
    // (small: its jittered tests). Stratified draws scatter less than that;
    // the cache measures by how much where it resamples (detail::NoiseModel).
    // With nothing to draw, or each light taken once, the estimate is exact.
    if (every || !(sum > 0)) out.ownVariance = 0;
    else if (count >= 2)
        out.ownVariance = varianceOfMean(drawSum, drawSquares, double(count));
    return true;
}

}  // namespace ml
