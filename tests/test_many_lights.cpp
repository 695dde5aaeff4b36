// Many lights (the many-lights issue): lights that share a cache mesh where
// they give a small share of the light (LightCoverage, SharedLightSampler)
// add up to what a mesh per light holds; a room of 100 small lights keeps
// their power; sampling spread over threads gives the same cache as one
// thread.
#include "TestSamplers.h"
#include "cache/IrradianceCache.h"
#include "cache/LightCoverage.h"
#include "cache/ProgressiveSession.h"
#include "cache/SharedLightSampler.h"
#include "core/Random.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/reference/ExactIrradiance.h"
#include "core/reference/Lambert.h"
#include "core/scenes/CornellBox.h"
#include "core/scenes/OfficeScene.h"
#include "gpu_sampling/SamplerFactory.h"
#include "gpu_sampling/gl/GlContext.h"
#include "viewer/compositor/Compositor.h"
#include "GlTestContext.h"
#include "SessionRun.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

using namespace ml;

namespace {

// An empty office (no desks, partition or cabinets): nothing occludes, so
// each light's unoccluded closed form is its exact irradiance.
Scene emptyOffice(int nx, int nz, double panelSize) {
    OfficeSettings s;
    s.panelsX = nx;
    s.panelsZ = nz;
    s.panelSize = panelSize;
    s.desks = 0;
    s.partitions = 0;
    s.cabinets = 0;
    return makeOfficeScene(s);
}

// Exact direct light with a made-up occluder: points with x < 0 see half of
// every light. visibility and partial as a sampler would report them.
struct HalfShadowed {
    const Scene* scene;
    VertexSample operator()(size_t light, const Vec3& x, const Vec3& n, uint32_t) const {
        const double v = x.x < 0 ? 0.5 : 1.0;
        return {v * unoccludedIrradiance(scene->lights[light], x, n), v, v < 1};
    }
};


}  // namespace

TEST(LightCoverage, WeightsAreZeroOutsideTheFacesALightKeeps) {
    const Scene scene = emptyOffice(8, 6, 0.4);
    const LightCoverage coverage(scene, 0.05);
    ASSERT_TRUE(coverage.sharing()) << "48 panels: each must give under 5% somewhere";
    // Every point where w_l > 0 lies in a box that covers(l, ...) accepts:
    // tested on a grid of tiny triangles over the room.
    size_t checked = 0, positive = 0;
    for (double x = -3.9; x < 4; x += 0.37)
        for (double z = -2.9; z < 3; z += 0.41)
            for (double y : {0.0, 1.4, 2.78}) {
                const Vec3 p(x, y, z);
                const Triangle3 t{p, p + Vec3(1e-3, 0, 0), p + Vec3(0, 0, 1e-3)};
                for (size_t l = 0; l < scene.lights.size(); ++l) {
                    const double w = coverage.weight(l, p);
                    ASSERT_GE(w, 0.0);
                    ASSERT_LE(w, 1.0);
                    if (w > 0) {
                        ++positive;
                        EXPECT_TRUE(coverage.covers(l, t)) << "light " << l << " at " << p.x << "," << p.y << "," << p.z;
                    }
                    ++checked;
                }
            }
    EXPECT_GT(positive, 0u);
    EXPECT_LT(positive, checked) << "some light must give its light to the shared mesh somewhere";
    // Right under it a light gives well over 5%: its weight is near 1 there
    // (1 at the grid nodes; interpolation may blend in a neighbour node a
    // cell away, on the ramp from 0.8τ to τ: the lowest measured is 0.86).
    for (size_t l = 0; l < scene.lights.size(); ++l)
        EXPECT_GT(coverage.weight(l, Vec3(scene.lights[l].centroid.x, 0.0, scene.lights[l].centroid.z)), 0.8)
            << "light " << l;
}

// The samplers below make their shadows up (none is in the scene's
// geometry), so the shared estimates take the wrapped sampler's pairs, not
// shadow rays (K draws, fewer in a first pass, as by default).
constexpr int kDraws = SharedLightSampler::kDraws, kFirstDraws = SharedLightSampler::kFirstDraws, kPairsOnly = 0;

