// Textured emitters (issue 13): a light whose radiance varies over it is
// sampled by its texture (EmitterTexture.h), not at its mean. The light: a
// 1 × 1 quad 1 above a floor, its texture two texels magnified to the
// nearest, bright on the x < 0 half, dark on the other. Its exact
// irradiance is that of two uniform half-quads, each at its texel's
// radiance: Lambert's closed form, or with an occluder ExactDirect on the
// scene with the light cut in two. The raster and ray-traced samplers, the
// shared-mesh estimator and the path tracer must all agree with it; a
// uniform texture must give what no texture gives.
#include "TestSamplers.h"
#include "cache/LightCoverage.h"
#include "cache/SharedLightSampler.h"
#include "core/EmitterTexture.h"
#include "core/Random.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "core/reference/ExactIrradiance.h"
#include "core/reference/Lambert.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/direct/RayTracedLightSampler.h"

#include "GlTestContext.h"
#include "MeanAndError.h"

#include <gtest/gtest.h>

#include <functional>
#include <memory>

using namespace ml;

namespace {

const Vec3 kUp(0, 1, 0);
const Rgb kFactor(3.0, 2.5, 2.0);

// `width` × 1 texels (sRGB, nearest, clamped), left to right.
std::shared_ptr<Texture> texels(const std::vector<std::array<unsigned char, 3>>& rgb) {
    auto t = std::make_shared<Texture>();
    t->name = "test emission";
    t->width = int(rgb.size());
    t->height = 1;
    for (const auto& c : rgb) t->rgba.insert(t->rgba.end(), {c[0], c[1], c[2], 255});
    t->nearest = true;
    t->wrapS = t->wrapT = TextureWrap::ClampToEdge;
    return t;
}

std::shared_ptr<Texture> halves() { return texels({{255, 230, 180}, {40, 70, 110}}); }

Mesh quad(const std::string& name, const std::array<Vec3, 4>& p, const Vec3& normal, uint32_t material) {
    Mesh m;
    m.name = name;
    m.positions.assign(p.begin(), p.end());
    m.normals.assign(4, normal);
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    m.materials = {material, material};
    m.sourceLines = {0, 0};
    return m;
}

// The floor's top face (y = 0, 8 × 8) and the light facing down at y = 1,
// x and z in [x0, x1] × [−0.5, 0.5].
Mesh floorMesh() { return quad("floor", {{{-4, 0, -4}, {-4, 0, 4}, {4, 0, 4}, {4, 0, -4}}}, kUp, 0); }
Mesh lightMesh(const std::string& name, double x0, double x1, uint32_t material) {
    return quad(name, {{{x0, 1, -0.5}, {x1, 1, -0.5}, {x1, 1, 0.5}, {x0, 1, 0.5}}}, -kUp, material);
}
// A 0.4 × 0.6 blocker at y = 0.5 under the bright half (both sides occlude).
Mesh blocker() { return quad("blocker", {{{-0.45, 0.5, -0.3}, {-0.45, 0.5, 0.3}, {-0.05, 0.5, 0.3}, {-0.05, 0.5, -0.3}}}, kUp, 0); }

struct Options {
    std::shared_ptr<Texture> texture;  // null: untextured at Ke = kFactor × `mean`
    Rgb mean{1.0};
    bool blocked = false;
    bool secondLight = false;  // an untextured light 20× brighter at x = −3 (the shared-mesh test)
};

// Light 0 is the quad, uv = (x + 0.5, z + 0.5).
Scene litFloor(const Options& o) {
    Scene s;
    s.name = "textured emitter";
    Material light = Material::diffuse("panel", Rgb(0.0), kFactor * (o.texture ? o.texture->imageMean() : o.mean));
    if (o.texture) {
        light.keMap.image = o.texture;
        light.keMap.factor = kFactor;
    }
    s.materials = {Material::diffuse("grey", Rgb(0.5)), light, Material::diffuse("lamp", Rgb(0.0), Rgb(40.0))};
    Mesh l = lightMesh("panel", -0.5, 0.5, 1);
    if (o.texture)
        for (const Vec3& p : l.positions) l.texcoords.push_back(Vec2(p.x + 0.5, p.z + 0.5));
    s.meshes = {floorMesh(), l};
    if (o.blocked) s.meshes.push_back(blocker());
    if (o.secondLight) s.meshes.push_back(lightMesh("lamp", -3.5, -2.5, 2));
    s.finalize();
    return s;
}

// The radiance of each half of the light: the factor × its texel, decoded
// by the same Texture::sample the renderer uses.
Rgb halfRadiance(const Texture& t, double u) { return kFactor * t.sample(Vec2(u, 0.5)); }

// The textured light's exact irradiance at x (normal up), from the scene
// with the light cut into two uniform halves (ExactDirect: exact with the
// blocker too).
class Exact {
public:
    Exact(const Texture& t, bool blocked) {
        split_.name = "halves";
        split_.materials = {Material::diffuse("grey", Rgb(0.5)), Material::diffuse("left", Rgb(0.0), halfRadiance(t, 0.25)),
                            Material::diffuse("right", Rgb(0.0), halfRadiance(t, 0.75))};
        split_.meshes = {floorMesh(), lightMesh("left", -0.5, 0.0, 1), lightMesh("right", 0.0, 0.5, 2)};
        if (blocked) split_.meshes.push_back(blocker());
        split_.finalize();
        exact_ = std::make_unique<ExactDirect>(split_);
    }
    Rgb at(const Vec3& x) const { return exact_->irradiance(0, x, kUp) + exact_->irradiance(1, x, kUp); }

private:
    Scene split_;
    std::unique_ptr<ExactDirect> exact_;
};

const std::vector<Vec3> kPoints = {{-0.9, 0, 0.2}, {-0.3, 0, 0.0}, {0.05, 0, 0.1}, {0.4, 0, -0.3}, {1.5, 0, 0.5}};

DirectSamplerSettings jittered(DirectEstimator e) {
    DirectSamplerSettings s;
    s.estimator = e;
    s.imageSize = 32;
    s.bits = 8;
    return s;
}

using SampleFn = std::function<DirectSample(const Vec3& x, uint32_t seed)>;

// Over 48 seeds, the mean of each channel within 4 standard errors of the
// exact value (MeanAndError.h: ~1e-4 chance each for an unbiased sampler),
// plus 2e-4 of it for the eye's lift (samplingEyeLift: at most ~1e-4).
void expectExact(const SampleFn& sample, const Exact& exact, const std::string& what) {
    for (size_t i = 0; i < kPoints.size(); ++i) {
        const Rgb truth = exact.at(kPoints[i]);
        std::vector<double> channels[3];
        for (uint32_t seed = 0; seed < 48; ++seed) {
            const Rgb e = sample(kPoints[i], seedFor(11, uint32_t(i), seed)).irradiance;
            for (int c = 0; c < 3; ++c) channels[c].push_back(e[c]);
        }
        for (int c = 0; c < 3; ++c)
            test::expectUnbiased(channels[c], truth[c], 2e-4 * truth[c],
                                 concat(what, ", point ", i, ", channel ", c));
    }
}

}  // namespace

