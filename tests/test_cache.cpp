// The cache's refinement, file and worker thread, driven by analytic
// irradiance functions (no GL): what is split, where, how a saved cache
// resumes, which files are refused, and what readers of snapshots see.
#include "cache/CacheWorker.h"
#include "cache/EdgeOnSurfaces.h"
#include "cache/IndirectSolver.h"
#include "cache/IrradianceCache.h"
#include "TestSamplers.h"
#include "TestScenes.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/scenes/BenchScene.h"
#include "core/scenes/CornellBox.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <thread>

using namespace ml;

namespace {

const Scene& bench() {
    static const Scene scene = makeBenchScene();
    return scene;
}

CacheSettings coarse() {
    CacheSettings s;
    s.maxEdgeFraction = 1.0 / 16;  // bench diagonal ≈ 4.3: base edges ≤ 0.27
    s.minEdgeFraction = 1.0 / 1024;
    return s;
}

// A shadow edge at x = 0.3: bright on one side, dark on the other, with a
// penumbra 0.1 wide that the "sampler" reports as partial visibility.
VertexSample step(size_t, const Vec3& x, const Vec3&, uint32_t) {
    const double d = x.x - 0.3;
    const double vis = std::clamp(0.5 - d / 0.1, 0.0, 1.0);
    return {Rgb(0.05 + 0.95 * vis), vis, vis > 0 && vis < 1};
}

// The same with noise drawn from the seed in the penumbra, so resampling
// changes values and the seeds used must repeat exactly.
VertexSample noisyStep(size_t l, const Vec3& x, const Vec3& n, uint32_t seed) {
    VertexSample s = step(l, x, n, seed);
    if (s.partial) s.irradiance *= 1 + 0.05 * (double(hash32(seed) & 0xffff) / 65535.0 - 0.5);
    return s;
}

using SampleFunction = VertexSample (*)(size_t, const Vec3&, const Vec3&, uint32_t);
FunctionSampler<SampleFunction> stepSampler(step), noisyStepSampler(noisyStep);

IrradianceMeshCopy viewOf(const IrradianceCache& c) { return c.copyMesh(0); }

void expectSameView(const IrradianceMeshCopy& a, const IrradianceMeshCopy& b) {
    ASSERT_EQ(a.positions.size(), b.positions.size());
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    for (size_t i = 0; i < a.positions.size(); ++i) {
        ASSERT_EQ(a.positions[i], b.positions[i]) << "vertex " << i;
        ASSERT_EQ(a.irradiance[i], b.irradiance[i]) << "vertex " << i;
        ASSERT_EQ(a.samples[i], b.samples[i]) << "vertex " << i;
    }
    // The same triangles; their order may differ (a split reuses one of
    // the faces it replaces, which one depends on halfedge numbering, and
    // nothing drawn or refined depends on face order).
    auto canonical = [](std::vector<glm::uvec3> tris) {
        std::vector<std::array<uint32_t, 3>> out;
        for (glm::uvec3 t : tris) {
            while (t.x > t.y || t.x > t.z) t = glm::uvec3(t.y, t.z, t.x);  // rotate, keeping orientation
            out.push_back({t.x, t.y, t.z});
        }
        std::sort(out.begin(), out.end());
        return out;
    };
    EXPECT_TRUE(canonical(a.triangles) == canonical(b.triangles));
}

// Total length of the edges used by exactly one triangle: the mesh's border.
// A T-vertex inside an object would add border where there was none.
double borderLength(const IrradianceMeshCopy& m) {
    std::map<std::pair<uint32_t, uint32_t>, int> uses;
    for (const glm::uvec3& t : m.triangles)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = t[k], b = t[(k + 1) % 3];
            uses[{std::min(a, b), std::max(a, b)}]++;
        }
    double len = 0;
    for (const auto& [e, n] : uses)
        if (n == 1) len += glm::length(m.positions[e.first] - m.positions[e.second]);
    return len;
}

std::string tempPath(const std::string& name) {
    return (std::filesystem::temp_directory_path() / ("meshlight_test_cache_" + name)).string();
}

}  // namespace

TEST(CacheLayout, DirectLightBehindALightsPlaneReadsZeroOnAWallCrossingIt) {
    // A panel 2 cm under a ceiling and a wall from the floor to the ceiling
    // beside it: the wall's top 2 cm lie behind the panel's plane and get
    // none of its light, and below the plane the light grows from 0. Direct
    // light's base mesh is cut along the plane (CacheSettings::
    // lightPlaneCuts): no triangle spans it, so linear interpolation reads
    // exactly 0 above it. Uncut, a triangle spans it and spreads the light
    // below over the strip (what the office's walls showed under the ceiling).
    const double h = 0.02;
    const std::vector<Material> materials = {Material::diffuse("light", Rgb(0.5), Rgb(1.0)),
                                             Material::diffuse("grey", Rgb(0.5))};
    const Scene scene =
        test::sceneOf("panel and wall", materials,
                      {test::quadMesh("ceiling", 1, Vec3(-1, 1, -1), 2.0 * test::kX, 2.0 * test::kZ),
                       test::quadMesh("panel", 0, Vec3(-0.3, 1 - h, -0.3), 0.6 * test::kX, 0.6 * test::kZ),
                       test::quadMesh("floor", 1, Vec3(-1, 0, -1), 2.0 * test::kZ, 2.0 * test::kX),
                       test::quadMesh("wall", 1, Vec3(1, 0, -1), 2.0 * test::kZ, 1.0 * test::kY)});
    ASSERT_EQ(scene.lights.size(), 1u);
    // The light as it is near its plane: nothing behind it, growing
    // linearly in front (the panel seen edge-on from the wall).
    const double plane = 1 - h;
    const auto exact = [plane](size_t, const Vec3& x, const Vec3&, uint32_t) {
        return VertexSample{Rgb(std::max(0.0, plane - x.y)), 1.0, false};
    };
    for (const bool cuts : {true, false}) {
        CacheSettings settings;
        settings.lightPlaneCuts = cuts;
        IrradianceCache cache(scene, settings);
        test::sampleEveryVertex(cache, exact, 1, 1);
        const IrradianceMeshCopy m = cache.copyMesh(0);
        // The most light linear interpolation puts on the wall above the
        // plane: at a corner above it, or where an edge crosses it.
        double above = 0, most = 0;
        bool spans = false;
        for (const glm::uvec3& t : m.triangles) {
            bool wall = true;
            for (int k = 0; k < 3; ++k) wall = wall && std::abs(m.positions[t[k]].x - 1) < 1e-9;
            if (!wall) continue;
            for (int k = 0; k < 3; ++k) {
                const Vec3 &p = m.positions[t[k]], &q = m.positions[t[(k + 1) % 3]];
                const double ep = luminance(m.irradiance[t[k]]), eq = luminance(m.irradiance[t[(k + 1) % 3]]);
                most = std::max(most, ep);
                // Corners on the plane (within rounding) count as above.
                if (p.y > plane - 1e-9) above = std::max(above, ep);
                if (std::min(p.y, q.y) < plane - 1e-9 && std::max(p.y, q.y) > plane + 1e-9) {
                    spans = true;
                    const double f = (plane - p.y) / (q.y - p.y);
                    above = std::max(above, (1 - f) * ep + f * eq);
                }
            }
        }
        ASSERT_GT(most, 0.0);
        if (cuts) {
            EXPECT_FALSE(spans);
            EXPECT_LE(above, 1e-9 * most);
        } else {
            EXPECT_TRUE(spans);
            EXPECT_GT(above, 0.01 * most);
        }
    }
}