TEST(SharedLights, OwnAndSharedMeshesAddUpToEveryLightsWholeLight) {
    // At points, the lights' own weighted estimates plus the shared
    // estimate average to Σ_l E_l: exactly where nothing occludes (the
    // control variate leaves no noise there), within the draws' noise in
    // the made-up half shadow (mean of 256 seeds: the occluded half of the
    // drawn lights scaled by 1/p; its standard error is well under 1% of
    // the total for 4 draws a sample, less for the 16 drawn now, and 2% is
    // four standard errors of the former).
    const Scene scene = emptyOffice(8, 6, 0.4);
    auto coverage = std::make_shared<const LightCoverage>(scene, 0.05);
    SharedLightSampler sampler(scene, coverage,
                               std::make_unique<test::FunctionDirectSampler<HalfShadowed>>(HalfShadowed{&scene}), kDraws,
                               kFirstDraws, kPairsOnly);
    const size_t lights = scene.lights.size();
    for (const Vec3& p : {Vec3(2.1, 0.0, 1.3), Vec3(-2.4, 0.0, -0.7), Vec3(3.99, 1.2, 0.4), Vec3(-1.0, 0.75, 2.99)}) {
        const Vec3 n = p.y == 0 ? Vec3(0, 1, 0) : std::abs(p.x) > 3.9 ? Vec3(-1, 0, 0) : Vec3(0, 0, -1);
        const double v = p.x < 0 ? 0.5 : 1.0;
        Rgb truth(0.0), own(0.0);
        for (size_t l = 0; l < lights; ++l) {
            truth += v * unoccludedIrradiance(scene.lights[l], p, n);
            own += sampler.sample(l, p, n, 1).irradiance;
        }
        Rgb shared(0.0);
        constexpr int kSeeds = 256;
        for (int k = 0; k < kSeeds; ++k) shared += sampler.sample(lights, p, n, seedFor(7, uint32_t(k))).irradiance;
        shared /= double(kSeeds);
        ASSERT_GT(truth.r, 0.0);
        if (v == 1)
            EXPECT_NEAR((own.r + shared.r) / truth.r, 1.0, 1e-12) << "unoccluded at " << p.x << "," << p.y << "," << p.z;
        else
            EXPECT_NEAR((own.r + shared.r) / truth.r, 1.0, 0.02) << "half shadowed at " << p.x << "," << p.y << "," << p.z;
    }
}

// A sampler that, like the GPU light sampler, answers some pairs exactly
// without the GPU: every third light is in the way of nothing at x > 0
// (E_l = U_l) and hidden at x < 0 (E_l = 0); the others' pairs need the GPU
// and are noisy, each seed seeing a visible fraction uniform in [0, 1]
// (mean ½, as a penumbra's estimate would scatter).
class PartlyOnCpu final : public DirectSampler {
public:
    explicit PartlyOnCpu(const Scene& scene) : scene_(scene) {}
    std::string name() const override { return "partly on the CPU"; }
    static bool cpu(size_t light) { return light % 3 == 0; }
    static Rgb exact(const Light& light, size_t l, const Vec3& x, const Vec3& n) {
        return cpu(l) ? (x.x > 0 ? 1.0 : 0.0) * unoccludedIrradiance(light, x, n)
                      : 0.5 * unoccludedIrradiance(light, x, n);
    }
    VertexSample sample(size_t light, const Vec3& x, const Vec3& n, uint32_t seed) override {
        VertexSample out;
        if (sampleWithoutGpu(light, x, n, seed, out)) return out;
        const double v = double(hash32(seed) >> 8) / 16777216.0;
        return {v * unoccludedIrradiance(scene_.lights[light], x, n), v, true};
    }
    bool sampleWithoutGpu(size_t light, const Vec3& x, const Vec3& n, uint32_t, VertexSample& out) override {
        if (!cpu(light)) return false;
        const double v = x.x > 0 ? 1.0 : 0.0;
        out = {v * unoccludedIrradiance(scene_.lights[light], x, n), v, false};
        return true;
    }
private:
    const Scene& scene_;
};

