// The image's error estimate (viewer/compositor/ImageErrorEstimate.h), what
// `render --until-error` stops on, against the relative RMSE measured
// against the path tracer, on the Cornell box and the office, and the
// Cornell box made 1,000 times dimmer.
//
// Each state is the worker's snapshot after a budget of samples on one
// thread (the same on any machine). The measured error is the composite's
// relative RMSE against a path-traced reference with the reference's own
// noise taken out in quadrature (E[(x − r)²] = (x − R)² + σ²). The issue
// asks the estimate to be within a factor of 1.5 of the measurement from
// 10% down to 1%; a state is checked where the measurement is at least
// twice the reference's noise before it is taken out (below, the
// subtraction is too uncertain to judge a factor of 1.5). The composite uses 16 sub-pixel passes, so that
// what the estimate leaves out (the sub-pixel sampling: 0.4% of the Cornell
// box at 16 passes against 64) stays small beside what is checked.
#include "GlTestContext.h"

#include "cache/ProgressiveSession.h"
#include "core/image/ImageMetrics.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "core/scenes/CornellBox.h"
#include "core/scenes/OfficeScene.h"
#include "gpu_sampling/SamplerFactory.h"
#include "viewer/compositor/Compositor.h"
#include "viewer/compositor/ImageErrorEstimate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