TEST(CacheRefinement, ALinearSignalNeedsNoSplit) {
    // The plane fitted to a vertex's neighbours reproduces any linear
    // signal, on any ring and at borders: nothing to split, nothing to
    // resample, and the predicted error is zero up to rounding.
    IrradianceCache cache(bench(), coarse());
    auto linear = samplerOf([](size_t, const Vec3& x, const Vec3&, uint32_t) {
        return VertexSample{Rgb(1 + 0.3 * x.x + 0.2 * x.z + 0.1 * x.y), 1.0, false};
    });
    cache.refine(linear, 1 << 20, 1);  // samples the base mesh
    const RefineReport r = cache.refine(linear, 1 << 20, 1);
    EXPECT_EQ(0u, r.splits);
    EXPECT_EQ(0u, r.resamples);
    EXPECT_TRUE(r.converged());
    EXPECT_LT(cache.estimatedError(), 1e-9);
}

TEST(CacheRefinement, TheLightACacheHoldsIsItsMeshesIntegral) {
    // What the worker weighs indirect light's error by (bounce 1's light
    // over direct light's): each vertex's mean times a third of its faces'
    // area, which for the linear interpolation the meshes show is exactly
    // each triangle's area times the mean of its corners. Unsampled, a
    // cache holds nothing; sampled with different light per mesh, the sum
    // over meshes.
    IrradianceCache cache(bench(), coarse());
    EXPECT_EQ(0.0, cache.integratedLuminance());
    auto linear = samplerOf([](size_t l, const Vec3& x, const Vec3&, uint32_t) {
        return VertexSample{Rgb(1 + 0.3 * x.x + 0.2 * x.z + 0.1 * x.y) * double(l + 1), 1.0, false};
    });
    cache.refine(linear, 1 << 20, 1);
    cache.refine(linear, 1 << 20, 1);
    double expected = 0;
    for (const IrradianceMeshCopy& m : cache.copyMeshes()) expected += luminance(test::integrate(m));
    ASSERT_GT(expected, 0.0);
    // Only the order of the sums differs.
    EXPECT_NEAR(expected, cache.integratedLuminance(), 1e-9 * expected);
}

TEST(CacheRefinement, UniformSplitsHalveTheBaseWhereTheLightIsLinear) {
    // The same linear signal with CacheSettings::uniformEdgeFraction half
    // the base edge: no edge asks for a split by its error, yet every lit
    // edge longer than the uniform edge is split, and every new vertex is
    // sampled in the round that made it.
    CacheSettings s = coarse();
    s.uniformEdgeFraction = s.maxEdgeFraction / 2;
    IrradianceCache cache(bench(), s);
    auto linear = samplerOf([](size_t, const Vec3& x, const Vec3&, uint32_t) {
        return VertexSample{Rgb(1 + 0.3 * x.x + 0.2 * x.z + 0.1 * x.y), 1.0, false};
    });
    const size_t base = cache.totalVertices();
    cache.refine(linear, 1 << 20, 1);  // samples the base mesh
    size_t splits = 0;
    for (int round = 0; round < 40; ++round) {
        const RefineReport r = cache.refine(linear, 1 << 20, 1);
        splits += r.splits;
        EXPECT_EQ(0u, cache.unsampledCount());
        if (r.converged()) break;
    }
    EXPECT_GT(cache.totalVertices(), 2 * base);
    EXPECT_EQ(cache.totalVertices(), base + splits);
    const double uniform = s.uniformEdgeFraction * bench().bounds.diagonal();
    const IrradianceMeshCopy m = viewOf(cache);
    for (const glm::uvec3& t : m.triangles)
        for (int k = 0; k < 3; ++k)
            ASSERT_LE(glm::length(m.positions[t[k]] - m.positions[t[(k + 1) % 3]]), uniform * (1 + 1e-9));
    // The signal is linear: the new vertices hold it exactly, and the
    // estimate stays zero.
    EXPECT_LT(cache.estimatedError(), 1e-9);
    // Without the setting the same signal keeps its base.
    IrradianceCache plain(bench(), coarse());
    plain.refine(linear, 1 << 20, 1);
    EXPECT_EQ(0u, plain.refine(linear, 1 << 20, 1).splits);
    // An edge is at most the base's longest fraction; one above it is
    // refused.
    CacheSettings bad = coarse();
    bad.uniformEdgeFraction = 2 * bad.maxEdgeFraction;
    EXPECT_THROW(bad.validate(), InputError);
}

TEST(CacheRefinement, TheEstimateDoesNotGrowWithTheNumberOfLights) {
    // The bench's unit light over its floor, and the same light cut into
    // four quarters (four lights, four meshes), each giving a quarter of the
    // same curved irradiance. The light is the same, and so is its relative
    // error: each mesh's errors are relative to its own light's level, so
    // the estimate is their RMS over the meshes, not that times the number
    // of meshes (which made the office's 13 direct meshes read 10.7% where
    // the whole image measured 4.7%). The tone curve
    // weighs a quarter of the level a little differently: within 1.25x.
    Material emitter, grey;
    emitter.ke = Rgb(1.0);
    grey.kd = Rgb(0.5);
    const Scene one = test::sceneOf("one light", {emitter, grey}, {test::unitLight(), test::floorMesh()});
    std::vector<Mesh> quarters;
    for (double x : {-0.5, 0.0})
        for (double z : {-0.5, 0.0})
            quarters.push_back(test::quadMesh("light", 0, Vec3(x, 1.0, z), 0.5 * test::kX, 0.5 * test::kZ));
    quarters.push_back(test::floorMesh());
    const Scene four = test::sceneOf("four lights", {emitter, grey}, quarters);
    ASSERT_EQ(one.lights.size(), 1u);
    ASSERT_EQ(four.lights.size(), 4u);
    auto curved = [](const Vec3& x) { return 1 + 4 * x.x * x.x + 2 * x.z * x.z; };
    auto whole = samplerOf([&](size_t, const Vec3& x, const Vec3&, uint32_t) {
        return VertexSample{Rgb(curved(x)), 1.0, false};
    });
    auto quarter = samplerOf([&](size_t, const Vec3& x, const Vec3&, uint32_t) {
        return VertexSample{Rgb(curved(x) / 4), 1.0, false};
    });
    IrradianceCache a(one, coarse()), b(four, coarse());
    a.refine(whole, 1 << 20, 1);  // samples the base meshes
    b.refine(quarter, 1 << 20, 1);
    const double ea = a.estimatedError(), eb = b.estimatedError();
    std::printf("one light: estimated %.3f%%; four: %.3f%%\n", 100 * ea, 100 * eb);
    ASSERT_GT(ea, 0.001);  // the curvature is seen
    EXPECT_LT(eb, 1.25 * ea);
    EXPECT_GT(eb, ea / 1.25);
}