TEST(SharedLights, LightsAnsweredWithoutTheGpuAreSubtractedExactlyAndNeverDrawn) {
    // The shared estimate asks the wrapped sampler, for its brightest
    // lights, whether it can answer them without the GPU; those it can are
    // counted exactly and the draws go to the rest. Its mean stays Σ (1 −
    // w_l) E_l: over 4096 seeds within 2% (one sample's standard deviation
    // here is 0.18-0.36 of the total, measured over 65,536 seeds, whose
    // means were within 0.07%; so 2% is over 3.5 standard errors). Where
    // every light reaching a point is answered on the CPU the estimate is
    // exact for every seed and needs no GPU pair.
    const Scene scene = emptyOffice(8, 6, 0.4);
    auto coverage = std::make_shared<const LightCoverage>(scene, 0.05);
    SharedLightSampler sampler(scene, coverage, std::make_unique<PartlyOnCpu>(scene), kDraws, kFirstDraws, kPairsOnly);
    const size_t lights = scene.lights.size();
    for (const Vec3& p : {Vec3(2.1, 0.0, 1.3), Vec3(-2.4, 0.0, -0.7), Vec3(3.99, 1.2, 0.4)}) {
        const Vec3 n = p.y == 0 ? Vec3(0, 1, 0) : Vec3(-1, 0, 0);
        Rgb truth(0.0);
        for (size_t l = 0; l < lights; ++l)
            truth += (1 - coverage->weight(l, p)) * PartlyOnCpu::exact(scene.lights[l], l, p, n);
        ASSERT_GT(truth.r, 0.0);
        // Both as a first pass (asking none) and as later samples.
        for (bool firstPass : {true, false}) {
            sampler.firstSamples(firstPass);
            Rgb mean(0.0);
            constexpr int kSeeds = 4096;
            for (int k = 0; k < kSeeds; ++k) mean += sampler.sample(lights, p, n, seedFor(11, uint32_t(k))).irradiance;
            mean /= double(kSeeds);
            EXPECT_NEAR(mean.r / truth.r, 1.0, 0.02) << "at " << p.x << "," << p.y << "," << p.z << (firstPass ? ", first pass" : "");
        }
        sampler.firstSamples(false);
    }
    // A scene whose every light the sampler answers on the CPU, every
    // other one hidden (E_l = 0, exact): drawn, as before this rule, the
    // hidden ones made the estimate depend on the seed.
    Scene lit = emptyOffice(8, 6, 0.4);
    lit.lights.resize(0);
    for (size_t l = 0; l < scene.lights.size(); l += 3) lit.lights.push_back(scene.lights[l]);
    ASSERT_LE(lit.lights.size(), 16u) << "all of them among the lights asked";
    auto litCoverage = std::make_shared<const LightCoverage>(lit, 0.3);  // fewer lights: each shares where under 30%
    struct AllOnCpu final : DirectSampler {
        const Scene& scene;
        explicit AllOnCpu(const Scene& s) : scene(s) {}
        std::string name() const override { return "all on the CPU"; }
        static double visible(size_t light) { return light % 2 == 0 ? 1.0 : 0.0; }
        VertexSample sample(size_t light, const Vec3& x, const Vec3& n, uint32_t) override {
            ADD_FAILURE() << "a GPU pair was asked for";
            return {visible(light) * unoccludedIrradiance(scene.lights[light], x, n), visible(light), false};
        }
        bool sampleWithoutGpu(size_t light, const Vec3& x, const Vec3& n, uint32_t, VertexSample& out) override {
            out = {visible(light) * unoccludedIrradiance(scene.lights[light], x, n), visible(light), false};
            return true;
        }
    };
    SharedLightSampler exact(lit, litCoverage, std::make_unique<AllOnCpu>(lit), kDraws, kFirstDraws, kPairsOnly);
    const Vec3 p(-2.4, 0.0, -0.7), n(0, 1, 0);
    Rgb truth(0.0);
    for (size_t l = 0; l < lit.lights.size(); ++l)
        truth += (1 - litCoverage->weight(l, p)) * AllOnCpu::visible(l) * unoccludedIrradiance(lit.lights[l], p, n);
    ASSERT_GT(truth.r, 0.0);
    for (uint32_t seed : {1u, 2u, 99u}) {
        VertexSample s;
        ASSERT_TRUE(exact.sampleWithoutGpu(lit.lights.size(), p, n, seed, s));
        EXPECT_NEAR(s.irradiance.r / truth.r, 1.0, 1e-12) << "seed " << seed;
        EXPECT_EQ(exact.sample(lit.lights.size(), p, n, seed).irradiance, s.irradiance);
    }
}

