// The ray-traced direct-light sampler (RayTracedLightSampler.h): the same
// jittered points as the raster sampler, decided by shadow rays. It must
// agree with the exact occluded irradiance as the raster sampler does
// (tests/test_direct_sampler.cpp's tolerances), and with the raster sampler
// itself sample for sample.
//
// Reference point, as in test_direct_sampler.cpp: both samplers look from an
// eye lifted off the receiver (samplingEyeLift), which moves an estimator's
// expectation by at most the "lift allowance" computed below; on the bench it
// is below 1e-4 of the value.
#include "core/Error.h"
#include "core/MeshUtil.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/reference/ExactIrradiance.h"
#include "core/reference/Lambert.h"
#include "core/scenes/BenchScene.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/direct/Jitter.h"
#include "gpu_sampling/direct/LightFrustum.h"
#include "gpu_sampling/direct/RayTracedLightSampler.h"

#include "BenchReference.h"
#include "GlTestContext.h"
#include "MeanAndError.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <set>

using namespace ml;
using test::benchScene, test::exactAt;
using test::clearOfPenumbra, test::eyePoint, test::liftAllowance, test::penumbraReceivers;

namespace {

const EmbreeScene& benchRays() {
    static const EmbreeScene rays(benchScene());
    return rays;
}

DirectSamplerSettings settingsFor(DirectEstimator estimator, int size, int bits) {
    DirectSamplerSettings s;
    s.method = DirectMethod::Jittered;
    s.estimator = estimator;
    s.imageSize = size;
    s.bits = bits;
    return s;
}

}  // namespace

TEST(RayTracedSampler, ControlVariateIsLambertWhereNothingOccludes) {
    // As for the raster sampler: with no sample occluded, the control
    // variate is Lambert's closed form at the receiver, nothing subtracted;
    // the sums differ from the polygon's only by rounding (1e-15), 1e-9
    // leaves room for another summation order.
    const RayTracedLightSampler s(benchRays(), settingsFor(DirectEstimator::ControlVariate, 32, 4));
    std::vector<ReceiverPoint> receivers;
    for (const ReceiverPoint& r : makeBenchReceivers(20))
        if (clearOfPenumbra(r.position, 0.02)) receivers.push_back(r);
    ASSERT_GE(receivers.size(), 100u);
    const Light& light = benchScene().lights[0];
    const std::vector<Vec3> polygon = {light.geometry[0][0], light.geometry[0][1], light.geometry[0][2],
                                       light.geometry[1][2]};
    for (size_t i = 0; i < receivers.size(); ++i) {
        const ReceiverPoint& r = receivers[i];
        const DirectSample d = s.sample(0, r.position, r.normal, jitter::seedFor(1, uint32_t(i)));
        const double lambert = cosineSolidAngle(r.position, r.normal, polygon);
        EXPECT_GT(d.lightSamples, 0u);
        EXPECT_EQ(d.visibleSamples, d.lightSamples) << "at (" << r.position.x << ", " << r.position.z << ")";
        EXPECT_EQ(d.frusta, 1u);
        EXPECT_NEAR(d.cosineSolidAngle, lambert, 1e-9 * lambert);
        EXPECT_NEAR(d.irradiance.g, lambert, 1e-9 * lambert);  // Ke = 1
    }
}