TEST(CacheRefinement, ASpikeBesideALightCountsAsAtMostTheLevelShown) {
    // Irradiance 10,000 times the floor's at one corner of the bench's
    // light (a receiver touching an emitter): the plane fitted around its
    // dark neighbours misses them by thousands of times their level. What
    // an edge counts in the estimate is capped at 100% of the level shown
    // (showing nothing, or twice the light); uncapped it read 132% here.
    // Splitting is not capped: the spike's edges still come first.
    auto spiked = samplerOf([](size_t, const Vec3& x, const Vec3&, uint32_t) {
        const double d2 = glm::dot(x - Vec3(0.5, 0.0, 0.5), x - Vec3(0.5, 0.0, 0.5));
        return VertexSample{Rgb(1 + 1e4 * std::exp(-d2 / 0.002)), 1.0, false};
    });
    IrradianceCache cache(bench(), coarse());
    cache.refine(spiked, 1 << 20, 1);
    const double e = cache.estimatedError();
    std::printf("estimated %.3f%%\n", 100 * e);
    EXPECT_GT(e, 0.01);
    EXPECT_LE(e, 1.0);
    const RefineReport r = cache.refine(spiked, 1 << 20, 1);
    EXPECT_GT(r.splits, 0u);
}

// The step of `step`, where the bright side (x < 0.25) is answered without
// the GPU, as an unoccluded pair would be, and the rest needs it; counts
// both kinds of call.
class TwoKindSampler final : public VertexSampler {
public:
    VertexSample sample(size_t l, const Vec3& x, const Vec3& n, uint32_t seed) override {
        ++gpu;
        return step(l, x, n, seed);
    }
    bool sampleWithoutGpu(size_t l, const Vec3& x, const Vec3& n, uint32_t seed, VertexSample& out) override {
        ++asked;
        if (!cheap(x)) return false;
        out = step(l, x, n, seed);
        return true;
    }
    static bool cheap(const Vec3& x) { return x.x < 0.25; }
    size_t gpu = 0, asked = 0;
};

TEST(CacheRefinement, TheFirstPassTakesWhatNeedsNoGpuFirstAndFillsLikeWithLike) {
    IrradianceCache cache(bench(), coarse());
    const size_t n = cache.vertexCount(0);
    size_t cheapCount = 0;
    for (size_t v = 0; v < n; ++v) cheapCount += TwoKindSampler::cheap(cache.position(0, v));
    ASSERT_GT(cheapCount, 50u);
    ASSERT_GT(n - cheapCount, 50u);

    // A round smaller than the cheap vertices takes only cheap ones and
    // asks no vertex twice.
    TwoKindSampler sampler;
    const size_t first = cheapCount / 2;
    EXPECT_EQ(first, cache.refine(sampler, first, 1).estimates);
    EXPECT_EQ(0u, sampler.gpu);
    const size_t askedFirst = sampler.asked;
    EXPECT_GE(askedFirst, first);
    // The next takes the other cheap ones, then 20 that need the GPU.
    EXPECT_EQ(cheapCount - first + 20, cache.refine(sampler, cheapCount - first + 20, 1).estimates);
    EXPECT_EQ(20u, sampler.gpu);
    EXPECT_EQ(n, sampler.asked) << "every vertex is asked once";

    // A copy fills the unsampled vertices that need the GPU from sampled
    // ones of their kind (here all on the dark side, 0.05), not from their
    // bright neighbours across the edge. On the floor (the bench's largest
    // object, many of whose dark vertices were sampled); a small object
    // none of whose dark vertices has a sample yet (the light's own quad)
    // takes what its other vertices saw.
    const IrradianceMeshCopy m = cache.copyMesh(0);
    size_t filledDark = 0;
    for (size_t v = 0; v < n; ++v) {
        if (m.samples[v] || TwoKindSampler::cheap(m.positions[v])) continue;
        const bool floor = m.normals[v].y > 0.5 && std::abs(m.positions[v].y) < 1e-9;
        if (floor && m.positions[v].x > 0.45) {  // past the penumbra: the sampled dark side
            EXPECT_NEAR(0.05, m.irradiance[v].r, 1e-12) << "vertex " << v << " at x " << m.positions[v].x;
            ++filledDark;
        }
    }
    EXPECT_GT(filledDark, 10u);
    // The same cache as one sampled in plain rounds: every value is the
    // sampler's at that vertex.
    cache.refine(sampler, 1 << 20, 1);
    const IrradianceMeshCopy all = cache.copyMesh(0);
    for (size_t v = 0; v < n; ++v) ASSERT_EQ(step(0, all.positions[v], all.normals[v], 0).irradiance, all.irradiance[v]);
}

TEST(CacheRefinement, NewVerticesGoWhereTheSignalSteps) {
    IrradianceCache cache(bench(), coarse());
    const size_t base = cache.vertexCount(0);
    for (int round = 0; round < 12; ++round) cache.refine(stepSampler, 400, 1);
    const IrradianceMeshCopy m = viewOf(cache);
    ASSERT_GT(m.positions.size(), base + 500);
    // Within two base edges of the step (0.54 here), for every new vertex
    // but those that longest-edge propagation adds to keep the mesh
    // conforming: a chain climbs to edges at most 2× longer each step, and
    // is short, so 90% is a loose bound.
    const double band = 2 * coarse().maxEdgeFraction * bench().bounds.diagonal();
    size_t near = 0;
    for (size_t v = base; v < m.positions.size(); ++v) near += std::abs(m.positions[v].x - 0.3) < band;
    EXPECT_GT(double(near) / double(m.positions.size() - base), 0.9);
    // Finer near the step than anywhere else: its edges were halved at
    // least twice more than any elsewhere.
    double shortestNear = kInf, shortestFar = kInf;
    for (const glm::uvec3& t : m.triangles)
        for (int k = 0; k < 3; ++k) {
            const Vec3 a = m.positions[t[k]], b = m.positions[t[(k + 1) % 3]];
            const double len = glm::length(a - b);
            double& shortest = std::abs(0.5 * (a.x + b.x) - 0.3) < 0.1 ? shortestNear : shortestFar;
            shortest = std::min(shortest, len);
        }
    EXPECT_LE(shortestNear, 0.25 * shortestFar);
}