TEST(SharedLights, EachEstimateReportsItsDrawsScatter) {
    const Scene scene = emptyOffice(8, 6, 0.4);
    auto coverage = std::make_shared<const LightCoverage>(scene, 0.05);
    const size_t lights = scene.lights.size();
    const Vec3 up(0, 1, 0);
    {
        // Every draw says the same where each light's occluded part is in
        // proportion to its draw weight: half of every light hidden (x < 0)
        // or none (x > 0). Their scatter, and so the variance, is 0.
        SharedLightSampler sampler(scene, coverage,
                                   std::make_unique<test::FunctionDirectSampler<HalfShadowed>>(HalfShadowed{&scene}),
                                   kDraws, kFirstDraws, kPairsOnly);
        for (const Vec3& p : {Vec3(2.1, 0.0, 1.3), Vec3(-2.4, 0.0, -0.7)}) {
            const VertexSample s = sampler.sample(lights, p, up, 3);
            EXPECT_GE(s.ownVariance, 0.0);
            EXPECT_LE(s.ownVariance, 1e-20 * luminance(s.irradiance) * luminance(s.irradiance)) << "at x " << p.x;
        }
    }
    // Draws whose visibility is uniform in [0, 1] (PartlyOnCpu's GPU pairs),
    // 4 of them as in a first pass, which asks no light: over 4096 seeds,
    // the mean variance reported against the estimates' own scatter. The
    // draws are stratified over the lights' CDF, but each stratum holds the
    // same mix of CPU and GPU lights and the visibilities are independent,
    // so the stratification gains nothing and the two agree in expectation.
    // The scatter's relative standard error over 4096 seeds is about
    // √(2/4095) = 2.2% (somewhat more for these skewed estimates), and the
    // mean variance's about as much: over 8 other bases of the seeds the
    // ratio read 0.955-1.049 (standard deviation 3.4%), so 10% is about 3
    // of them.
    SharedLightSampler sampler(scene, coverage, std::make_unique<PartlyOnCpu>(scene), kDraws, kFirstDraws, kPairsOnly);
    const Vec3 p(2.1, 0.0, 1.3);
    {
        FirstSamples first(sampler);
        double sum = 0, squares = 0, own = 0;
        constexpr int kSeeds = 4096;
        for (int k = 0; k < kSeeds; ++k) {
            const VertexSample s = sampler.sample(lights, p, up, seedFor(13, uint32_t(k)));
            const double y = luminance(s.irradiance);
            sum += y, squares += y * y, own += s.ownVariance;
        }
        const double scatter = (squares - sum * sum / kSeeds) / (kSeeds - 1);
        ASSERT_GT(scatter, 0.0);
        EXPECT_NEAR(own / kSeeds / scatter, 1.0, 0.1);
    }
    // Where no more lights are left to draw than an estimate draws, each is
    // taken once: the estimate is then the exact sum over them of what the
    // wrapped sampler says (its own noise aside), and its variance 0. The
    // 12-panel office's lights are all asked (16 are), every third answered
    // on the CPU; the other 8 are drawn, in light order.
    const Scene twelve = emptyOffice(4, 3, 0.6);
    auto twelveCoverage = std::make_shared<const LightCoverage>(twelve, 0.3);
    SharedLightSampler each(twelve, twelveCoverage, std::make_unique<PartlyOnCpu>(twelve), kDraws, kFirstDraws,
                            kPairsOnly);
    PartlyOnCpu wrapped(twelve);
    for (const Vec3& q : {Vec3(1.7, 0.0, 0.9), Vec3(-2.2, 0.0, -1.1)}) {
        for (uint32_t seed : {1u, 77u}) {
            Rgb expected(0.0);
            uint32_t drawn = 0;
            for (size_t l = 0; l < twelve.lights.size(); ++l) {
                const double w = twelveCoverage->weight(l, q);
                const Rgb u = unoccludedIrradiance(twelve.lights[l], q, up);
                if (w >= 1 || !(luminance(u) > 0)) continue;
                const Rgb e = PartlyOnCpu::cpu(l) ? PartlyOnCpu::exact(twelve.lights[l], l, q, up)
                                                  : wrapped.sample(l, q, up, seedFor(seed, drawn++, uint32_t(l))).irradiance;
                expected += (1 - w) * e;
            }
            ASSERT_GT(drawn, 0u);
            ASSERT_LE(drawn, 16u);
            const VertexSample s = each.sample(twelve.lights.size(), q, up, seed);
            ASSERT_GT(expected.r, 0.0);
            EXPECT_NEAR(s.irradiance.r / expected.r, 1.0, 1e-12) << "at x " << q.x << ", seed " << seed;
            EXPECT_EQ(s.ownVariance, 0.0);
        }
    }
}