TEST(TexturedEmitter, TheMeanRadianceIsWrongHere) {
    // What the test below guards against: Lambert's form at the light's mean
    // radiance is 10-40% off the exact value at these points (so a sampler
    // that ignored the texture would fail by far more than its noise).
    const auto t = halves();
    const Scene scene = litFloor({t});
    const Exact exact(*t, false);
    for (const Vec3& x : {kPoints[0], kPoints[3], kPoints[4]}) {
        const Rgb mean = scene.lights[0].radiance * unoccludedCosineSolidAngle(scene.lights[0], x, kUp);
        EXPECT_GT(std::abs(mean.r / exact.at(x).r - 1), 0.1) << x.x;
    }
}

TEST(TexturedEmitter, RasterSamplerWeighsTheTexture) {
    // Without the blocker every pair is answered on the CPU (Lambert's form
    // corrected by the samples); with it, the pairs near it are rasterised.
    const auto t = halves();
    for (bool blocked : {false, true}) {
        const Scene scene = litFloor({t, Rgb(1.0), blocked});
        const Exact exact(*t, blocked);
        for (DirectEstimator e : {DirectEstimator::ControlVariate, DirectEstimator::Plain}) {
            DirectLightSampler sampler(test::glContext(), scene, jittered(e));
            expectExact([&](const Vec3& x, uint32_t seed) { return sampler.sample(0, x, kUp, seed); }, exact,
                        concat("raster ", directEstimatorName(e), blocked ? " blocked" : " open"));
        }
    }
}