// With a sampler whose every sample is noisy (an indirect gather), a
// vertex's residual less twice its standard error asks for splits: a 30%
// step in the light, sampled once per vertex (standard error taken as 3%),
// leaves residuals whose quarter, less the noise, stays under the 4% split
// tolerance the indirect meshes use. Where the samples report surfaces
// nearer than the edges are long (VertexSample::reach: a contact, a
// corner), the light may step along the edge: the difference of its ends,
// less their noise, is the predicted error, 0.5·0.3/1 − 0.06 ≈ 0.09, and the
// edges across the step split. The same light without a reach splits far
// less there.
TEST(CacheRefinement, AStepBesideANearSurfaceSplitsWhereNoiseHidesItsResidual) {
    CacheSettings s = coarse();
    s.sampleNoise = 0.03;
    s.splitTolerance = 0.04;
    s.maxSamplesPerVertex = 1;  // the noise stays as assumed: nothing resampled away
    const auto refined = [&](double reach) {
        IrradianceCache cache(bench(), s);
        const size_t base = cache.vertexCount(0);
        auto sampler = samplerOf([reach](size_t, const Vec3& x, const Vec3&, uint32_t) {
            VertexSample v;
            v.irradiance = Rgb(x.x < 0.3 ? 1.0 : 0.7);
            v.reach = reach;
            return v;
        });
        for (int round = 0; round < 12; ++round) cache.refine(sampler, 400, 1);
        const IrradianceMeshCopy m = viewOf(cache);
        const double band = 2 * s.maxEdgeFraction * bench().bounds.diagonal();
        size_t near = 0;
        for (size_t v = base; v < m.positions.size(); ++v) near += std::abs(m.positions[v].x - 0.3) < band;
        return near;
    };
    const size_t withReach = refined(0.01), without = refined(std::numeric_limits<double>::infinity());
    std::printf("new vertices near the step: %zu with a reach of 0.01, %zu without\n", withReach, without);
    EXPECT_GT(withReach, 200u);
    EXPECT_GT(withReach, 4 * without);
}

// Noisy samplers' settings (3% assumed per sample) under which every vertex
// is sampled again, up to `samples` times, and none split (the light these
// tests give is uniform).
CacheSettings resampledUnsplit(uint32_t samples) {
    CacheSettings s = coarse();
    s.sampleNoise = 0.03;
    s.noiseTolerance = 1e-3;
    s.splitTolerance = 0.9;
    s.maxSamplesPerVertex = samples;
    return s;
}

// A sampler whose every sample is noisy is taken to err by the assumed
// sampleNoise per sample only until the vertices sampled more than once
// measure it: samples uniform within 1 ± 0.2·√3 (standard deviation 0.2)
// measure 0.2. Tolerance 7.5%: the pooled estimate is a ratio of sums over
// the bench's 356 vertices of 4 samples each, ~1,070 degrees of freedom
// (its relative standard error is 1.3% for this distribution), and the
// means' own spread lowers it by about 0.2²/2n, 0.5%.
TEST(CacheRefinement, OneSamplesNoiseIsMeasuredOnceVerticesAreResampled) {
    constexpr double kSpread = 0.2;
    auto noisy = samplerOf([](size_t, const Vec3&, const Vec3&, uint32_t seed) {
        const double u = hash32(seed) * (1.0 / 4294967296.0);
        return VertexSample{Rgb(1 + kSpread * std::sqrt(3.0) * (2 * u - 1)), 1.0, false};
    });
    CacheSettings s = resampledUnsplit(4);
    IrradianceCache cache(bench(), s);
    cache.refine(noisy, 1 << 20, 1);  // one sample each: nothing measured yet
    EXPECT_EQ(cache.sampleNoise(), 0.03);
    for (int round = 0; round < 3; ++round) cache.refine(noisy, 1 << 20, 1);
    std::printf("measured noise of one sample: %.4f (%zu vertices)\n", cache.sampleNoise(), cache.totalVertices());
    EXPECT_NEAR(cache.sampleNoise(), kSpread, 0.075 * kSpread);
    // Direct light's samplers (sampleNoise 0) can be exact: nothing is assumed or measured.
    s.sampleNoise = 0;
    IrradianceCache direct(bench(), s);
    for (int round = 0; round < 4; ++round) direct.refine(noisy, 1 << 20, 1);
    EXPECT_EQ(direct.sampleNoise(), 0.0);
}

// Noise probes (IrradianceCache::setNoiseProbes) measure a first pass's
// noise before any vertex is resampled: every 2nd vertex (by a hash of its
// index) of the bench's 356 takes a second sample of the same spread as
// above (0.2). Tolerance 15%: the probes give about 178 degrees of
// freedom, over which the spread of a uniform distribution's pooled
// standard deviation is about 3.4%; four of those.
TEST(CacheRefinement, NoiseProbesMeasureTheFirstPasssNoise) {
    constexpr double kSpread = 0.2;
    auto noisy = samplerOf([](size_t, const Vec3&, const Vec3&, uint32_t seed) {
        const double u = hash32(seed) * (1.0 / 4294967296.0);
        return VertexSample{Rgb(1 + kSpread * std::sqrt(3.0) * (2 * u - 1)), 1.0, false};
    });
    IrradianceCache cache(bench(), resampledUnsplit(4));
    cache.setNoiseProbes(2);
    const RefineReport first = cache.refine(noisy, 1 << 20, 1);
    size_t vertices = 0, probed = 0;
    for (const IrradianceMeshCopy& m : cache.copyMeshes())
        for (uint32_t n : m.samples) {
            ASSERT_TRUE(n == 1 || n == 2) << n;
            vertices += 1, probed += n == 2;
        }
    EXPECT_EQ(first.estimates, vertices + probed);
    EXPECT_GT(probed, vertices * 35 / 100);
    EXPECT_LT(probed, vertices * 65 / 100);
    std::printf("first pass: %zu of %zu vertices probed, noise of one sample %.4f\n", probed, vertices,
                cache.sampleNoise());
    EXPECT_NEAR(cache.sampleNoise(), kSpread, 0.15 * kSpread);
}

// A vertex's samples weigh by their work (VertexSample::work: a ray
// gather's rays), their variance going as its inverse: a first pass's
// cheap gather counts for less in the mean and for more in the noise.
// Exact: one sample of 2 at work 1 and one of 1 at work 3 make a mean of
// (2 + 3) / 4 = 1.25 and Σ w (y − ȳ)² = 0.5625 + 0.1875 = 0.75, so the
// mean's variance is 0.75 / (2 − 1) / 4 = 0.1875.
TEST(CacheRefinement, SamplesWeighByTheirWork) {
    int round = 0;
    auto sampler = samplerOf([&round](size_t, const Vec3&, const Vec3&, uint32_t) {
        VertexSample v;
        v.irradiance = Rgb(round == 0 ? 2.0 : 1.0);
        v.work = round == 0 ? 1.0 : 3.0;
        return v;
    });
    CacheSettings s = resampledUnsplit(2);
    IrradianceCache cache(bench(), s);
    cache.refine(sampler, 1 << 20, 1);
    round = 1;
    cache.refine(sampler, 1 << 20, 1);
    const IrradianceMeshCopy m = viewOf(cache);
    ASSERT_GT(m.positions.size(), 0u);
    for (size_t v = 0; v < m.positions.size(); ++v) {
        ASSERT_EQ(m.samples[v], 2u);
        EXPECT_EQ(m.irradiance[v], Rgb(1.25));
        EXPECT_NEAR(m.standardError[v].g, std::sqrt(0.1875), 1e-12);
    }
}

