#include "SharedLightSampler.h"

#include "core/EmitterTexture.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/reference/Lambert.h"

#include <algorithm>

namespace ml {

Rgb unoccludedIrradiance(const Light& light, const Vec3& x, const Vec3& n) {
    if (light.punctual()) return punctualIncidence(light, x, n).irradiance;
    return light.radiance * unoccludedCosineSolidAngle(light, x, n);
}

SharedLightSampler::SharedLightSampler(const Scene& scene, std::shared_ptr<const LightCoverage> coverage,
                                       std::unique_ptr<DirectSampler> perLight, int lights)
    : scene_(scene), coverage_(std::move(coverage)), perLight_(std::move(perLight)), draws_(lights) {
    ML_ASSERT(coverage_ && perLight_ && draws_ >= 1, "a shared-light sampler needs its coverage and sampler");
    for (const Light& l : scene_.lights) textured_.push_back(EmitterTexture(scene_, l).textured());
}

std::string SharedLightSampler::name() const {
    return concat(perLight_->name(), "; lights share a mesh where they give under ", 100 * coverage_->share(),
                  "% of the light, ", draws_, " lights drawn per shared estimate");
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

template <class Take>
bool SharedLightSampler::estimateShared(const Vec3& x, const Vec3& n, uint32_t seed, Take take, VertexSample& out) {
    const size_t lights = scene_.lights.size();
    coverage_->weights(x, weights_);
    // (1 − w_l) U_l for every light, the total exactly, the draws' CDF by luminance.
    cdf_.clear();
    unoccluded_.clear();
    candidates_.clear();
    shared_.clear();
    Rgb total(0.0);
    double sum = 0;
    size_t next = 0;
    for (size_t l = 0; l < lights; ++l) {
        double w = 0;
        if (next < weights_.size() && weights_[next].first == l) w = weights_[next++].second;
        if (w >= 1 || coverage_->gathered(l)) continue;  // its own mesh, or the gather, carries it
        const Rgb full = unoccludedIrradiance(scene_.lights[l], x, n);
        const double y = (1 - w) * luminance(full);
        if (!(y > 0)) continue;
        total += (1 - w) * full;
        sum += y;
        candidates_.push_back(uint32_t(l));
        unoccluded_.push_back(full);
        shared_.push_back(1 - w);
        cdf_.push_back(sum);
    }
    if (!(sum > 0)) {  // nothing shared reaches this point
        out = {};
        return true;
    }
    Rgb occluded(0.0);
    double visibleSum = 0;
    bool partial = false;
    for (int k = 0; k < draws_; ++k) {
        // Stratified over [0, 1): draw k in [k/K, (k+1)/K).
        const double u = (double(k) + double(hash32(seedFor(seed, 0x5a1e5u, uint32_t(k))) >> 8) / 16777216.0) /
                         double(draws_) * sum;
        const size_t c = size_t(std::upper_bound(cdf_.begin(), cdf_.end(), u) - cdf_.begin());
        const size_t i = std::min(c, candidates_.size() - 1);
        const uint32_t l = candidates_[i];
        const double p = (cdf_[i] - (i ? cdf_[i - 1] : 0.0)) / sum;
        VertexSample e;
        if (!take(l, seedFor(seed, uint32_t(k), l), e)) return false;
        // (1 − w_l) O_l / p_l, O_l = U_l − E_l, never negative for a
        // uniform light; a textured one's may be (see the header).
        const Rgb difference = unoccluded_[i] - e.irradiance;
        const Rgb o = (textured_[l] ? difference : glm::max(difference, Rgb(0.0))) * shared_[i];
        occluded += o / (p * double(draws_));
        visibleSum += e.visibility;
        partial = partial || e.partial;
    }
    out.irradiance = glm::max(total - occluded, Rgb(0.0));
    out.visibility = std::clamp(visibleSum / double(draws_), 0.0, 1.0);
    out.partial = partial;
    return true;
}

}  // namespace ml