TEST(TexturedEmitter, RayTracedSamplerWeighsTheTexture) {
    const auto t = halves();
    for (bool blocked : {false, true}) {
        const Scene scene = litFloor({t, Rgb(1.0), blocked});
        const EmbreeScene rays(scene);
        const Exact exact(*t, blocked);
        for (DirectEstimator e : {DirectEstimator::ControlVariate, DirectEstimator::Plain}) {
            const RayTracedLightSampler sampler(rays, jittered(e));
            expectExact([&](const Vec3& x, uint32_t seed) { return sampler.sample(0, x, kUp, seed); }, exact,
                        concat("ray-traced ", directEstimatorName(e), blocked ? " blocked" : " open"));
        }
    }
}

TEST(TexturedEmitter, PathTracerAgrees) {
    // Direct light alone (depth 1), 40000 samples a point: the estimate's
    // own standard error is about 0.3% of it; within 4 of them.
    const auto t = halves();
    for (bool blocked : {false, true}) {
        const Scene scene = litFloor({t, Rgb(1.0), blocked});
        const EmbreeScene rays(scene);
        PathTracerSettings ps;
        ps.maxDepth = 1;
        const PathTracer tracer(rays, ps);
        const Exact exact(*t, blocked);
        for (size_t i = 0; i < kPoints.size(); ++i) {
            const IrradianceEstimate e = tracer.irradiance(kPoints[i], kUp, 40000, uint32_t(i));
            const Rgb truth = exact.at(kPoints[i]);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(e.direct[c], truth[c], 4 * e.directError[c] + 1e-12)
                    << (blocked ? "blocked" : "open") << ", point " << i << ", channel " << c;
        }
    }
}

TEST(TexturedEmitter, SharedMeshKeepsABrighterThanMeanLight) {
    // Near the bright lamp at x = −3 the panel's share is small, so the
    // shared mesh carries it, there seeing its bright half nearer: E > U,
    // the Lambert form at its mean. Each light's sample here is exact (a
    // closed form), and the panel is the only light shared there, drawn
    // with probability 1: own + shared must equal Σ E exactly. Clamping
    // O = U − E at 0, right for uniform lights, would give U instead.
    const auto t = halves();
    const Scene scene = litFloor({t, Rgb(1.0), false, true});
    ASSERT_EQ(scene.lights.size(), 2u);
    const Exact exact(*t, false);
    auto coverage = std::make_shared<const LightCoverage>(scene, 0.2);
    auto closedForm = [&](size_t l, const Vec3& x, const Vec3& n, uint32_t) {
        VertexSample s;
        s.irradiance = l == 0 ? exact.at(x) : unoccludedIrradiance(scene.lights[1], x, n);
        s.visibility = 1;
        return s;
    };
    SharedLightSampler sampler(scene, coverage,
                               std::make_unique<test::FunctionDirectSampler<decltype(closedForm)>>(closedForm));
    int brighter = 0;
    for (const Vec3& x : {Vec3(-3.0, 0, 0.0), Vec3(-2.6, 0, 0.4), Vec3(-3.4, 0, -0.3)}) {
        const double w = coverage->weight(0, x);
        const Rgb e = exact.at(x), u = unoccludedIrradiance(scene.lights[0], x, kUp);
        if (w < 1 && e.r > 1.01 * u.r) ++brighter;
        const Rgb truth = e + unoccludedIrradiance(scene.lights[1], x, kUp);
        const Rgb sum = sampler.sample(0, x, kUp, 1).irradiance + sampler.sample(1, x, kUp, 1).irradiance +
                        sampler.sample(2, x, kUp, 1).irradiance;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c] / truth[c], 1.0, 1e-12) << x.x << ", channel " << c;
    }
    EXPECT_GT(brighter, 0) << "no point where the shared mesh carries the panel's brighter-than-mean light";
}