// A sampler that measures each sample's own variance (a ray gather's rays'
// scatter, VertexSample::ownVariance) says which vertices are noisy from
// their first sample: until resampling measures the noise, the assumed
// sampleNoise (3%) is spread over the vertices by their own variances,
// scaled so that Σ noise² = sampleNoise²·Σ mean² (exact here: every mean is
// 1, so a vertex's standard error is √(0.03²·N·own / Σ own)); and the
// vertices whose samples scattered are resampled first. Here the samples
// of the vertices not facing up (the blocks' sides and the wall, not the
// floor and the tops) say 10% and the rest 0.1%: a budget of half those
// vertices resamples them only. Without the own variances every vertex
// would count 3% and the resamples would go by area and light.
TEST(CacheRefinement, VerticesWhoseSamplesScatteredAreResampledFirst) {
    const auto ownVariance = [](const Vec3& n) { return n.y > 0.5 ? 1e-6 : 0.01; };
    auto sampler = samplerOf([&](size_t, const Vec3&, const Vec3& n, uint32_t) {
        VertexSample v;
        v.irradiance = Rgb(1.0);
        v.ownVariance = ownVariance(n);
        return v;
    });
    IrradianceCache cache(bench(), resampledUnsplit(2));
    cache.refine(sampler, 1 << 20, 1);
    size_t vertices = 0, noisy = 0;
    double sumOwn = 0;
    for (const IrradianceMeshCopy& m : cache.copyMeshes())
        for (const Vec3& n : m.normals) vertices++, noisy += !(n.y > 0.5), sumOwn += ownVariance(n);
    ASSERT_GT(noisy, 20u);
    ASSERT_LT(noisy, vertices / 2);
    for (const IrradianceMeshCopy& m : cache.copyMeshes())
        for (size_t v = 0; v < m.positions.size(); ++v)
            EXPECT_NEAR(m.standardError[v].g, std::sqrt(0.03 * 0.03 * double(vertices) * ownVariance(m.normals[v]) / sumOwn),
                        1e-12);
    const RefineReport r = cache.refine(sampler, noisy / 2, 2);
    EXPECT_EQ(r.resamples, noisy / 2);
    size_t resampled = 0, resampledQuiet = 0;
    for (const IrradianceMeshCopy& m : cache.copyMeshes())
        for (size_t v = 0; v < m.positions.size(); ++v)
            if (m.samples[v] == 2) resampled++, resampledQuiet += m.normals[v].y > 0.5;
    EXPECT_EQ(resampled, noisy / 2);
    EXPECT_EQ(resampledQuiet, 0u);
}

// Once the vertices are resampled, the own variances' scale is measured:
// their samples' spreads pooled, over what their own variances said
// (Σ (n−1)·s² / Σ (n−1)·own), and each vertex's variance pools its spread
// (n − 1 degrees of freedom) with its own variance so scaled
// (kOwnVarianceFreedom = 2). Exact: every vertex sampled 1.0 then 1.2
// (Σ (y − ȳ)² = 0.02), the samples of those facing up saying 0.04 each
// and the rest 0.01; so the scale is 0.02·N / Σ own, and a
// vertex's standard error √((0.02 + 2·scale·own) / 3 / 2).
TEST(CacheRefinement, TheOwnVariancesScaleIsMeasuredAndPooledWithTheSpread) {
    int round = 0;
    const auto ownVariance = [](const Vec3& n) { return n.y > 0.5 ? 0.04 : 0.01; };
    auto sampler = samplerOf([&](size_t, const Vec3&, const Vec3& n, uint32_t) {
        VertexSample v;
        v.irradiance = Rgb(round == 0 ? 1.0 : 1.2);
        v.ownVariance = ownVariance(n);
        return v;
    });
    IrradianceCache cache(bench(), resampledUnsplit(2));
    cache.refine(sampler, 1 << 20, 1);
    round = 1;
    cache.refine(sampler, 1 << 20, 1);
    double vertices = 0, sumOwn = 0;
    for (const IrradianceMeshCopy& m : cache.copyMeshes())
        for (size_t v = 0; v < m.positions.size(); ++v) {
            ASSERT_EQ(m.samples[v], 2u);
            vertices += 1, sumOwn += ownVariance(m.normals[v]);
        }
    ASSERT_GE(vertices, 64.0);  // kMeasuredNoiseFreedom
    const double scale = 0.02 * vertices / sumOwn;
    for (const IrradianceMeshCopy& m : cache.copyMeshes())
        for (size_t v = 0; v < m.positions.size(); ++v)
            EXPECT_NEAR(m.standardError[v].g, std::sqrt((0.02 + 2 * scale * ownVariance(m.normals[v])) / 3 / 2), 1e-12);
}

// Samples whose spread goes as 1/√work (0.4 at work 1, 0.2 at work 4)
// measure one full sample's noise (work 4, the most a sample took) as 0.2:
// the pooled spread is of a unit of work. Tolerance as above (7.5%).
TEST(CacheRefinement, TheMeasuredNoiseIsAFullSamples) {
    int round = 0;
    auto sampler = samplerOf([&round](size_t, const Vec3&, const Vec3&, uint32_t seed) {
        const double u = hash32(seed) * (1.0 / 4294967296.0), work = round == 0 ? 1.0 : 4.0;
        VertexSample v;
        v.irradiance = Rgb(1 + 0.4 / std::sqrt(work) * std::sqrt(3.0) * (2 * u - 1));
        v.work = work;
        return v;
    });
    CacheSettings s = resampledUnsplit(4);
    IrradianceCache cache(bench(), s);
    for (; round < 4; ++round) cache.refine(sampler, 1 << 20, 1);
    std::printf("measured noise of a full sample: %.4f\n", cache.sampleNoise());
    EXPECT_NEAR(cache.sampleNoise(), 0.2, 0.075 * 0.2);
}

TEST(CacheRefinement, SplitsAreConformingAndRespectTheMinimumSize) {
    CacheSettings s = coarse();
    IrradianceCache cache(bench(), s);
    const double border = borderLength(viewOf(cache));
    for (int round = 0; round < 30; ++round) cache.refine(stepSampler, 2000, 1);
    const IrradianceMeshCopy m = viewOf(cache);
    // The border is the objects' outlines: refinement adds none (relative
    // 1e-12: sums of the same lengths split in halves, in another order).
    EXPECT_NEAR(border, borderLength(m), 1e-12 * border);
    // No edge below half the minimum: only edges longer than the minimum are
    // chosen, and bisection halves an edge at most once per choice (longer
    // neighbours split first are longer still).
    const double minLen = s.minEdgeFraction * bench().bounds.diagonal();
    for (const glm::uvec3& t : m.triangles)
        for (int k = 0; k < 3; ++k)
            ASSERT_GE(glm::length(m.positions[t[k]] - m.positions[t[(k + 1) % 3]]), 0.5 * minLen * (1 - 1e-9));
}

TEST(CacheRefinement, TheVertexBudgetHolds) {
    CacheSettings s = coarse();
    IrradianceCache probe(bench(), s);
    s.maxVertices = probe.totalVertices() + 300;
    IrradianceCache cache(bench(), s);
    for (int round = 0; round < 20; ++round) cache.refine(stepSampler, 2000, 1);
    // An action is taken only while 2 more vertices fit; a longest-edge
    // chain can add a few more (at most its length, 48).
    EXPECT_LE(cache.totalVertices(), s.maxVertices + 48);
    EXPECT_GT(cache.totalVertices(), s.maxVertices - 48);
}