namespace ml {
namespace {

// A session of `scene` with its plan's indirect light, on one thread (the
// same cache on any machine), ending after `samples` samples; started.
std::unique_ptr<ProgressiveSession> startSession(const Scene& scene, uint64_t samples) {
    DirectChoice direct;
    direct.backend = GlBackend::OsMesa;
    IndirectChoice indirect;
    indirect.decide(scene);
    SessionSettings s;
    s.worker.threads = 1;
    s.worker.seed = 3;
    s.indirect = indirect.solver;
    StopRule stop;
    stop.samples = samples;
    auto session = std::make_unique<ProgressiveSession>(scene, s, samplerFactory(scene, direct, indirect), stop);
    session->start();
    return session;
}

// The snapshot's meshes after `samples` samples.
CacheSnapshot refined(const Scene& scene, uint64_t samples) {
    const std::unique_ptr<ProgressiveSession> session = startSession(scene, samples);
    CacheWorker::Reader reader = session->reader();
    StopRule stop;
    stop.samples = samples;
    session->refineUntil(reader, stop, 0);
    session->stop();
    const CacheSnapshot* last = reader.acquire();
    CacheSnapshot copy;
    copy.direct = last->direct;
    copy.indirect = last->indirect;
    copy.samples = last->samples;
    return copy;
}

struct Check {
    double estimated, measured, raw;
    bool judged;  // the raw error at least twice the reference's noise
};

// The estimate against the measurement at each budget.
std::vector<Check> compare(const Scene& scene, int width, int height, int spp, std::vector<uint64_t> budgets) {
    const Camera camera = scene.cameraOrDefault(double(width) / height);
    const EmbreeScene rays(scene);
    const PathTracer tracer(rays, PathTracerSettings{});
    const ReferenceImage ref = tracer.render(camera, width, height, spp);
    const double noise = relativeRmsError(ref.standardError, ref.radiance);
    Compositor compositor(test::glContext(), scene);
    CompositorSettings cs;
    cs.width = width;
    cs.height = height;
    cs.passes = 16;
    std::vector<Check> out;
    for (uint64_t budget : budgets) {
        const CacheSnapshot snap = refined(scene, budget);
        // No bounce shown yet: `render` calls the error unknown (the image
        // lacks light nothing has measured), so there is nothing to judge.
        if (snap.indirect.empty()) continue;
        const ImageErrorEstimate e = estimateImageError(compositor, scene, camera, snap.direct, snap.indirect, cs);
        const double raw = relativeRmse(e.image, ref.radiance);
        const double measured = std::sqrt(std::max(0.0, raw * raw - noise * noise));
        std::printf("%s, %llu samples: estimated %.2f%%, measured %.2f%% (raw %.2f%%, reference noise %.2f%%)\n",
                    scene.name.c_str(), static_cast<unsigned long long>(budget), 100 * e.cache, 100 * measured,
                    100 * raw, 100 * noise);
        out.push_back({e.cache, measured, raw, raw >= 2 * noise});
    }
    return out;
}

void expectWithinFactor(const std::vector<Check>& checks, double factor) {
    int judged = 0;
    for (const Check& c : checks) {
        // The truth lies between the measurement with the reference's noise
        // taken out and the raw one; where the noise is small beside the
        // error, both are the same.
        EXPECT_LE(c.estimated, factor * c.raw);
        EXPECT_GE(c.estimated, c.measured / factor);
        if (!c.judged) continue;
        ++judged;
        EXPECT_LE(c.estimated, factor * c.measured);
    }
    EXPECT_GE(judged, 1) << "no state measurable against the reference's noise";
}

TEST(ImageErrorEstimate, CornellBoxWithinOneAndAHalfOfThePathTracer) {
    // 64x64 against 2048 spp (1.3% noise, 14 s on 2 cores): bounce 1 done
    // and bounce 2 not shown yet (10,000 samples), its tail shaped as
    // IndirectSolver.h's shapeAsLaterBounces says, by the albedo each
    // vertex sees (4.2% measured, 4.1% estimated; half bounce 1's shape and
    // half its mean 8.0% and 6.1%; bounce 1's own shape 9.9% and 4.8%);
    // bounce 2 half gathered, shown with the later bounces as a tail of
    // the ratio bounce 2 measures, shaped again by the albedo seen (12,000:
    // 2.0% measured, 2.4% estimated; 2.5% both with bounce 2's own shape
    // and one ratio for the three channels); and the bounces'
    // first passes further on (24,000: under 1%, within the reference's
    // noise).
    expectWithinFactor(compare(makeCornellBox(), 64, 64, 2048, {10000, 12000, 24000}), 1.5);
}

TEST(ImageErrorEstimate, OfficeWithinOneAndAHalfOfThePathTracer) {
    // A small office (4 x 3 m, two panels, two desks, a cabinet and the
    // partition) at 64x36 against 1024 spp: before bounce 2 is shown
    // (30,000 samples; 7.1% measured, 8.4% estimated) and with the first
    // passes done (60,000).
    OfficeSettings o;
    o.width = 4;
    o.depth = 3;
    o.panelsX = 2;
    o.panelsZ = 1;
    o.desks = 2;
    o.cabinets = 1;
    expectWithinFactor(compare(makeOfficeScene(o), 64, 36, 1024, {30000, 60000}), 1.5);
}

// The scene with every emitter's radiance times k.
Scene withEmission(Scene scene, float k) {
    for (Material& m : scene.materials) m.ke *= k;
    for (Light& l : scene.lights) l.radiance *= k;
    return scene;
}

TEST(ImageErrorEstimate, ADimSceneEstimatesAndMeasuresAsItsBrightTwin) {
    // The Cornell box at half its emission (mean radiance 0.07) and 1,000
    // times dimmer still (7e-5, like the back rooms of ../shared/scenes at
    // 6e-4): the same budget makes the same cache scaled (the refinement
    // judges levels against the cache's own white), so the dim box's
    // estimate, and its error against the reference scaled alike, must read
    // as its twin's. Both means are under 0.1, where the metric's floor is
    // the mean's square; with a fixed floor of 0.1² the dim box would read under
    // 0.01% (an error of 5% of 7e-5 over 0.1).
    // Tolerance 1% of the value: the two caches are sampled alike but not
    // bit for bit (the sampler's exact solid angles are not scaled, its
    // weights are).
    const float k = 1e-3f;
    const Scene twin = withEmission(makeCornellBox(), 0.5f), dim = withEmission(twin, k);
    const int size = 48;
    const Camera camera = twin.cameraOrDefault(1.0);
    const EmbreeScene rays(twin);
    const ReferenceImage ref = PathTracer(rays, PathTracerSettings{}).render(camera, size, size, 256);
    ImageRgb dimRef = ref.radiance;
    for (float& v : dimRef.data) v *= k;
    Compositor twinCompositor(test::glContext(), twin), dimCompositor(test::glContext(), dim);
    CompositorSettings cs;
    cs.width = cs.height = size;
    cs.passes = 4;
    const CacheSnapshot a = refined(twin, 12000), b = refined(dim, 12000);
    ASSERT_FALSE(a.indirect.empty());
    const ImageErrorEstimate ea = estimateImageError(twinCompositor, twin, camera, a.direct, a.indirect, cs);
    const ImageErrorEstimate eb = estimateImageError(dimCompositor, dim, camera, b.direct, b.indirect, cs);
    const double ma = relativeRmse(ea.image, ref.radiance), mb = relativeRmse(eb.image, dimRef);
    std::printf("twin: estimated %.3f%%, measured %.3f%%; 1/1000 as bright: estimated %.3f%%, measured %.3f%%\n",
                100 * ea.cache, 100 * ma, 100 * eb.cache, 100 * mb);
    EXPECT_GT(ma, 0.01);  // an error to compare, well above rounding
    EXPECT_NEAR(eb.cache, ea.cache, 0.01 * ea.cache);
    EXPECT_NEAR(mb, ma, 0.01 * ma);
}

// Two bounce meshes on the Cornell box's direct mesh's geometry, each with
// the error `error` at every vertex, of which `noise` is noise; direct
// light without error. The estimate of the composite.
double estimateOfTwoMeshes(Compositor& compositor, const Scene& scene, const Camera& camera,
                           const IrradianceMeshCopy& base, const CompositorSettings& cs, const Rgb errors[2],
                           const Rgb noises[2]) {
    IrradianceMeshCopy direct = base;
    direct.predictedError.assign(base.irradiance.size(), Rgb(0.0));
    direct.predictedNoise.assign(base.irradiance.size(), Rgb(0.0));
    std::vector<IrradianceMeshCopy> bounces;
    for (int k = 0; k < 2; ++k) {
        IrradianceMeshCopy m = base;
        m.predictedError.assign(base.irradiance.size(), errors[k]);
        m.predictedNoise.assign(base.irradiance.size(), noises[k]);
        bounces.push_back(std::move(m));
    }
    return estimateImageError(compositor, scene, camera, {direct}, bounces, cs).cache;
}

TEST(ImageErrorEstimate, NoiseOfTwoMeshesAddsInQuadratureTheRestLinearly) {
    // Every bounce draws its own rays, so two meshes' noise σ reads as one
    // mesh's √2 σ; an interpolation error leans the same way in both, so two
    // meshes' b reads as one mesh's 2b. Each pixel's error is Kd/π times
    // √2 σ or 2b, so the estimates are those exactly, and in the ratio √2.
    // Tolerance 1e-4 of the value: float composites of σ, σ² and Kd.
    const Scene scene = makeCornellBox();
    const CacheSnapshot snap = refined(scene, 3000);
    ASSERT_EQ(snap.direct.size(), 1u);
    const Camera camera = scene.cameraOrDefault(1.0);
    Compositor compositor(test::glContext(), scene);
    CompositorSettings cs;
    cs.width = cs.height = 48;
    cs.passes = 1;
    const IrradianceMeshCopy& base = snap.direct.front();
    double mean = 0;
    for (const Rgb& e : base.irradiance) mean += luminance(e);
    const Rgb sigma(0.05 * mean / double(base.irradiance.size())), zero(0.0);
    const auto estimate = [&](Rgb e0, Rgb n0, Rgb e1, Rgb n1) {
        const Rgb errors[2] = {e0, e1}, noises[2] = {n0, n1};
        return estimateOfTwoMeshes(compositor, scene, camera, base, cs, errors, noises);
    };
    const double noiseInBoth = estimate(sigma, sigma, sigma, sigma);
    const double noiseInOne = estimate(std::sqrt(2.0) * sigma, std::sqrt(2.0) * sigma, zero, zero);
    const double biasInBoth = estimate(sigma, zero, sigma, zero);
    const double biasInOne = estimate(2.0 * sigma, zero, zero, zero);
    std::printf("noise in both %.5f%%, in one %.5f%%; bias in both %.5f%%, in one %.5f%%\n", 100 * noiseInBoth,
                100 * noiseInOne, 100 * biasInBoth, 100 * biasInOne);
    ASSERT_GT(noiseInBoth, 1e-4);
    EXPECT_NEAR(noiseInBoth, noiseInOne, 1e-4 * noiseInOne);
    EXPECT_NEAR(biasInBoth, biasInOne, 1e-4 * biasInOne);
    EXPECT_NEAR(biasInBoth / noiseInBoth, std::sqrt(2.0), 1e-4);
}

TEST(ImageErrorEstimate, ALongRunsErrorDoesNotRise) {
    // One session of the Cornell box (full GI, one thread), its snapshots
    // taken as the samples pass 16,000, 32,000 and 64,000: the composite's
    // relative RMSE against one path-traced reference must not rise from
    // one to the next. The reference's noise adds the same σ² to every
    // measurement (the cross term averages out), so raw errors compare; a
    // rise of up to 0.05% (absolute) is allowed for that cross term.
    const Scene scene = makeCornellBox();
    const int size = 48;
    const Camera camera = scene.cameraOrDefault(1.0);
    const EmbreeScene rays(scene);
    const ReferenceImage ref = PathTracer(rays, PathTracerSettings{}).render(camera, size, size, 1024);
    const std::unique_ptr<ProgressiveSession> session = startSession(scene, 64000);
    CacheWorker::Reader reader = session->reader();
    Compositor compositor(test::glContext(), scene);
    CompositorSettings cs;
    cs.width = cs.height = size;
    cs.passes = 16;
    std::vector<double> errors;
    for (uint64_t budget : {16000, 32000, 64000}) {
        const CacheSnapshot* s = nullptr;
        for (;;) {
            s = reader.acquire();
            if ((s && s->samples >= budget) || session->finished()) break;
            session->waitForVersion((s ? s->version : 0) + 1, 0.05);
        }
        s = reader.acquire();
        ASSERT_TRUE(s);
        errors.push_back(relativeRmse(compositor.render(camera, s->direct, s->indirect, cs), ref.radiance));
        std::printf("%llu samples (%d of %d bounces done): relative RMSE %.3f%%\n",
                    static_cast<unsigned long long>(s->samples), s->bouncesFinished, s->bounces, 100 * errors.back());
    }
    session->stop();
    for (size_t k = 1; k < errors.size(); ++k) EXPECT_LE(errors[k], errors[k - 1] + 5e-4) << "snapshot " << k;
}

}  // namespace
}  // namespace ml