TEST(RayTracedSampler, MeanOfManyPassesConvergesToExact) {
    // Passes with fresh seeds are independent, identically distributed
    // estimates; unbiased, their mean lies within 4 standard errors of the
    // exact value except with probability ~1e-4 (Student's t, 47 degrees of
    // freedom), below 1 % over the 40 checks here; the seeds are fixed, so
    // the outcome is reproducible. The lift allowance (< 1e-4 of the value)
    // is a known offset of the expectation, added as in test_direct_sampler.
    // 32² images keep the test to a few million rays.
    constexpr int kPasses = 48;
    const std::vector<ReceiverPoint> receivers = penumbraReceivers(10);
    ASSERT_EQ(receivers.size(), 10u);
    for (auto estimator : {DirectEstimator::Plain, DirectEstimator::ControlVariate})
        for (int bits : {1, 4}) {
            const RayTracedLightSampler s(benchRays(), settingsFor(estimator, 32, bits));
            for (size_t i = 0; i < receivers.size(); ++i) {
                const ReceiverPoint& r = receivers[i];
                std::vector<double> passes;
                for (int k = 0; k < kPasses; ++k)
                    passes.push_back(
                        s.sample(0, r.position, r.normal, jitter::seedFor(3, uint32_t(i), 0, uint32_t(k))).cosineSolidAngle);
                test::expectUnbiased(passes, exactAt(r.position, r.normal), liftAllowance(r.position, r.normal),
                                     concat(directEstimatorName(estimator), " × ", bits, " bits at (", r.position.x,
                                            ", ", r.position.z, ")"));
            }
        }
}

TEST(RayTracedSampler, TestsTheSamePointsAsTheRasterSampler) {
    // Same frusta, same seeds, same jitter: the two samplers test the same
    // window points, and decide each the same way up to rounding (float
    // barycentrics on the GPU, Embree's float ray-triangle tests here). Only
    // samples within rounding of an occluder's outline can differ; a jittered
    // point lands there with probability ~1e-6 per sample, so over these
    // ~25,000 light samples per point we allow 2 differing samples, each
    // worth at most the largest weight of one sample (cv estimates differ by
    // the occluded weights only).
    DirectLightSampler raster(test::glContext(), benchScene(), settingsFor(DirectEstimator::ControlVariate, 64, 8));
    const RayTracedLightSampler rays(benchRays(), settingsFor(DirectEstimator::ControlVariate, 64, 8));
    for (const ReceiverPoint& r : penumbraReceivers(12)) {
        for (uint32_t pass = 0; pass < 2; ++pass) {
            const uint32_t seed = jitter::seedFor(11, pass);
            const DirectSample a = raster.sample(0, r.position, r.normal, seed);
            const DirectSample b = rays.sample(0, r.position, r.normal, seed);
            EXPECT_EQ(a.frusta, b.frusta);
            EXPECT_EQ(a.lightSamples, b.lightSamples) << "at (" << r.position.x << ", " << r.position.z << ")";
            const long differing = std::labs(long(a.visibleSamples) - long(b.visibleSamples));
            EXPECT_LE(differing, 2) << "at (" << r.position.x << ", " << r.position.z << ")";
            // The largest weight of one sample: cosθ·dω ≤ (pixel area at the
            // window's nearest point to the axis)/bits ≤ window area / (64²·8).
            const std::vector<SamplingFrustum> frusta =
                fitFrusta(visibleLightPieces(benchScene().lights[0], eyePoint(r.position, r.normal), r.normal),
                          eyePoint(r.position, r.normal),
                          benchScene().lights[0].geometry[0][1] - benchScene().lights[0].geometry[0][0],
                          DirectSamplerSettings{}.maxHalfAngleDegrees);
            ASSERT_EQ(frusta.size(), 1u);
            const double maxSample =
                (frusta[0].rightEdge - frusta[0].left) * (frusta[0].top - frusta[0].bottom) / (64.0 * 64.0 * 8.0);
            EXPECT_LE(std::abs(a.cosineSolidAngle - b.cosineSolidAngle), 2 * maxSample + 1e-12)
                << "raster " << a.cosineSolidAngle << ", ray traced " << b.cosineSolidAngle;
        }
    }
}