TEST(CacheRefinement, PenumbraVerticesAreResampledUntilQuiet) {
    // This sampler's noise (1.4% standard deviation, below) is what the
    // cache must assume of one sample until it has two.
    CacheSettings s = coarse();
    s.singleSampleNoise = 0.014;
    IrradianceCache cache(bench(), s);
    for (int round = 0; round < 40; ++round) cache.refine(noisyStepSampler, 4000, 3);
    const IrradianceMeshCopy m = viewOf(cache);
    size_t resampled = 0, partial = 0;
    for (size_t v = 0; v < m.positions.size(); ++v) {
        const VertexSample s = step(0, m.positions[v], m.normals[v], 0);
        if (!s.partial) {
            // Outside the penumbra one sample is trusted.
            EXPECT_EQ(1u, m.samples[v]) << "vertex " << v;
            continue;
        }
        ++partial;
        resampled += m.samples[v] > 1;
    }
    ASSERT_GT(partial, 50u);
    // ±2.5% uniform noise is 1.4% standard deviation; the tolerance (0.5%)
    // needs several samples wherever the level is above the dark floor.
    EXPECT_GT(double(resampled) / double(partial), 0.5);
}

TEST(CacheFile, ALoadedCacheRefinesExactlyLikeOneNeverSaved) {
    const std::string path = tempPath("resume.mlc");
    IrradianceCache straight(bench(), coarse());
    for (int round = 0; round < 8; ++round) straight.refine(noisyStepSampler, 300, 5);

    {
        IrradianceCache first(bench(), coarse());
        for (int round = 0; round < 4; ++round) first.refine(noisyStepSampler, 300, 5);
        first.save(path);
    }
    IrradianceCache resumed(bench(), coarse());
    resumed.load(path);
    for (int round = 0; round < 4; ++round) resumed.refine(noisyStepSampler, 300, 5);
    EXPECT_EQ(straight.rounds(), resumed.rounds());
    EXPECT_EQ(straight.totalSamples(), resumed.totalSamples());
    expectSameView(viewOf(straight), viewOf(resumed));
    std::filesystem::remove(path);
}

TEST(CacheFile, ALoadedCacheSamplesEveryVertexWhereTheSavedOneDid) {
    // Where a vertex is sampled (IrradianceCache::position) comes from the
    // scene and the layout, not from the file: a loaded cache must keep
    // them, or its next samples land elsewhere than the saved cache's did.
    // The Cornell box's walls meet, so the vertices of their edges lie in
    // the plane of the wall beside them and are sampled inside their own
    // faces (EdgeOnSurfaces); with CacheLayout::insetBorders, as the bounce
    // meshes are laid, every border vertex is. Equal bit for bit.
    const std::string path = tempPath("where.mlc");
    const Scene scene = makeCornellBox();
    for (const bool insetEveryBorder : {false, true}) {
        CacheLayout layout;
        layout.insetBorders = insetEveryBorder;
        IrradianceCache saved(scene, coarse(), layout);
        saved.save(path);
        IrradianceCache loaded(scene, coarse(), layout);
        loaded.load(path);
        ASSERT_EQ(saved.meshCount(), loaded.meshCount());
        size_t moved = 0;
        for (size_t l = 0; l < saved.meshCount(); ++l) {
            const IrradianceMeshCopy vertices = saved.copyMesh(l);
            ASSERT_EQ(saved.vertexCount(l), loaded.vertexCount(l));
            for (size_t v = 0; v < saved.vertexCount(l); ++v) {
                ASSERT_EQ(saved.position(l, v), loaded.position(l, v)) << "mesh " << l << ", vertex " << v;
                moved += saved.position(l, v) != vertices.positions[v];
            }
        }
        EXPECT_GT(moved, 8u) << (insetEveryBorder ? "every border inset" : "edge-on borders inset");
    }
    std::filesystem::remove(path);
}

TEST(EdgeOnSurfaces, OneIndexPerSceneWhileAnyHolderLives) {
    // The direct meshes' cache and each bounce's ask for the index of the
    // same scene: they share one (a million-triangle scene's holds about
    // 130 MB). Another fingerprint is another scene, with an index of its own.
    const Scene scene = makeCornellBox();
    const std::shared_ptr<const EdgeOnSurfaces> a = EdgeOnSurfaces::forScene(scene, 17);
    const std::shared_ptr<const EdgeOnSurfaces> b = EdgeOnSurfaces::forScene(scene, 17);
    const std::shared_ptr<const EdgeOnSurfaces> other = EdgeOnSurfaces::forScene(scene, 18);
    EXPECT_EQ(a.get(), b.get());
    EXPECT_NE(a.get(), other.get());
    // The Cornell box's back wall meets its floor along z = 559.2: the
    // floor's plane passes through a point of that edge, not the wall's own.
    EXPECT_TRUE(a->through(Vec3(300.0, 0.0, 559.2), Vec3(0.0, 0.0, -1.0)));
    EXPECT_FALSE(a->through(Vec3(300.0, 200.0, 559.2), Vec3(0.0, 0.0, -1.0)));
}

TEST(CacheFile, BadFilesAreRefusedAndLeaveTheCacheAsItWas) {
    const std::string path = tempPath("good.mlc");
    IrradianceCache saved(bench(), coarse());
    for (int round = 0; round < 3; ++round) saved.refine(stepSampler, 300, 1);
    saved.save(path);
    std::string bytes;
    {
        std::ifstream in(path, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    auto writeBad = [&](const std::string& name, const std::string& content) {
        const std::string p = tempPath(name);
        std::ofstream(p, std::ios::binary) << content;
        return p;
    };
    std::string flipped = bytes;
    flipped[bytes.size() / 2] ^= 0x20;
    std::string badMagic = bytes;
    badMagic[0] = 'X';
    const std::vector<std::pair<std::string, std::string>> cases = {
        {writeBad("truncated.mlc", bytes.substr(0, bytes.size() - 9)), "truncated"},
        {writeBad("half.mlc", bytes.substr(0, bytes.size() / 2)), "truncated"},
        {writeBad("flipped.mlc", flipped), "corrupt"},
        {writeBad("magic.mlc", badMagic), "not a Meshlight cache"},
        {writeBad("empty.mlc", ""), "not a Meshlight cache"},
        {writeBad("trailing.mlc", bytes + "x"), "trailing"},
        {tempPath("missing.mlc"), "cannot open"},
    };
    IrradianceCache target(bench(), coarse());
    target.refine(stepSampler, 100, 1);
    const IrradianceMeshCopy before = viewOf(target);
    for (const auto& [file, why] : cases) {
        try {
            target.load(file);
            ADD_FAILURE() << file << " was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
        }
        expectSameView(before, viewOf(target));
        std::filesystem::remove(file);
    }
    // Another scene, other settings.
    Scene other = makeBenchScene(2);
    IrradianceCache otherScene(other, coarse());
    EXPECT_THROW(
        try { otherScene.load(path); } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("another scene"), std::string::npos) << e.what();
            throw;
        },
        InputError);
    CacheSettings finer = coarse();
    finer.splitTolerance = 0.02;
    IrradianceCache otherSettings(bench(), finer);
    EXPECT_THROW(otherSettings.load(path), InputError);
    std::filesystem::remove(path);
}

