// Samplers made of closed forms, for the tests: a cache mesh, a worker or a
// session filled from a function of the point instead of a GPU pass.
#pragma once

#include "cache/CacheWorker.h"
#include "cache/DirectSampler.h"
#include "cache/IrradianceCache.h"

#include <functional>
#include <memory>
#include <string>
#include <utility>

namespace ml::test {

// A DirectSampler from `f(light, x, n, seed)` returning a VertexSample.
template <class F>
class FunctionDirectSampler final : public DirectSampler {
public:
    explicit FunctionDirectSampler(F f) : f_(std::move(f)) {}
    std::string name() const override { return "test function"; }
    VertexSample sample(size_t light, const Vec3& x, const Vec3& n, uint32_t seed) override {
        return f_(light, x, n, seed);
    }

private:
    F f_;
};

// A worker's samplers: direct light from `f`, no indirect estimator.
template <class F>
SamplerFactory functionSamplers(F f) {
    return [f] {
        WorkerSamplers s;
        s.direct = std::make_unique<FunctionDirectSampler<F>>(f);
        return s;
    };
}

// ∫ E dA over a mesh copy, W per channel when E is in W·m⁻² and lengths in
// metres: linear interpolation makes each triangle's integral exactly its
// area times the mean of its corners.
inline Rgb integrate(const IrradianceMeshCopy& m) {
    Rgb sum(0.0);
    for (const glm::uvec3& t : m.triangles) {
        const double area = 0.5 * glm::length(glm::cross(m.positions[t.y] - m.positions[t.x],
                                                         m.positions[t.z] - m.positions[t.x]));
        sum += area * (m.irradiance[t.x] + m.irradiance[t.y] + m.irradiance[t.z]) / 3.0;
    }
    return sum;
}

// Closed forms: the irradiance alone (visibility 1, never partial), or a
// whole VertexSample.
using IrradianceFn = std::function<Rgb(size_t light, const Vec3& x, const Vec3& n, uint32_t seed)>;
using SampleFn = std::function<VertexSample(size_t light, const Vec3& x, const Vec3& n, uint32_t seed)>;

// ml::sampleEveryVertex with a closed form.
template <class F>
void sampleEveryVertex(IrradianceCache& cache, F f, int passes, uint32_t seed) {
    auto sampler = samplerOf(std::move(f));
    ml::sampleEveryVertex(cache, sampler, passes, seed);
}

}  // namespace ml::test