TEST(TexturedEmitter, SharedRaysWeighTheTexture) {
    // A row of 30 textured panels (0.4 × 1, bright left half, dark right
    // half) 1 above the floor, the blocker under one of them: at floor
    // points more lights share a mesh than its pairs would take, so the
    // shared estimate shoots rays, each weighing U_l − E_l at its point by
    // the texture, L̄ g − L(y) g V. Against the exact shared light (the
    // scene with every panel cut into its two uniform halves, ExactDirect),
    // over 2048 seeds as a first pass and as later samples: the mean within
    // 4 of its standard errors (measured from the same estimates, 0.14% of
    // the light), that error under 1% of the light, and the exact light of
    // the panels at their mean radiance (ExactDirect on the scene itself)
    // over 8 of them away, so that ignoring the texture would fail.
    const auto t = halves();
    constexpr int kPanels = 30;
    const auto panelX = [](int i) { return -7.5 + 0.5 * i; };
    Scene scene, split;
    scene.name = "textured panels";
    split.name = "halved panels";
    Material panel = Material::diffuse("panel", Rgb(0.0), kFactor * t->imageMean());
    panel.keMap.image = t;
    panel.keMap.factor = kFactor;
    scene.materials = {Material::diffuse("grey", Rgb(0.5)), panel};
    split.materials = {Material::diffuse("grey", Rgb(0.5)), Material::diffuse("left", Rgb(0.0), halfRadiance(*t, 0.25)),
                       Material::diffuse("right", Rgb(0.0), halfRadiance(*t, 0.75))};
    scene.meshes = {floorMesh(), blocker()};
    split.meshes = {floorMesh(), blocker()};
    for (int i = 0; i < kPanels; ++i) {
        const double x0 = panelX(i), x1 = x0 + 0.4;
        Mesh l = lightMesh(concat("panel", i), x0, x1, 1);
        for (const Vec3& p : l.positions) l.texcoords.push_back(Vec2((p.x - x0) / 0.4, p.z + 0.5));
        scene.meshes.push_back(l);
        split.meshes.push_back(lightMesh(concat("left", i), x0, x0 + 0.2, 1));
        split.meshes.push_back(lightMesh(concat("right", i), x0 + 0.2, x1, 2));
    }
    scene.finalize();
    split.finalize();
    ASSERT_EQ(scene.lights.size(), size_t(kPanels));
    ASSERT_EQ(split.lights.size(), size_t(2 * kPanels));
    const ExactDirect exact(split);
    // Light l of the scene is the panel at x0 = scene.lights[l]'s; its halves
    // are the split scene's lights whose centroids lie within it.
    const auto exactOf = [&](size_t l, const Vec3& x) {
        Rgb e(0.0);
        for (size_t k = 0; k < split.lights.size(); ++k)
            if (std::abs(split.lights[k].centroid.x - scene.lights[l].centroid.x) < 0.2)
                e += exact.irradiance(k, x, kUp);
        return e;
    };
    const ExactDirect uniform(scene);  // each panel at its mean radiance
    auto coverage = std::make_shared<const LightCoverage>(scene, 0.1);
    const auto pairs = [&](size_t l, const Vec3& x, const Vec3&, uint32_t) {
        VertexSample s;
        s.irradiance = exactOf(l, x);
        return s;
    };
    SharedLightSampler sampler(scene, coverage, std::make_unique<test::FunctionDirectSampler<decltype(pairs)>>(pairs));
    const size_t lights = scene.lights.size();
    for (const Vec3& x : {Vec3(-0.3, 0, 0.1), Vec3(-0.1, 0, -0.2), Vec3(0.6, 0, 0.3)}) {
        Rgb truth(0.0), atMean(0.0);
        size_t shared = 0;
        for (size_t l = 0; l < lights; ++l) {
            const double w = coverage->weight(l, x);
            truth += (1 - w) * exactOf(l, x);
            atMean += (1 - w) * uniform.irradiance(l, x, kUp);
            shared += w < 1;
        }
        ASSERT_GT(shared, size_t(SharedLightSampler::kDraws)) << "at " << x.x;
        for (bool firstPass : {true, false}) {
            sampler.firstSamples(firstPass);
            constexpr int kSeeds = 2048;
            Rgb sum(0.0), squares(0.0);
            for (int k = 0; k < kSeeds; ++k) {
                const Rgb e = sampler.sample(lights, x, kUp, seedFor(23, uint32_t(k))).irradiance;
                sum += e, squares += e * e;
            }
            for (int c = 0; c < 3; ++c) {
                const double m = sum[c] / kSeeds;
                const double standardError = std::sqrt((squares[c] - sum[c] * m) / (kSeeds - 1) / kSeeds);
                const std::string at = concat("at ", x.x, ", channel ", c, firstPass ? ", first pass" : "");
                EXPECT_NEAR(m, truth[c], 4 * standardError) << at;
                EXPECT_LT(standardError, 0.01 * truth[c]) << at;
                // The texture moves the light by over 8 standard errors
                // (1.5-4.7% here): the panels at their mean would fail.
                EXPECT_GT(std::abs(truth[c] - atMean[c]), 8 * standardError) << at;
            }
        }
        sampler.firstSamples(false);
    }
}

