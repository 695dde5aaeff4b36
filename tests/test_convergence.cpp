// Convergence of the progressive cache (ctest label `convergence`): the
// error of the direct-light image against the exact one falls as the sample
// budget doubles, and refinement puts its new vertices in penumbrae.
// Budgets are counted in samples, not seconds, so the results do not depend
// on the machine's speed or load.
#include "cache/IrradianceCache.h"
#include "TestSamplers.h"
#include "core/image/ImageMetrics.h"
#include "core/reference/ExactIrradiance.h"
#include "core/scenes/BenchScene.h"
#include "core/scenes/CornellBox.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "viewer/compositor/Compositor.h"
#include "viewer/bench/ExactDirectImage.h"

#include "GlTestContext.h"

#include <gtest/gtest.h>

#include <cstdio>

using namespace ml;

namespace {

test::SampleFn samplerFn(DirectLightSampler& sampler) {
    return [&sampler](size_t l, const Vec3& x, const Vec3& n, uint32_t seed) {
        const DirectSample s = sampler.sample(l, x, n, seed);
        const double vis = s.unoccluded > 0 ? std::clamp(s.cosineSolidAngle / s.unoccluded, 0.0, 1.0) : 1.0;
        return VertexSample{s.irradiance, vis, s.partiallyVisible()};
    };
}

// Refines until the cache has taken at least `samples` samples.
void refineUntil(IrradianceCache& cache, const test::SampleFn& fn, uint64_t samples,
                 const std::optional<RefinementCamera>& view) {
    auto sampler = samplerOf(fn);
    while (cache.totalSamples() < samples) {
        const RefineReport r = cache.refine(sampler, 512, 1, view);
        if (r.converged()) break;
    }
}

}  // namespace

TEST(Convergence, CornellDirectErrorFallsAsTheSampleBudgetDoubles) {
    const Scene scene = makeCornellBox();
    const Camera camera = *scene.camera;
    CompositorSettings cs;
    cs.width = cs.height = 64;
    cs.supersample = 2;
    ExactImageSettings es;
    es.width = es.height = 64;
    es.supersample = 2;
    const ImageRgb exact = renderExactDirect(scene, camera, es);

    CacheSettings settings;
    settings.maxEdgeFraction = 1.0 / 16;  // a coarse start, so refinement has work to do
    // This 64×64 image is small: let refinement go below its pixels, or it
    // would converge (nothing left to split) before the budgets run out.
    settings.minEdgePixels = 0.25;
    IrradianceCache cache(scene, settings);
    const uint64_t base = cache.totalVertices();
    DirectLightSampler sampler(test::glContext(), scene, DirectSamplerSettings{});
    Compositor compositor(test::glContext(), scene);
    const RefinementCamera view{camera, cs.width, cs.height};
    std::vector<double> errors;
    for (int k = 0; k < 4; ++k) {
        refineUntil(cache, samplerFn(sampler), base << k, view);
        const ImageRgb image = compositor.render(camera, {cache.copyMesh(0)}, cs);
        errors.push_back(relativeRmse(image, exact));
        std::printf("budget %llu samples: %zu vertices, relative RMSE %.4f%%, estimated error %.4f%%\n",
                    static_cast<unsigned long long>(base << k), cache.totalVertices(), 100 * errors.back(),
                    100 * cache.estimatedError(view));
    }
    // Each doubling must help: the budget goes where the error is.
    for (size_t k = 1; k < errors.size(); ++k) EXPECT_LT(errors[k], errors[k - 1]) << "budget step " << k;
    // The target is 1% at 256×256 within 30 s; at 8× the base
    // budget (a few seconds on llvmpipe) this image is well below it: 0.5%
    // leaves room for another GL implementation's rasterisation rules.
    EXPECT_LT(errors.back(), 0.005);
}

TEST(Convergence, NewVerticesLandInsideTheExactPenumbra) {
    const Scene scene = makeBenchScene();
    CacheSettings settings;
    settings.maxEdgeFraction = 1.0 / 16;
    IrradianceCache cache(scene, settings);
    const size_t base = cache.vertexCount(0);
    DirectLightSampler sampler(test::glContext(), scene, DirectSamplerSettings{});
    refineUntil(cache, samplerFn(sampler), 4 * base + 4000, std::nullopt);
    ASSERT_GT(cache.vertexCount(0), base + 1000);

    // Exact visibility at each new vertex: inside the penumbra when some
    // but not all of the light is seen (1e-9 of the unoccluded value
    // separates them from rounding). A vertex within one minimum edge of
    // the penumbra counts as in it: the split that made it was caused by
    // the penumbra's edge.
    const ExactDirect exact(scene);
    const IrradianceMeshCopy m = cache.copyMesh(0);
    size_t inside = 0, lit = 0;
    for (size_t v = base; v < m.positions.size(); ++v) {
        const double unoccluded = exact.unoccludedCosineSolidAngle(0, m.positions[v], m.normals[v]);
        if (!(unoccluded > 0)) continue;
        ++lit;
        const double visible = exact.cosineSolidAngle(0, m.positions[v], m.normals[v]);
        inside += visible > 1e-9 * unoccluded && visible < (1 - 1e-9) * unoccluded;
    }
    std::printf("%zu new vertices facing the light, %zu inside the exact penumbra\n", lit, inside);
    ASSERT_GT(lit, 500u);
    // Most: more than half. The floor's penumbra covers ~2×2 of its 3×3
    // area, so uniform refinement would put about 45% there (by area): the
    // bound asks for better than uniform.
    EXPECT_GT(double(inside) / double(lit), 0.6);
}