TEST(SharedLights, ShadowRaysAverageToTheExactSharedLight) {
    // Where more lights are left to draw than K pairs would take, the shared
    // estimate's occluded part comes from shadow rays, each to a point drawn
    // on a light drawn by its share. Against the exact visible light of
    // every light (ExactDirect: the occluders projected onto the light and
    // subtracted with CGAL's Booleans), in the 48-panel office, at floor
    // points, one per row across the room, that the furniture hides 10-50%
    // of the shared lights from (by rays to their centres). The wrapped sampler answers
    // every pair exactly without the GPU, so later samples subtract the 16
    // brightest exactly and shoot the rays at the rest; a first pass asks
    // none. Over 2048 seeds the mean is within 4 of its standard errors
    // (each measured from the same estimates) of the truth; that standard
    // error is under 1% of the light, so the test sees a bias of a few
    // percent; and the estimates do see the shadow (their mean is over 1%
    // below the unoccluded light). Each estimate's own variance takes the
    // rays as independent; they are stratified over the lights, so it must
    // not fall below the estimates' measured scatter by more than the
    // latter's sampling error (√(2/2047) = 3%, 15% is five of them).
    OfficeSettings os;
    os.panelsX = 8;
    os.panelsZ = 6;
    const Scene scene = makeOfficeScene(os);
    const ExactDirect exact(scene);
    struct ExactOnCpu final : DirectSampler {
        const ExactDirect& exact;
        explicit ExactOnCpu(const ExactDirect& e) : exact(e) {}
        std::string name() const override { return "exact on the CPU"; }
        VertexSample sample(size_t l, const Vec3& x, const Vec3& n, uint32_t) override {
            return {exact.irradiance(l, x, n), 1.0, false};
        }
        bool sampleWithoutGpu(size_t l, const Vec3& x, const Vec3& n, uint32_t seed, VertexSample& out) override {
            out = sample(l, x, n, seed);
            return true;
        }
    };
    auto coverage = std::make_shared<const LightCoverage>(scene, 0.1);
    SharedLightSampler sampler(scene, coverage, std::make_unique<ExactOnCpu>(exact));
    const EmbreeScene rays(scene);
    const size_t lights = scene.lights.size();
    const Vec3 up(0, 1, 0);
    int tested = 0;
    for (double x = -3.7; x < 4 && tested < 3; x += 0.53)
        for (double z = -2.7; z < 3; z += 0.47) {
            const Vec3 p(x, 0.0, z);
            int reaching = 0, hidden = 0;
            for (size_t l = 0; l < lights; ++l) {
                if (coverage->weight(l, p) >= 1 || !(unoccludedIrradiance(scene.lights[l], p, up).g > 0)) continue;
                ++reaching;
                const Vec3 origin = p + 1e-5 * up, to = scene.lights[l].centroid - origin;
                RayFilter filter;
                filter.skipLight = int(l);
                hidden += rays.occluded(origin, to, 1e-6, 1 - 1e-6, filter);
            }
            if (reaching <= 2 * SharedLightSampler::kAskedLights || 10 * hidden < reaching || 2 * hidden > reaching)
                continue;
            Rgb truth(0.0), open(0.0);
            for (size_t l = 0; l < lights; ++l) {
                const double w = coverage->weight(l, p);
                truth += (1 - w) * exact.irradiance(l, p, up);
                open += (1 - w) * unoccludedIrradiance(scene.lights[l], p, up);
            }
            for (bool firstPass : {true, false}) {
                sampler.firstSamples(firstPass);
                constexpr int kSeeds = 2048;
                double sum = 0, squares = 0, own = 0;
                for (int k = 0; k < kSeeds; ++k) {
                    const VertexSample s = sampler.sample(lights, p, up, seedFor(17, uint32_t(k)));
                    sum += s.irradiance.g, squares += s.irradiance.g * s.irradiance.g;
                    own += s.ownVariance;
                }
                const double mean = sum / kSeeds, scatter = (squares - sum * sum / kSeeds) / (kSeeds - 1);
                const double standardError = std::sqrt(scatter / kSeeds);
                const std::string at = concat("at ", p.x, ",", p.z, firstPass ? ", first pass" : "");
                EXPECT_NEAR(mean, truth.g, 4 * standardError) << at;
                EXPECT_LT(standardError, 0.01 * truth.g) << at;
                EXPECT_LT(truth.g, 0.99 * open.g) << at;
                // ownVariance is in luminance; the scatter in green. Their
                // ratio is luminance's over green's: the panels' colour.
                const double lumaOverGreen = luminance(open) / open.g;
                EXPECT_GT(own / kSeeds, 0.85 * scatter * lumaOverGreen * lumaOverGreen) << at;
            }
            sampler.firstSamples(false);
            ++tested;
            break;  // the next point from another row
        }
    EXPECT_EQ(tested, 3) << "floor points in the furniture's partial shadow";
}

TEST(SharedLights, ShadowRaysAreExactWhereNothingIsInTheWay) {
    // In the office without furniture no shadow ray is blocked (not by the
    // light it goes to, nor by the other panels in its plane): every seed's
    // estimate is Σ (1 − w_l) U_l, with no variance, as the pairs give.
    const Scene scene = emptyOffice(8, 6, 0.4);
    auto coverage = std::make_shared<const LightCoverage>(scene, 0.05);
    const auto closedForm = [&](size_t l, const Vec3& x, const Vec3& n, uint32_t) {
        return VertexSample{unoccludedIrradiance(scene.lights[l], x, n), 1.0, false};
    };
    SharedLightSampler sampler(scene, coverage,
                               std::make_unique<test::FunctionDirectSampler<decltype(closedForm)>>(closedForm));
    const size_t lights = scene.lights.size();
    for (const Vec3& p : {Vec3(2.1, 0.0, 1.3), Vec3(3.99, 1.2, 0.4), Vec3(-1.0, 2.7, 2.99)}) {
        const Vec3 n = p.y == 0 ? Vec3(0, 1, 0) : std::abs(p.x) > 3.9 ? Vec3(-1, 0, 0) : Vec3(0, 0, -1);
        Rgb truth(0.0);
        for (size_t l = 0; l < lights; ++l)
            truth += (1 - coverage->weight(l, p)) * unoccludedIrradiance(scene.lights[l], p, n);
        ASSERT_GT(truth.r, 0.0);
        for (uint32_t seed : {1u, 5u, 1234u}) {
            const VertexSample s = sampler.sample(lights, p, n, seed);
            EXPECT_NEAR(s.irradiance.r / truth.r, 1.0, 1e-12) << "at " << p.x << "," << p.y << "," << p.z;
            EXPECT_EQ(s.ownVariance, 0.0);
            EXPECT_NEAR(s.visibility, 1.0, 1e-12);
        }
    }
}