TEST(RayTracedSampler, NonPlanarLightIsUnbiasedWhereNothingOccludes) {
    // A light folded into a V (two triangles, 90° apart, both front faces
    // towards the receiver): not planar, so the sampler finds the light by
    // rays and uses the plain estimator. Nothing occludes, so the exact value
    // is Lambert's formula summed over both triangles. 4 standard errors of
    // 48 passes, as above.
    Scene scene;
    scene.name = "fold";
    Material lamp;
    lamp.name = "lamp";
    lamp.kd = Rgb(0.0);
    lamp.ke = Rgb(2.0);
    scene.materials = {lamp};
    Mesh mesh;
    mesh.name = "lamp";
    // Ridge along x at y = 1; wings down to y = 1.5 at z = ±0.5: a valley
    // seen from below, each face tilted 45° towards the floor.
    mesh.positions = {Vec3(-0.5, 1, 0), Vec3(0.5, 1, 0), Vec3(-0.5, 1.5, 0.5), Vec3(0.5, 1.5, -0.5)};
    mesh.triangles = {glm::uvec3(0, 1, 2), glm::uvec3(0, 3, 1)};
    mesh.materials = {0, 0};
    mesh.sourceLines = {0, 0};
    computeShadingNormals(mesh, 0.0);
    scene.meshes.push_back(mesh);
    scene.finalize();
    ASSERT_EQ(scene.lights.size(), 1u);
    ASSERT_FALSE(scene.lights[0].planar);
    const EmbreeScene rays(scene);
    const RayTracedLightSampler s(rays, settingsFor(DirectEstimator::ControlVariate, 32, 4));
    const Vec3 n(0, 1, 0);
    int checked = 0;
    for (const Vec3& x : {Vec3(0, 0, 0), Vec3(0.4, 0, -0.3), Vec3(-0.6, 0.2, 0.5)}) {
        double lambert = 0;
        for (const Triangle3& t : scene.lights[0].geometry) {
            ASSERT_GT(glm::dot(glm::cross(t[1] - t[0], t[2] - t[0]), x - t[0]), 0) << "a face turns away";
            lambert += cosineSolidAngle(x, n, {t[0], t[1], t[2]});
        }
        std::vector<double> passes;
        for (uint32_t k = 0; k < 48; ++k) passes.push_back(s.sample(0, x, n, jitter::seedFor(5, k)).cosineSolidAngle);
        // The eye's lift (1e-6 of the scene) moves Lambert's value by ~1e-6 of it.
        test::expectUnbiased(passes, lambert, 1e-5 * lambert, concat("Lambert at (", x.x, ", ", x.z, ")"));
        ++checked;
    }
    EXPECT_EQ(checked, 3);
}

TEST(RayTracedSampler, SameSeedRepeatsBitForBitAndDifferentSeedsDiffer) {
    const RayTracedLightSampler s(benchRays(), settingsFor(DirectEstimator::Plain, 32, 4));
    for (const ReceiverPoint& r : penumbraReceivers(3)) {
        const DirectSample a = s.sample(0, r.position, r.normal, 1234);
        s.sample(0, Vec3(0.3, 0, 0.3), Vec3(0, 1, 0), 99);
        const DirectSample b = s.sample(0, r.position, r.normal, 1234);
        EXPECT_EQ(std::memcmp(&a.cosineSolidAngle, &b.cosineSolidAngle, sizeof(double)), 0);
        std::set<double> values;
        for (uint32_t seed = 0; seed < 6; ++seed)
            values.insert(s.sample(0, r.position, r.normal, jitter::seedFor(9, seed)).cosineSolidAngle);
        EXPECT_EQ(values.size(), 6u);
    }
}

TEST(RayTracedSampler, RefusesTheOcclusionQueryAndBadSettings) {
    DirectSamplerSettings s;
    s.method = DirectMethod::OcclusionQuery;
    EXPECT_THROW(RayTracedLightSampler(benchRays(), s), InputError);
    s = {};
    s.bits = 3;
    EXPECT_THROW(RayTracedLightSampler(benchRays(), s), InputError);
    // A receiver behind the light sees nothing: zero, no frustum.
    const RayTracedLightSampler ok(benchRays(), DirectSamplerSettings{});
    const DirectSample above = ok.sample(0, Vec3(0, 2, 0), Vec3(0, 1, 0), 1);
    EXPECT_EQ(above.cosineSolidAngle, 0.0);
    EXPECT_EQ(above.frusta, 0u);
    EXPECT_THROW(ok.sample(0, Vec3(0, std::nan(""), 0), Vec3(0, 1, 0), 1), InputError);
}