TEST(TexturedEmitter, AUniformTextureIsNoTexture) {
    // Every texel alike: τ = 1 up to rounding, so every sampler gives what
    // the untextured light of the same Ke gives, seed for seed (1e-12: the
    // rounding of L / L̄ and of the sums it enters).
    const auto t = texels({{150, 150, 150}, {150, 150, 150}});
    for (bool blocked : {false, true}) {
        const Scene textured = litFloor({t, Rgb(1.0), blocked});
        const Scene plain = litFloor({nullptr, t->imageMean(), blocked});
        ASSERT_TRUE(EmitterTexture(textured, textured.lights[0]).textured());
        DirectLightSampler rasterT(test::glContext(), textured, jittered(DirectEstimator::ControlVariate));
        DirectLightSampler rasterP(test::glContext(), plain, jittered(DirectEstimator::ControlVariate));
        const EmbreeScene raysT(textured), raysP(plain);
        const RayTracedLightSampler tracedT(raysT, jittered(DirectEstimator::Plain));
        const RayTracedLightSampler tracedP(raysP, jittered(DirectEstimator::Plain));
        PathTracerSettings ps;
        ps.maxDepth = 1;
        const PathTracer pathT(raysT, ps), pathP(raysP, ps);
        for (size_t i = 0; i < kPoints.size(); ++i) {
            const Vec3& x = kPoints[i];
            const Rgb a[3] = {rasterT.sample(0, x, kUp, 5).irradiance, tracedT.sample(0, x, kUp, 5).irradiance,
                              pathT.irradiance(x, kUp, 256, uint32_t(i)).direct};
            const Rgb b[3] = {rasterP.sample(0, x, kUp, 5).irradiance, tracedP.sample(0, x, kUp, 5).irradiance,
                              pathP.irradiance(x, kUp, 256, uint32_t(i)).direct};
            for (int k = 0; k < 3; ++k) {
                ASSERT_GT(b[k].r, 0.0);
                EXPECT_NEAR(a[k].r / b[k].r, 1.0, 1e-12) << "sampler " << k << ", point " << i;
            }
        }
    }
}