// A direct cache's shared mesh: its estimates' own variance makes a vertex
// sampled once count as noisy, where the lights' own meshes (an exact
// sampler's one sample outside penumbrae) count as exact. The shared
// mesh's estimates are 1 W/m² (the lights' own 0, so that the scoring's
// dark floor, a fiftieth of twice the mean light, stays small: 0.04) and
// say 1e-4 of their own variance, so before any
// resampled vertex measures the scale (1 until then) each shared vertex's
// standard error is exactly √1e-4 = 1%, over the 0.5% tolerance; a budget
// of resamples goes to shared vertices alone.
TEST(SharedLights, TheSharedMeshsScatteredEstimatesAreResampled) {
    const Scene scene = emptyOffice(8, 6, 0.4);
    const size_t lights = scene.lights.size();
    CacheSettings cs;
    cs.lightShare = 0.05;
    cs.uniformEdgeFraction = 0;  // uniform light: nothing to split
    CacheLayout layout;
    layout.coverage = std::make_shared<const LightCoverage>(scene, cs.lightShare);
    IrradianceCache cache(scene, cs, layout);
    ASSERT_TRUE(cache.hasSharedMesh());
    auto sampler = samplerOf([&](size_t mesh, const Vec3&, const Vec3&, uint32_t) {
        VertexSample v;
        v.irradiance = Rgb(mesh == lights ? 1.0 : 0.0);
        if (mesh == lights) v.ownVariance = 1e-4;
        return v;
    });
    cache.refine(sampler, 1 << 22, 1);
    std::vector<IrradianceMeshCopy> meshes = cache.copyMeshes();
    ASSERT_EQ(meshes.size(), lights + 1);
    size_t shared = meshes[lights].positions.size();
    ASSERT_GT(shared, 100u);
    for (size_t m = 0; m <= lights; ++m)
        for (size_t v = 0; v < meshes[m].positions.size(); ++v) {
            ASSERT_EQ(meshes[m].samples[v], 1u) << "mesh " << m;
            EXPECT_NEAR(meshes[m].standardError[v].g, m == lights ? 0.01 : 0.0, 1e-12) << "mesh " << m;
        }
    const RefineReport r = cache.refine(sampler, shared / 2, 2);
    EXPECT_EQ(r.splits, 0u);
    EXPECT_EQ(r.resamples, shared / 2);
    meshes = cache.copyMeshes();
    size_t resampled = 0;
    for (size_t m = 0; m <= lights; ++m)
        for (size_t v = 0; v < meshes[m].positions.size(); ++v)
            if (meshes[m].samples[v] > 1) {
                EXPECT_EQ(m, lights) << "a light's own mesh resampled";
                ++resampled;
            }
    EXPECT_EQ(resampled, shared / 2);
}

TEST(SharedLights, TheSharedMeshsLightIsItsOwnIntegral) {
    // What the worker discounts direct light's weight by (CacheWorker: the
    // share φ of direct light the shared mesh holds): the shared mesh's
    // integral alone, as integratedLuminance sums every mesh's (each
    // vertex's mean times a third of its faces' area, the linear meshes'
    // exact integral). Lights' own meshes at 1 W/m², the shared one at
    // 1 + x²/10: only the order of the sums differs. Without a shared mesh, 0.
    const Scene scene = emptyOffice(8, 6, 0.4);
    const size_t lights = scene.lights.size();
    CacheSettings cs;
    cs.lightShare = 0.05;
    CacheLayout layout;
    layout.coverage = std::make_shared<const LightCoverage>(scene, cs.lightShare);
    IrradianceCache cache(scene, cs, layout);
    ASSERT_TRUE(cache.hasSharedMesh());
    EXPECT_EQ(cache.sharedLuminance(), 0.0);  // nothing sampled yet
    auto sampler = samplerOf([&](size_t mesh, const Vec3& x, const Vec3&, uint32_t) {
        return VertexSample{Rgb(mesh == lights ? 1 + 0.1 * x.x * x.x : 1.0), 1.0, false};
    });
    cache.refine(sampler, 1 << 22, 1);
    const std::vector<IrradianceMeshCopy> meshes = cache.copyMeshes();
    ASSERT_EQ(meshes.size(), lights + 1);
    const double shared = luminance(test::integrate(meshes[lights]));
    double total = 0;
    for (const IrradianceMeshCopy& m : meshes) total += luminance(test::integrate(m));
    ASSERT_GT(shared, 0.0);
    ASSERT_GT(total, shared);
    EXPECT_NEAR(cache.sharedLuminance(), shared, 1e-9 * shared);
    EXPECT_NEAR(cache.integratedLuminance(), total, 1e-9 * total);

    CacheSettings none = cs;
    none.lightShare = 0;
    IrradianceCache perLight(scene, none);
    ASSERT_FALSE(perLight.hasSharedMesh());
    perLight.refine(sampler, 1 << 22, 1);
    EXPECT_GT(perLight.integratedLuminance(), 0.0);
    EXPECT_EQ(perLight.sharedLuminance(), 0.0);
}

