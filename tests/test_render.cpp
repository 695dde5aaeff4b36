// The first image end to end: cache v0 sampled by the GPU sampler or the
// exact reference, composited, on a small Cornell box render.
#include "cache/IrradianceCache.h"
#include "TestSamplers.h"
#include "core/image/ImageMetrics.h"
#include "core/reference/ExactIrradiance.h"
#include "core/scenes/CornellBox.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/gl/GlContext.h"
#include "viewer/compositor/Compositor.h"

#include "GlTestContext.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

using namespace ml;

namespace {

const Scene& cornell() {
    static const Scene scene = makeCornellBox();
    return scene;
}

// A coarse cache keeps each render under a few seconds on llvmpipe.
CacheSettings coarseCache() {
    CacheSettings s;
    s.maxEdgeFraction = 1.0 / 24.0;
    return s;
}

ImageRgb renderWith(const test::IrradianceFn& estimate, uint32_t seed, int passes = 1) {
    IrradianceCache cache(cornell(), coarseCache());
    test::sampleEveryVertex(cache, estimate, passes, seed);
    std::vector<IrradianceMeshCopy> views = cache.copyMeshes();
    Compositor compositor(test::glContext(), cornell());
    CompositorSettings cs;
    cs.width = 64;
    cs.height = 64;
    cs.supersample = 2;
    return compositor.render(*cornell().camera, views, cs);
}

test::IrradianceFn samplerEstimate(DirectLightSampler& sampler) {
    return [&sampler](size_t l, const Vec3& x, const Vec3& n, uint32_t seed) {
        return sampler.sample(l, x, n, seed).irradiance;
    };
}

}  // namespace

TEST(Render, SameSeedGivesTheSameImageBitForBit) {
    DirectLightSampler sampler(test::glContext(), cornell(), DirectSamplerSettings{});
    const ImageRgb a = renderWith(samplerEstimate(sampler), 7);
    const ImageRgb b = renderWith(samplerEstimate(sampler), 7);
    ASSERT_EQ(a.data.size(), b.data.size());
    EXPECT_EQ(0, std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)));
    // And a different seed draws different jitter somewhere in the penumbrae.
    DirectSamplerSettings plain;
    plain.estimator = DirectEstimator::Plain;
    DirectLightSampler plainSampler(test::glContext(), cornell(), plain);
    const ImageRgb c = renderWith(samplerEstimate(plainSampler), 7);
    const ImageRgb d = renderWith(samplerEstimate(plainSampler), 8);
    EXPECT_NE(0, std::memcmp(c.data.data(), d.data.data(), c.data.size() * sizeof(float)));
}

TEST(Render, JitteredImageMatchesTheExactDirectImage) {
    // Both images interpolate the same cache mesh, so they differ only by the
    // per-vertex sampling error. With the control variate that error lives in
    // penumbrae only; the bench measures a mean below 0.1% of the unoccluded
    // irradiance per pass. 1% relative RMSE leaves room for the few vertices
    // in the blocks' penumbrae while still failing on any systematic error
    // (a wrong cosine, pixel weight or frustum would cost several percent).
    const ExactDirect exact(cornell());
    const ImageRgb reference = renderWith(
        [&](size_t l, const Vec3& x, const Vec3& n, uint32_t) { return exact.irradiance(l, x, n); }, 1);
    DirectLightSampler sampler(test::glContext(), cornell(), DirectSamplerSettings{});
    const ImageRgb image = renderWith(samplerEstimate(sampler), 1);
    EXPECT_LT(relativeRmse(image, reference), 0.01);

    // The plain estimator is noisier but unbiased: averaging 4 passes keeps
    // it within 2%.
    DirectSamplerSettings plain;
    plain.estimator = DirectEstimator::Plain;
    DirectLightSampler plainSampler(test::glContext(), cornell(), plain);
    EXPECT_LT(relativeRmse(renderWith(samplerEstimate(plainSampler), 1, 4), reference), 0.02);
}

TEST(Render, EveryPixelFiniteAndTheLightShowsItsRadiance) {
    DirectLightSampler sampler(test::glContext(), cornell(), DirectSamplerSettings{});
    const ImageRgb image = renderWith(samplerEstimate(sampler), 3);
    for (float v : image.data) ASSERT_TRUE(std::isfinite(v));
    // The brightest pixel is on the light: Le = (17, 12, 4) plus the light's
    // own diffuse reflection of nothing (it does not light itself), box-filtered
    // with at most its neighbours: its red channel cannot exceed 17.
    double maxRed = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) maxRed = std::max(maxRed, image.at(x, y).r);
    EXPECT_LE(maxRed, 17.0 + 1e-4);
    EXPECT_GT(maxRed, 8.0);  // at least half a pixel of light is fully covered
}

TEST(Render, UnoccludedCacheVerticesHoldLambertsValue) {
    // Wherever the exact reference finds nothing in the way, the control
    // variate's estimate is Lambert's closed form at the receiver itself:
    // equal to rounding (1e-9 relative), whatever the jitter. The receiver is
    // the vertex's shading point (position(): a border vertex in the plane of
    // a surface meeting it is sampled just inside its faces).
    IrradianceCache cache(cornell(), coarseCache());
    DirectLightSampler sampler(test::glContext(), cornell(), DirectSamplerSettings{});
    const ExactDirect exact(cornell());
    test::sampleEveryVertex(cache, samplerEstimate(sampler), 1, 5);
    const IrradianceMeshCopy view = cache.copyMesh(0);
    size_t checked = 0;
    for (size_t v = 0; v < view.positions.size(); ++v) {
        const Vec3 p = cache.position(0, v);
        const Vec3 n = cache.normal(0, v);
        const double visible = exact.cosineSolidAngle(0, p, n);
        const double unoccluded = exact.unoccludedCosineSolidAngle(0, p, n);
        if (!(visible > 0) || visible < unoccluded * (1 - 1e-12)) continue;
        const Rgb e = exact.irradiance(0, p, n);
        ASSERT_NEAR(view.irradiance[v].r, e.r, 1e-9 * e.r) << "vertex " << v << " at " << p.x << "," << p.y << "," << p.z;
        ++checked;
    }
    EXPECT_GT(checked, 100u);
}
