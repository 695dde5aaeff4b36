// The paper's bench (§6.1, core/scenes/BenchScene.h) as the direct-light
// samplers' tests use it (test_direct_sampler.cpp, test_raytrace_sampler.cpp):
// its exact occluded irradiance, where the samplers look from, how far that
// moves their expectation, and receivers in and out of the occluder's
// penumbra. Every value is of the bench's one light, Ke = 1, so irradiance
// is the visible cosine-weighted solid angle (sr).
#pragma once

#include "core/reference/ExactIrradiance.h"
#include "core/scenes/BenchScene.h"
#include "gpu_sampling/direct/DirectLightSampler.h"

#include <cmath>
#include <vector>

namespace ml::test {

inline const Scene& benchScene() {
    static const Scene scene = makeBenchScene();
    return scene;
}
inline const ExactDirect& benchExact() {
    static const ExactDirect reference(benchScene());
    return reference;
}

// The exact visible cosine-weighted solid angle at the receiver x (normal
// n), and Lambert's value there (nothing occluding).
inline double exactAt(const Vec3& x, const Vec3& n) { return benchExact().cosineSolidAngle(0, x, n); }
inline double lambertAt(const Vec3& x, const Vec3& n) { return benchExact().unoccludedCosineSolidAngle(0, x, n); }

// The eye both samplers render from: x lifted along n by samplingEyeLift
// with the default DirectSamplerSettings::eyeOffset, so that a receiver
// never shadows itself.
inline Vec3 eyePoint(const Vec3& x, const Vec3& n) {
    const Scene& bench = benchScene();
    return x + glm::normalize(n) *
                   samplingEyeLift(bench.lights[0], x, DirectSamplerSettings{}.eyeOffset, bench.bounds.diagonal());
}

// How far the eye's lift can move an estimator's expectation:
// |E(eye) − E(x)| + |Lambert(eye) − Lambert(x)| (plain estimates E(eye);
// the control variate subtracts occluded samples seen from the eye from
// Lambert's value at x). Below 1e-4 of the value on the bench.
inline double liftAllowance(const Vec3& x, const Vec3& n) {
    const Vec3 eye = eyePoint(x, n);
    return std::abs(exactAt(eye, n) - exactAt(x, n)) + std::abs(lambertAt(eye, n) - lambertAt(x, n));
}

// The shadow of the bench occluder on the floor is all penumbra and lies in
// x ∈ [−0.9, 1.1], z ∈ [−1.1, 0.9] (BenchScene.h). Receivers further than
// `margin` outside it see the whole light.
inline bool clearOfPenumbra(const Vec3& p, double margin) {
    return p.x < -0.9 - margin || p.x > 1.1 + margin || p.z < -1.1 - margin || p.z > 0.9 + margin;
}

// `count` receivers of the 20×20 grid that see between 20% and 80% of the
// light, spread over the shadow: penumbra, away from the umbra, where the
// control variate's clamp at 0 and its "no visible sample gives 0" rule
// would bias it (on purpose: they trade a tiny bias for never returning a
// negative irradiance).
inline std::vector<ReceiverPoint> penumbraReceivers(size_t count) {
    std::vector<ReceiverPoint> candidates;
    for (const ReceiverPoint& r : makeBenchReceivers(20)) {
        const double visible = exactAt(r.position, r.normal), all = lambertAt(r.position, r.normal);
        if (visible > 0.2 * all && visible < 0.8 * all) candidates.push_back(r);
    }
    std::vector<ReceiverPoint> out;
    for (size_t k = 0; k < count && !candidates.empty(); ++k) out.push_back(candidates[k * candidates.size() / count]);
    return out;
}

}  // namespace ml::test