TEST(CacheWorker, ReadersSeeWholeSnapshotsInOrderWhileRefinementRuns) {
    IrradianceCache cache(bench(), coarse());
    WorkerSettings ws;
    ws.publishSeconds = 0;  // publish after every round: as many swaps as possible
    ws.roundBudget = 64;
    // Deterministic and checkable: every vertex's value is a function of
    // its position, so a torn snapshot (positions of one version, values of
    // another) shows as a mismatch.
    CacheWorker worker(cache, test::functionSamplers(step), ws);
    CacheWorker::Reader reader = worker.reader();
    worker.start();
    uint64_t last = 0, seen = 0;
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(1500);
    while (std::chrono::steady_clock::now() < until) {
        const CacheSnapshot* s = reader.acquire();
        if (!s) continue;
        ASSERT_GE(s->version, last);
        if (s->version == last) continue;
        last = s->version;
        ++seen;
        ASSERT_EQ(1u, s->direct.size());
        const IrradianceMeshCopy& m = s->direct[0];
        ASSERT_EQ(m.positions.size(), s->vertices);
        for (const glm::uvec3& t : m.triangles) ASSERT_LT(std::max({t.x, t.y, t.z}), m.positions.size());
        for (size_t v = 0; v < m.positions.size(); ++v)
            if (m.samples[v]) {
                ASSERT_EQ(step(0, m.positions[v], m.normals[v], 0).irradiance, m.irradiance[v]);
            }
    }
    worker.stop();
    worker.rethrowIfFailed();
    EXPECT_GT(seen, 5u);
}

TEST(CacheWorker, PausesResumesAndStops) {
    IrradianceCache cache(bench(), coarse());
    WorkerSettings ws;
    ws.publishSeconds = 0;
    ws.roundBudget = 32;
    CacheWorker worker(cache, test::functionSamplers(noisyStep), ws);
    CacheWorker::Reader reader = worker.reader();
    worker.start();
    ASSERT_TRUE(worker.waitForVersion(3, 10));
    worker.pause();
    // A round in flight may still publish once.
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const uint64_t paused = reader.acquire()->version;
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    EXPECT_EQ(paused, reader.acquire()->version);
    worker.resume();
    EXPECT_TRUE(worker.waitForVersion(paused + 2, 10));
    worker.stop();
    // Stopped means no round runs any more: nothing is published after it.
    const uint64_t last = reader.acquire()->version;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    EXPECT_EQ(last, reader.acquire()->version) << "a stopped worker published again";
    worker.rethrowIfFailed();
}

TEST(CacheWorker, AFailureReachesTheMainThreadWithWhereItHappened) {
    IrradianceCache cache(bench(), coarse());
    const auto failing = [](size_t l, const Vec3& x, const Vec3& n, uint32_t s) {
        if (x.x > 1.0) throw std::runtime_error("sampler broke");
        return step(l, x, n, s);
    };
    CacheWorker worker(cache, test::functionSamplers(failing), WorkerSettings{});
    worker.start();
    worker.waitForVersion(1u << 30, 20);  // returns when the worker ends
    ASSERT_TRUE(worker.finished());
    try {
        worker.rethrowIfFailed();
        FAIL() << "no failure reported";
    } catch (const std::runtime_error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("sampler broke"), std::string::npos) << what;
        EXPECT_NE(what.find("vertex"), std::string::npos) << what;
        EXPECT_NE(what.find("light 0"), std::string::npos) << what;
        EXPECT_NE(what.find("point"), std::string::npos) << what;
    }
}

TEST(CacheRefinement, AnInterruptEndsARoundBetweenBatchesAndKeepsWhatItTook) {
    IrradianceCache cache(bench(), coarse());
    size_t taken = 0;
    auto sampler = samplerOf([&](size_t l, const Vec3& x, const Vec3& n, uint32_t seed) {
        ++taken;
        return step(l, x, n, seed);
    });
    const size_t all = cache.unsampledCount();
    ASSERT_GT(all, 300u);
    // The first pass, asked to stop once anything is taken: it ends after
    // the batch under way (the first, a few dozen), keeping those samples
    // and counting them.
    cache.setInterrupt([&] { return taken > 0; });
    RefineReport r = cache.refine(sampler, all, 1);
    EXPECT_GT(taken, 0u);
    EXPECT_LT(taken, all / 4);
    EXPECT_EQ(r.estimates, taken);
    EXPECT_EQ(cache.unsampledCount(), all - taken);
    EXPECT_EQ(cache.totalSamples(), taken);
    // Asked to stop before anything: nothing taken.
    cache.setInterrupt([] { return true; });
    r = cache.refine(sampler, all, 1);
    EXPECT_EQ(r.estimates, 0u);
    EXPECT_EQ(cache.unsampledCount(), all - taken);
    // No interrupt: the round whole.
    cache.setInterrupt({});
    cache.refine(sampler, all, 1);
    ASSERT_EQ(cache.unsampledCount(), 0u);
    // A refinement round interrupted at once still samples the vertices its
    // splits made (the cache keeps an estimate of its error), and takes
    // none of its resamples.
    cache.setInterrupt([] { return true; });
    const size_t before = taken;
    r = cache.refine(sampler, 4096, 1);
    EXPECT_GT(r.splits, 0u);
    EXPECT_EQ(r.resamples, 0u);
    EXPECT_EQ(cache.unsampledCount(), 0u);
    EXPECT_EQ(r.estimates, taken - before);
    EXPECT_LT(cache.estimatedError(), 1.0);
}