TEST(SharedLights, ARoomOfAHundredSmallLightsKeepsTheirPower) {
    // A closed room: every watt the lights emit lands on its surfaces, so
    // ∫ E dA over all the cache meshes equals the lights' power. The meshes
    // interpolate E linearly between vertices refined to 1%: 1% is the bound
    // asked, the integral of the error of a converged mesh is well below it.
    const Scene scene = emptyOffice(10, 10, 0.1);
    ASSERT_EQ(scene.lights.size(), 100u);
    Rgb power(0.0);
    for (const Light& l : scene.lights) power += l.power();  // Φ = π L A, W (the office is in metres)
    for (double share : {0.05, 0.0}) {
        CacheSettings cs;
        cs.lightShare = share;
        CacheLayout layout;
        layout.coverage = std::make_shared<const LightCoverage>(scene, share);
        IrradianceCache cache(scene, cs, layout);
        EXPECT_EQ(cache.hasSharedMesh(), share > 0);
        SharedLightSampler sampler(
            scene, layout.coverage,
            std::make_unique<test::FunctionDirectSampler<std::function<VertexSample(size_t, const Vec3&, const Vec3&,
                                                                                   uint32_t)>>>(
                [&](size_t l, const Vec3& x, const Vec3& n, uint32_t) {
                    return VertexSample{unoccludedIrradiance(scene.lights[l], x, n), 1.0, false};
                }));
        for (int round = 0; round < 200; ++round)
            if (cache.refine(sampler, 1 << 16, 1).converged()) break;
        Rgb landed(0.0);
        for (const IrradianceMeshCopy& m : cache.copyMeshes()) landed += test::integrate(m);
        EXPECT_NEAR(landed.r / power.r, 1.0, 0.01) << "light share " << share << ": " << cache.totalVertices()
                                                   << " vertices";
        if (share > 0) {
            // Memory grows with the area each light covers, not lights × scene.
            CacheSettings none = cs;
            none.lightShare = 0;
            const IrradianceCache perLight(scene, none);
            EXPECT_LT(IrradianceCache(scene, cs, layout).totalVertices(), perLight.totalVertices() / 3);
        }
    }
}

TEST(SamplerPool, ThreadsGiveTheSameCacheAsOneForASampleBudget) {
    // Direct and indirect light on the Cornell box, 12,000 samples: the
    // cache (every mesh, bit for bit) must not depend on the threads.
    const Scene scene = makeCornellBox();
    DirectChoice direct;
    direct.backend = GlBackend::OsMesa;
    IndirectChoice indirect;
    indirect.bounces.forced = 2;
    indirect.decide(scene);
    auto run = [&](int threads, double startSeconds = IndirectSettings{}.startSeconds) {
        SessionSettings s;
        s.worker.threads = threads;
        s.worker.seed = 5;
        s.indirect = indirect.solver;
        s.indirect->startSeconds = startSeconds;
        StopRule stop;
        stop.samples = 12000;
        ProgressiveSession session(scene, s, samplerFactory(scene, direct, indirect), stop);
        test::refineUntilStopped(session, stop);
        std::vector<IrradianceMeshCopy> meshes = session.cache().copyMeshes();
        for (const IrradianceMeshCopy& m : session.indirect()->copyMeshes()) meshes.push_back(m);
        return meshes;
    };
    const std::vector<IrradianceMeshCopy> one = run(1), two = run(2), three = run(3);
    // Nor on the machine's speed: indirect light starts early when direct
    // light's first pass would take longer than startSeconds at the measured
    // rate; at 0 s every rate would start it early, at 1e9 s none, and a
    // loaded machine lies between. Under a budget it waits either way.
    const std::vector<IrradianceMeshCopy> fast = run(1, 1e9), slow = run(1, 0.0);
    ASSERT_EQ(one.size(), two.size());
    ASSERT_EQ(one.size(), three.size());
    ASSERT_EQ(fast.size(), slow.size());
    for (size_t m = 0; m < one.size(); ++m) {
        ASSERT_EQ(one[m].positions, two[m].positions) << "mesh " << m;
        EXPECT_EQ(one[m].irradiance, two[m].irradiance) << "mesh " << m;
        EXPECT_EQ(one[m].irradiance, three[m].irradiance) << "mesh " << m;
        EXPECT_EQ(one[m].samples, two[m].samples) << "mesh " << m;
    }
    for (size_t m = 0; m < fast.size(); ++m) {
        ASSERT_EQ(fast[m].positions, slow[m].positions) << "mesh " << m;
        EXPECT_EQ(fast[m].irradiance, slow[m].irradiance) << "mesh " << m;
    }
}

