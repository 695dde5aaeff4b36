#include "NoisyReference.h"

#include "BenchRun.h"  // secondsSince

#include "core/Error.h"
#include "core/Random.h"
#include "core/raytrace/EmbreeScene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace ml {

Reference renderReference(const EmbreeScene& rays, const Camera& camera, int width, int height, int spp,
                          const PathTracerSettings& settings) {
    const std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    ReferenceImage image = PathTracer(rays, settings).render(camera, width, height, spp);
    Reference r;
    r.radiance = std::move(image.radiance);
    r.standardError = std::move(image.standardError);
    r.spp = spp;
    r.seconds = secondsSince(start);
    r.noise = relativeRmsError(r.standardError, r.radiance);
    return r;
}

ViewReferences renderViewReferences(const BenchRun& run, const EmbreeScene& rays, const std::vector<Camera>& cameras,
                                    int width, int height, int spp, const PathTracerSettings& settings, uint32_t tag) {
    run.progress("walkthrough: %zu references, %d spp at %dx%d (load %s)\n", cameras.size(), spp, width, height,
                 loadAverage().c_str());
    ViewReferences r;
    for (size_t v = 0; v < cameras.size(); ++v) {
        PathTracerSettings view = settings;
        view.seed = seedFor(settings.seed, tag, uint32_t(v));
        r.views.push_back(renderReference(rays, cameras[v], width, height, spp, view));
        r.seconds += r.views.back().seconds;
        r.noiseMax = std::max(r.noiseMax, r.views.back().noise);
    }
    std::printf("walkthrough: %zu views %dx%d; references %d spp, %.1f s in all, relative noise up to %.3f%%\n",
                cameras.size(), width, height, spp, r.seconds, 100 * r.noiseMax);
    return r;
}

Reference averageReferences(const Reference& a, const Reference& b) {
    ML_ASSERT(a.radiance.data.size() == b.radiance.data.size() && a.spp > 0 && b.spp > 0,
              "references of different sizes or without samples");
    const double wa = double(a.spp) / double(a.spp + b.spp), wb = 1 - wa;
    Reference r;
    r.radiance = a.radiance;
    r.standardError = a.standardError;
    for (size_t i = 0; i < r.radiance.data.size(); ++i) {
        const double sa = a.standardError.data[i], sb = b.standardError.data[i];
        r.radiance.data[i] = float(wa * a.radiance.data[i] + wb * b.radiance.data[i]);
        r.standardError.data[i] = float(std::sqrt(wa * wa * sa * sa + wb * wb * sb * sb));
    }
    r.spp = a.spp + b.spp;
    r.seconds = a.seconds + b.seconds;
    r.noise = relativeRmsError(r.standardError, r.radiance);
    return r;
}

ImageError errorAgainst(const ImageRgb& x, const Reference& ref) {
    const ImageRgb& r = ref.radiance;
    if (x.width != r.width || x.height != r.height)
        throw InputError(concat("image sizes differ: ", x.width, "x", x.height, " against a ", r.width, "x",
                                r.height, " reference"));
    const double floor = relativeRmseFloor(r);
    double squared = 0, noise = 0;
    for (size_t i = 0; i < r.data.size(); ++i) {
        const double w = 1.0 / (double(r.data[i]) * r.data[i] + floor), d = double(x.data[i]) - r.data[i],
                     s = ref.standardError.data[i];
        squared += d * d * w;
        noise += s * s * w;
    }
    const double n = double(std::max<size_t>(1, r.data.size()));
    return {std::sqrt(squared / n), std::sqrt(std::max(0.0, (squared - noise) / n))};
}

DoublingPathTracer::DoublingPathTracer(const EmbreeScene& rays, const Camera& camera, int width, int height,
                                       const PathTracerSettings& settings, int firstSpp)
    : rays_(rays), camera_(camera), width_(width), height_(height), settings_(settings), next_(firstSpp) {
    ML_ASSERT(firstSpp >= 2, "the doubling path tracer starts at 2 samples per pixel or more (its halves give its "
                             "noise), not ", firstSpp);
}

void DoublingPathTracer::step() {
    const auto start = std::chrono::steady_clock::now();
    PathTracerSettings s = settings_;
    s.seed = seedFor(settings_.seed, uint32_t(steps_++));
    const PathTracer tracer(rays_, s);
    const ReferenceImage r = tracer.render(camera_, width_, height_, next_);
    if (spp_ == 0) {
        image_ = r.radiance;
        variance_ = r.standardError;
        for (float& v : variance_.data) v *= v;
    } else {
        const double wOld = double(spp_) / double(spp_ + next_), wNew = double(next_) / double(spp_ + next_);
        for (size_t i = 0; i < image_.data.size(); ++i) {
            const double se = r.standardError.data[i];
            image_.data[i] = float(wOld * image_.data[i] + wNew * r.radiance.data[i]);
            variance_.data[i] = float(wOld * wOld * variance_.data[i] + wNew * wNew * se * se);
        }
    }
    spp_ += next_;
    next_ = spp_;
    seconds_ += secondsSince(start);
}

ImageRgb DoublingPathTracer::standardError() const {
    ImageRgb sigma = variance_;
    for (float& v : sigma.data) v = std::sqrt(v);
    return sigma;
}

double DoublingPathTracer::ownNoise(const ImageRgb& reference) const {
    return relativeRmsError(standardError(), reference);
}

Reference DoublingPathTracer::asReference() const {
    Reference r;
    r.radiance = image_;
    r.standardError = standardError();
    r.spp = spp_;
    r.seconds = seconds_;
    r.noise = relativeRmsError(r.standardError, r.radiance);
    return r;
}

std::optional<double> timeToLevel(const std::vector<double>& seconds, const std::vector<double>& errors,
                                  double level) {
    ML_ASSERT(seconds.size() == errors.size(), seconds.size(), " times for ", errors.size(), " errors");
    for (size_t i = 0; i < errors.size(); ++i) {
        if (errors[i] > level) continue;
        if (i == 0) return seconds[0];
        const double ea = errors[i - 1], eb = errors[i];  // ea > level >= eb
        const double ta = seconds[i - 1], tb = seconds[i];
        if (eb > 0 && ta > 0 && tb > 0) {
            const double f = std::log(ea / level) / std::log(ea / eb);
            return std::exp(std::log(ta) + f * (std::log(tb) - std::log(ta)));
        }
        return ta + (ea - level) / (ea - eb) * (tb - ta);
    }
    return std::nullopt;
}

}  // namespace ml