TEST(CacheWorker, AStopEndsTheRoundUnderWayUnlessASampleBudgetRules) {
    // One round of every base vertex, each sample a millisecond. Stopped
    // once 10 are taken: without a sample budget the round ends
    // there (its other vertices unsampled); with one, the stop waits for the
    // round, whose extent no clock may decide.
    for (const bool budget : {false, true}) {
        SCOPED_TRACE(budget ? "a sample budget" : "no budget");
        IrradianceCache cache(bench(), coarse());
        const size_t all = cache.unsampledCount();
        std::atomic<size_t> taken{0};
        const auto slow = [&taken](size_t l, const Vec3& x, const Vec3& n, uint32_t seed) {
            ++taken;
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
            return step(l, x, n, seed);
        };
        WorkerSettings ws;
        ws.roundBudget = all;
        ws.threads = 1;
        if (budget) ws.maxSamples = 10 * all;
        CacheWorker worker(cache, test::functionSamplers(slow), ws);
        worker.start();
        while (taken < 10 && !worker.finished()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        worker.stop();
        worker.rethrowIfFailed();
        if (budget) {
            EXPECT_EQ(cache.unsampledCount(), 0u);
        } else {
            EXPECT_GT(cache.unsampledCount(), all / 2);
            EXPECT_EQ(cache.totalSamples(), taken.load());
        }
    }
}

TEST(CacheWorker, ASampleBudgetEndsTheWorkerAndRepeatsExactly) {
    auto run = [] {
        auto cache = std::make_unique<IrradianceCache>(bench(), coarse());
        WorkerSettings ws;
        ws.maxSamples = 3000;
        ws.seed = 9;
        CacheWorker worker(*cache, test::functionSamplers(noisyStep), ws);
        worker.start();
        worker.waitForVersion(1u << 30, 60);
        EXPECT_TRUE(worker.finished());
        worker.stop();
        worker.rethrowIfFailed();
        return cache;
    };
    const auto a = run(), b = run();
    EXPECT_GE(a->totalSamples(), 3000u);
    expectSameView(viewOf(*a), viewOf(*b));
}

namespace {

// The bench scene plus a finely tessellated UV sphere (rings × segments × 2
// triangles), far more vertices than its irradiance needs.
Scene benchWithDenseSphere(int rings, int segments) {
    Scene scene = makeBenchScene();
    Mesh sphere;
    sphere.name = "dense sphere";
    const Vec3 centre(-1.0, 0.3, -1.0);
    const double r = 0.25;
    for (int i = 0; i <= rings; ++i)
        for (int j = 0; j <= segments; ++j) {
            const double th = kPi * i / rings, ph = 2 * kPi * j / segments;
            const Vec3 n(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
            sphere.positions.push_back(centre + r * n);
            sphere.normals.push_back(n);
        }
    auto at = [&](int i, int j) { return uint32_t(i * (segments + 1) + j); };
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            // Outward-facing (counter-clockwise seen from outside); the
            // poles' zero-area triangles are left out.
            if (i > 0) sphere.triangles.push_back({at(i, j), at(i, j + 1), at(i + 1, j)});
            if (i + 1 < rings) sphere.triangles.push_back({at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)});
        }
    sphere.materials.assign(sphere.triangles.size(), scene.meshes.back().materials.front());
    sphere.sourceLines.assign(sphere.triangles.size(), 0);
    scene.meshes.push_back(sphere);
    scene.finalize();
    return scene;
}

}  // namespace

TEST(CacheGrid, ADenseObjectIsSampledOnAGridAndInterpolatedToItsVertices) {
    const Scene scene = benchWithDenseSphere(150, 240);  // 72k triangles
    const size_t sphereVertices = scene.meshes.back().positions.size();
    IrradianceCache cache(scene, coarse());
    IrradianceCache plainBench(bench(), coarse());
    EXPECT_EQ(plainBench.totalVertices(), cache.totalVertices()) << "the sphere must not be in the cache mesh";
    // A linear field: the grid reproduces it within 1.5 cells × |∇f|₁ (see
    // GridCache), cells being the base edge length here.
    const Vec3 gradient(0.3, 0.1, 0.2);
    auto linear = samplerOf([&](size_t, const Vec3& x, const Vec3&, uint32_t) {
        return VertexSample{Rgb(2 + glm::dot(gradient, x)), 1.0, false};
    });
    cache.refine(linear, 1 << 22, 1);
    const uint64_t samples = cache.totalSamples();
    // Far fewer samples than the sphere alone has vertices.
    EXPECT_LT(samples - plainBench.totalVertices(), sphereVertices / 4);
    const IrradianceMeshCopy m = cache.copyMesh(0);
    ASSERT_EQ(cache.totalVertices() + sphereVertices, m.positions.size());
    const double cell = coarse().maxEdgeFraction * scene.bounds.diagonal();
    const double bound = 1.5 * cell * (gradient.x + gradient.y + gradient.z);
    for (size_t v = cache.totalVertices(); v < m.positions.size(); ++v) {
        ASSERT_NEAR(2 + glm::dot(gradient, m.positions[v]), m.irradiance[v].r, bound) << "vertex " << v;
        ASSERT_GE(m.samples[v], 1u);
    }
    // Saved and loaded, grid samples included.
    const std::string path = tempPath("grid.mlc");
    cache.save(path);
    IrradianceCache loaded(scene, coarse());
    loaded.load(path);
    expectSameView(m, loaded.copyMesh(0));
    std::filesystem::remove(path);
}

// A panel hung 2 cm under a ceiling and an open box (no bottom) standing on
// the floor: indirect light reaches the panel's back (the ceiling above it
// reflects light that came in from the room), never the box's inside.
Scene panelAndOpenBox(bool withPanel) {
    using namespace test;
    Material grey;
    grey.name = "grey";
    grey.kd = Rgb(0.6);
    Material panel = grey;
    panel.name = "panel";
    panel.ke = Rgb(5.0);
    std::vector<Mesh> meshes = {quadMesh("floor", 0, Vec3(-2, 0, -2), 4.0 * kZ, 4.0 * kX),
                                quadMesh("ceiling", 0, Vec3(-2, 2.5, -2), 4.0 * kX, 4.0 * kZ)};
    Mesh box;
    box.name = "box";
    const Vec3 lo(0.5, 0, 0.5);
    const double a = 0.5;
    addQuad(box, 0, lo + a * kY, a * kZ, a * kX);  // top, facing +y
    addQuad(box, 0, lo, a * kY, a * kX);           // z = 0.5, facing −z
    addQuad(box, 0, lo + a * kZ, a * kX, a * kY);  // z = 1, facing +z
    addQuad(box, 0, lo, a * kZ, a * kY);           // x = 0.5, facing −x
    addQuad(box, 0, lo + a * kX, a * kY, a * kZ);  // x = 1, facing +x
    meshes.push_back(box);
    if (withPanel) meshes.push_back(quadMesh("panel", 1, Vec3(-0.3, 2.48, -0.3), 0.6 * kX, 0.6 * kZ));  // facing down
    return sceneOf("panel and open box", {grey, panel}, meshes);
}

TEST(CacheLayout, BounceMeshesCopyTheBacksLightReachesButNotAnOpenBoxsInside) {
    // Direct light: no light is behind any face, so no copy at all.
    const Scene scene = panelAndOpenBox(true);
    EXPECT_EQ(IrradianceCache(scene, CacheSettings{}).backFaceCount(), 0u);
    // Indirect light: the panel's two triangles get a reversed copy (the
    // ceiling 2 cm behind them reflects light into the gap), the box's
    // faces none: their backs see only the box and the floor that closes
    // it. (Wound inwards, its sides would get copies: their backs would
    // face the room.)
    CacheLayout layout = bounceCacheLayout();
    EXPECT_EQ(IrradianceCache(scene, CacheSettings{}, layout).backFaceCount(), 0u);  // as for direct light
    layout.backFaces = CacheLayout::BackFaces::ReachedByScene;  // the ray gather's
    EXPECT_EQ(IrradianceCache(scene, CacheSettings{}, layout).backFaceCount(), 2u);
    EXPECT_EQ(IrradianceCache(panelAndOpenBox(false), CacheSettings{}, layout).backFaceCount(), 0u);
    // The Cornell box's blocks are open boxes too: its bounces copy nothing.
    EXPECT_EQ(IrradianceCache(makeCornellBox(), CacheSettings{}, layout).backFaceCount(), 0u);
}