TEST(SamplerPool, ThreadsGiveTheSameSharedMeshByRaysForASampleBudget) {
    // The same with lights sharing: the 48-panel office's direct light, its
    // shared mesh estimated by shadow rays (more lights left than its pairs
    // would take) on each thread's own Embree scene; 20,000 samples, so the
    // first pass and some refinement.
    OfficeSettings os;
    os.panelsX = 8;
    os.panelsZ = 6;
    const Scene scene = makeOfficeScene(os);
    DirectChoice direct;
    direct.backend = GlBackend::OsMesa;
    IndirectChoice none;
    none.enabled = false;
    auto run = [&](int threads) {
        SessionSettings s;
        s.worker.threads = threads;
        s.worker.seed = 3;
        StopRule stop;
        stop.samples = 20000;
        ProgressiveSession session(scene, s, samplerFactory(scene, direct, none), stop);
        test::refineUntilStopped(session, stop);
        return session.cache().copyMeshes();
    };
    const std::vector<IrradianceMeshCopy> one = run(1), two = run(2);
    ASSERT_EQ(one.size(), scene.lights.size() + 1);
    ASSERT_EQ(one.size(), two.size());
    for (size_t m = 0; m < one.size(); ++m) {
        ASSERT_EQ(one[m].positions, two[m].positions) << "mesh " << m;
        EXPECT_EQ(one[m].irradiance, two[m].irradiance) << "mesh " << m;
        EXPECT_EQ(one[m].samples, two[m].samples) << "mesh " << m;
    }
}


TEST(SharedLights, OwnMeshesShowOnlyTheFacesInView) {
    // A light's own mesh keeps only some faces; where it lacks the face in
    // view, the compositor must not show what it keeps behind it. The office
    // with every light's closed form (no occlusion, so both caches hold the
    // same function), composited from the cache with lights sharing and
    // from one with a mesh per light everywhere: the images differ only by
    // interpolation between the two caches' vertices. Before the fix the
    // wall behind the partition showed through it, 20-50% too bright there.
    const Scene scene = makeOfficeScene(OfficeSettings{});
    const auto closedForm = [&](size_t light, const Vec3& x, const Vec3& n, uint32_t) {
        return VertexSample{unoccludedIrradiance(scene.lights[light], x, n), 1.0, false};
    };
    auto unoccluded = samplerOf(closedForm);
    auto coverage = std::make_shared<const LightCoverage>(scene, 0.1);
    ASSERT_TRUE(coverage->sharing());
    CacheLayout sharedLayout;
    sharedLayout.coverage = coverage;
    IrradianceCache shared(scene, CacheSettings{}, sharedLayout), perLight(scene, CacheSettings{});
    SharedLightSampler sharedSampler(scene, coverage,
                                     std::make_unique<test::FunctionDirectSampler<decltype(closedForm)>>(closedForm),
                                     kDraws, kFirstDraws, kPairsOnly);
    shared.sampleUnsampled(sharedSampler, 1);
    perLight.sampleUnsampled(unoccluded, 1);
    ASSERT_EQ(shared.meshCount(), scene.lights.size() + 1);

    Compositor compositor(test::glContext(), scene);
    CompositorSettings cs;
    cs.width = 160;
    cs.height = 90;
    cs.supersample = 2;
    const Camera camera = scene.cameraOrDefault(16.0 / 9.0);
    const ImageRgb a = compositor.render(camera, shared.copyMeshes(), cs);
    const ImageRgb b = compositor.render(camera, perLight.copyMeshes(), cs);
    // Per pixel within 5% where the image is lit (the base meshes' linear
    // interpolation of a smooth closed form: 0.3% on the partition; more at
    // a few silhouette pixels where the two caches' triangles meet the
    // pixel differently), and the mean within 0.5%.
    size_t off = 0, lit = 0;
    double sumA = 0, sumB = 0;
    const size_t pixels = size_t(a.width) * size_t(a.height);
    for (size_t i = 0; i < pixels; ++i) {
        const double x = a.data[3 * i + 1], y = b.data[3 * i + 1];
        sumA += x, sumB += y;
        if (y > 1) ++lit, off += std::abs(x - y) > 0.05 * y;
    }
    EXPECT_GT(lit, pixels / 2);
    EXPECT_LT(double(off), 0.01 * double(lit)) << off << " of " << lit << " lit pixels off by over 5%";
    EXPECT_NEAR(sumA / sumB, 1.0, 0.005);
}
