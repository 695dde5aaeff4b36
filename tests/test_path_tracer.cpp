// The reference path tracer (core/raytrace): furnaces whose radiance is
// known in closed form, direct irradiance against the exact reference,
// determinism across thread counts, the BSDF's sampling, and the
// `reference` and `probe --method path|raytrace` commands.
//
// Statistical tolerances. Every Monte Carlo comparison allows 4 standard
// errors, the error being the tracer's own estimate (pooled over many pixels
// or over thousands of samples, so itself known to a few percent): a correct
// tracer fails one such check with probability ~6e-5 (normal tail), below
// 1 % over all the checks of this file. The seeds are fixed, so the outcome
// is reproducible; a wrong estimator (a missing MIS weight, a light counted
// twice, a leak) is off by many standard errors.
#include "core/Error.h"
#include "core/MeshUtil.h"
#include "core/image/Image.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "core/raytrace/PhongBsdf.h"
#include "core/reference/ExactIrradiance.h"
#include "core/scenes/BenchScene.h"
#include "core/scenes/CornellBox.h"

#include "CsvColumn.h"
#include "RunCommand.h"
#include "TempDirTest.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

using namespace ml;
namespace fs = std::filesystem;

namespace {

// --- furnaces ------------------------------------------------------------------

// The radiance everywhere inside test::furnaceBox(albedo, le) for paths of
// depth D (PathTracer.h): Le·(1 + a + … + a^D) = Le·(1 − a^(D+1))/(1 − a).
double furnaceRadiance(double albedo, double le, int depth) {
    return le * (1.0 - std::pow(albedo, depth + 1)) / (1.0 - albedo);
}

// Pooled over the image: the mean of the green channel, the standard error
// of that mean (√Σse²/N, the pixels being independent) and the ratio of the
// squared errors against `truth` to the squared standard errors (≈ 1 when
// the noise estimate is right).
struct Pooled {
    double mean = 0, standardError = 0, calibration = 0;
};
Pooled pool(const ReferenceImage& r, double truth) {
    Pooled p;
    double se2 = 0, err2 = 0;
    const double n = double(r.radiance.pixelCount());
    for (int y = 0; y < r.radiance.height; ++y)
        for (int x = 0; x < r.radiance.width; ++x) {
            const double v = r.radiance.at(x, y).g, s = r.standardError.at(x, y).g;
            p.mean += v / n;
            se2 += s * s;
            err2 += (v - truth) * (v - truth);
        }
    p.standardError = std::sqrt(se2) / n;
    p.calibration = err2 / se2;
    return p;
}

Camera insideCamera(double scale, const Vec3& offset) {
    Camera c;
    c.position = offset + scale * Vec3(0.1, 0.2, -0.3);
    c.target = offset + scale * Vec3(0.6, -0.1, 1.0);
    c.up = Vec3(0, 1, 0);
    c.fovYDegrees = 70;
    return c;
}

}  // namespace

TEST(PathTracer, FurnaceRadianceAtEachDepth) {
    // Depth D sums emission and D scatterings: Le·(1 − a^(D+1))/(1 − a).
    // D = 64 is the limit Le/(1 − a) to within a^65 < 1e-6 of it.
    // 16×16 pixels × 64 samples: the pooled mean is known to ~0.1 %.
    for (double albedo : {0.5, 0.8}) {
        const Scene scene = test::furnaceBox(albedo, 1.5);
        const EmbreeScene rays(scene);
        for (int depth : {1, 2, 3, 64}) {
            PathTracerSettings settings;
            settings.maxDepth = depth;
            settings.seed = uint32_t(depth);
            const PathTracer tracer(rays, settings);
            const ReferenceImage r = tracer.render(insideCamera(1.0, Vec3(0.0)), 16, 16, 64);
            const double truth = furnaceRadiance(albedo, 1.5, depth);
            const Pooled p = pool(r, truth);
            EXPECT_GT(p.standardError, 0.0);
            EXPECT_NEAR(p.mean, truth, 4 * p.standardError) << "albedo " << albedo << ", depth " << depth;
            // The noise file is calibrated: Σ err² / Σ se² is 1 within
            // ~0.1 (256 pixels, each se² an unbiased 1-degree estimate);
            // [0.5, 2] is far outside that, yet fails a noise estimate off
            // by √2 either way.
            EXPECT_GT(p.calibration, 0.5) << "albedo " << albedo << ", depth " << depth;
            EXPECT_LT(p.calibration, 2.0) << "albedo " << albedo << ", depth " << depth;
            EXPECT_EQ(r.paths, 16u * 16u * 64u);
            EXPECT_FALSE(r.cancelled);
        }
    }
}

TEST(PathTracer, FurnaceHoldsAtEveryScaleAndFarFromTheOrigin) {
    // The same box at 1e-3 and 1e5 of its size and 3e5 sizes away from the
    // world's origin: ray offsets relative to the scene keep rays from
    // leaking through walls or hitting the surface they leave; either would
    // darken the furnace by far more than 4 of its standard errors.
    const double albedo = 0.7, le = 2.0;
    const double truth = furnaceRadiance(albedo, le, 32);
    for (auto [scale, offset] : {std::pair{1e-3, Vec3(0.0)}, std::pair{1e5, Vec3(0.0)},
                                 std::pair{1.0, Vec3(3e5, -2e5, 1e5)}, std::pair{1e-3, Vec3(10.0, 0.0, -5.0)}}) {
        const Scene scene = test::furnaceBox(albedo, le, scale, offset);
        const EmbreeScene rays(scene);
        PathTracerSettings settings;
        settings.maxDepth = 32;
        const ReferenceImage r = PathTracer(rays, settings).render(insideCamera(scale, offset), 16, 16, 32);
        const Pooled p = pool(r, truth);
        EXPECT_NEAR(p.mean, truth, 4 * p.standardError) << "scale " << scale << ", offset " << offset.x;
    }
}

TEST(PathTracer, FurnaceIrradianceSplitsIntoDirectAndIndirect) {
    // On a wall of the furnace, light arrives with radiance
    // Le·(1 + … + a^(D−1)) from every direction: direct irradiance π·Le,
    // indirect π·Le·(a + … + a^(D−1)).
    const double albedo = 0.6, le = 1.0;
    const Scene scene = test::furnaceBox(albedo, le);
    const EmbreeScene rays(scene);
    for (int depth : {1, 3}) {
        PathTracerSettings settings;
        settings.maxDepth = depth;
        const PathTracer tracer(rays, settings);
        const IrradianceEstimate e = tracer.irradiance(Vec3(0.2, -1.0, 0.3), Vec3(0, 1, 0), 4096, 7);
        const double indirect = kPi * le * (furnaceRadiance(albedo, 1.0, depth - 1) - 1.0);
        EXPECT_NEAR(e.direct.g, kPi * le, 4 * e.directError.g) << "depth " << depth;
        EXPECT_NEAR(e.indirect.g, indirect, 4 * e.indirectError.g + 1e-12) << "depth " << depth;
        ASSERT_EQ(e.directPerLight.size(), 1u);
        EXPECT_EQ(e.directPerLight[0], e.direct);
    }
}

// --- direct irradiance against the exact reference ------------------------------

namespace {

void expectDirectMatchesExact(const Scene& scene, const std::vector<std::pair<Vec3, Vec3>>& points) {
    const EmbreeScene rays(scene);
    const ExactDirect exact(scene);
    PathTracerSettings direct, deeper;
    direct.maxDepth = 1;
    deeper.maxDepth = 3;
    const PathTracer tracer(rays, direct), tracer3(rays, deeper);
    for (size_t i = 0; i < points.size(); ++i) {
        const auto& [x, n] = points[i];
        const IrradianceEstimate e = tracer.irradiance(x, n, 4096, uint32_t(i));
        Rgb reference(0.0);
        for (size_t l = 0; l < scene.lights.size(); ++l) reference += exact.irradiance(l, x, n);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(e.direct[c], reference[c], 4 * e.directError[c])
                << scene.name << " point " << i << " channel " << c << ": exact " << reference[c];
        EXPECT_EQ(e.indirect, Rgb(0.0));
        Rgb sum(0.0);
        for (const Rgb& l : e.directPerLight) sum += l;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c], e.direct[c], 1e-12 * std::abs(e.direct[c]));
        // The direct part draws the first numbers of each sample's stream:
        // deeper paths leave it bit for bit the same.
        const IrradianceEstimate e3 = tracer3.irradiance(x, n, 4096, uint32_t(i));
        EXPECT_EQ(e3.direct, e.direct);
        EXPECT_GE(e3.indirect.r, 0.0);
    }
}

}  // namespace

TEST(PathTracer, DirectIrradianceMatchesExactOnTheBench) {
    // Floor points lit, in penumbra and under the occluder's centre.
    const std::vector<std::pair<Vec3, Vec3>> points = {
        {Vec3(0, 0, 0), Vec3(0, 1, 0)},          {Vec3(0.5, 0, -0.4), Vec3(0, 1, 0)},
        {Vec3(-0.7, 0, 0.6), Vec3(0, 1, 0)},     {Vec3(1.2, 0, 1.2), Vec3(0, 1, 0)},
        {Vec3(0.05, 0.25, -0.05), Vec3(0, 1, 0)}, {Vec3(0.3, 0, 0.8), Vec3(0.3, 1, -0.2)}};
    expectDirectMatchesExact(makeBenchScene(), points);
}

TEST(PathTracer, DirectIrradianceMatchesExactInTheCornellBox) {
    // Planar surfaces only (floor, back and right walls, block tops), lit
    // and in the blocks' shadows.
    const std::vector<std::pair<Vec3, Vec3>> points = {
        {Vec3(278, 0, 279), Vec3(0, 1, 0)},     {Vec3(100, 0, 400), Vec3(0, 1, 0)},
        {Vec3(450, 0, 100), Vec3(0, 1, 0)},     {Vec3(300, 0, 200), Vec3(0, 1, 0)},
        {Vec3(278, 274, 559.2), Vec3(0, 0, -1)}, {Vec3(0, 300, 280), Vec3(1, 0, 0)},
        {Vec3(180, 165, 170), Vec3(0, 1, 0)},   {Vec3(370, 330, 350), Vec3(0, 1, 0)}};
    expectDirectMatchesExact(makeCornellBox(), points);
}

// --- faces back to back ------------------------------------------------------------

namespace {

// The bench's light (1 × 1 at y = 1, facing down) with its twin facing up on
// the same corners, as exporters write a double-sided panel, in either
// order, over the floor: the sampled panel and its twin are two lights
// (core/Scene.h), the twin emitting away from the floor.
Scene twinPanelScene(bool twinFirst) {
    Mesh panel;
    panel.name = "panel";
    const Vec3 corner(-0.5, 1.0, -0.5);
    if (twinFirst) test::addQuad(panel, 0, corner, test::kZ, test::kX);  // facing up
    test::addQuad(panel, 0, corner, test::kX, test::kZ);                  // facing down
    if (!twinFirst) test::addQuad(panel, 0, corner, test::kZ, test::kX);
    return test::sceneOf("twin panel", test::lightAndGrey(4.0), {panel, test::floorMesh()});
}

}  // namespace

TEST(EmbreeScene, OfFacesBackToBackTheRayMeetsTheOneFacingIt) {
    // Embree returns either of two triangles at the same distance; before
    // this rule, rays from below met the panel's up-facing twin (its back)
    // in one of the two orders. 400 rays each way, through the whole panel.
    for (const bool twinFirst : {false, true}) {
        const Scene scene = twinPanelScene(twinFirst);
        const EmbreeScene rays(scene);
        int wrong = 0;
        for (int i = 0; i < 20; ++i)
            for (int k = 0; k < 20; ++k) {
                const Vec3 x(-0.475 + 0.05 * i, 0.0, -0.475 + 0.05 * k);
                for (const double dir : {1.0, -1.0}) {
                    const Vec3 origin = x + Vec3(0.0, dir > 0 ? 0.5 : 1.5, 0.0);
                    const Vec3 d(0.0, dir, 0.0);
                    RayHit hit;
                    ASSERT_TRUE(rays.intersect(origin, d, 0.0, 10.0, hit)) << i << "," << k;
                    const SurfacePoint s = rays.surface(hit);
                    EXPECT_NEAR(s.position.y, 1.0, 1e-12);
                    wrong += glm::dot(s.geometricNormal, d) >= 0;  // its back faces the ray
                }
            }
        EXPECT_EQ(wrong, 0) << (twinFirst ? "twin first" : "twin second");
    }
}

TEST(PathTracer, ADoubleSidedPanelLightsAsItsFacingSide) {
    // Under the twinned panel the image's estimator (next-event estimation
    // and BSDF-sampled hits, by MIS) must give the floor the direct light of
    // the down-facing panel alone: before the rule above, BSDF-sampled rays
    // met the twin's back in one order and that half of the estimate was
    // lost. Depth 1, a camera looking down at the floor, against the exact
    // irradiance (Kd/π·E per pixel), pooled over the image: 4σ.
    for (const bool twinFirst : {false, true}) {
        const Scene scene = twinPanelScene(twinFirst);
        const EmbreeScene rays(scene);
        const ExactDirect exact(scene);
        Camera camera;
        camera.position = Vec3(0.0, 0.9, 0.0);
        camera.target = Vec3(0.0, 0.0, 0.0);
        camera.up = Vec3(0, 0, 1);
        camera.fovYDegrees = 40;
        PathTracerSettings settings;
        settings.maxDepth = 1;
        const ReferenceImage r = PathTracer(rays, settings).render(camera, 4, 4, 512);
        // Each pixel's exact value at its centre ray's floor point; the
        // irradiance is smooth over a pixel (0.16 of the panel across), so
        // the mean over the image, not each pixel, is compared.
        double traced = 0, expected = 0, se2 = 0;
        const double f = std::tan(glm::radians(camera.fovYDegrees) / 2);
        const Mat4 world = glm::inverse(camera.view());
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 4; ++i) {
                const double ndcX = (i + 0.5) / 2 - 1, ndcY = 1 - (j + 0.5) / 2;
                const Vec3 d = glm::normalize(Vec3(world * Vec4(ndcX * f, ndcY * f, -1.0, 0.0)));
                const Vec3 x = camera.position + (camera.position.y / -d.y) * d;
                Rgb e(0.0);
                for (size_t l = 0; l < scene.lights.size(); ++l) e += exact.irradiance(l, x, test::kY);
                expected += 0.5 / kPi * e.g;
                traced += r.radiance.at(i, j).g;
                se2 += r.standardError.at(i, j).g * r.standardError.at(i, j).g;
            }
        EXPECT_NEAR(traced, expected, 4 * std::sqrt(se2) + 0.01 * expected) << (twinFirst ? "twin first" : "twin second");
    }
}

// --- determinism ----------------------------------------------------------------

TEST(PathTracer, SameSeedGivesTheSameImageWhateverTheThreadCount) {
    const Scene scene = makeCornellBox();
    const EmbreeScene rays(scene);
    const Camera camera = *scene.camera;
    std::vector<ReferenceImage> images;
    for (int threads : {1, 2, 5}) {
        PathTracerSettings s;
        s.maxDepth = 4;
        s.seed = 42;
        s.threads = threads;
        images.push_back(PathTracer(rays, s).render(camera, 40, 24, 4));
    }
    for (size_t k = 1; k < images.size(); ++k) {
        ASSERT_EQ(images[k].radiance.data.size(), images[0].radiance.data.size());
        EXPECT_EQ(std::memcmp(images[k].radiance.data.data(), images[0].radiance.data.data(),
                              images[0].radiance.data.size() * sizeof(float)), 0);
        EXPECT_EQ(std::memcmp(images[k].standardError.data.data(), images[0].standardError.data.data(),
                              images[0].standardError.data.size() * sizeof(float)), 0);
    }
    PathTracerSettings other;
    other.maxDepth = 4;
    other.seed = 43;
    const ReferenceImage different = PathTracer(rays, other).render(camera, 40, 24, 4);
    EXPECT_NE(std::memcmp(different.radiance.data.data(), images[0].radiance.data.data(),
                          images[0].radiance.data.size() * sizeof(float)), 0);
}

TEST(PathTracer, PassesGiveTheSameImageAndAStopKeepsWholePasses) {
    const Scene scene = makeCornellBox();
    const EmbreeScene rays(scene);
    const Camera camera = *scene.camera;
    PathTracerSettings s;
    s.maxDepth = 3;
    const PathTracer tracer(rays, s);
    const ReferenceImage whole = tracer.render(camera, 20, 12, 10);
    EXPECT_EQ(whole.samplesPerPixel, 10);
    for (int pass : {2, 4, 6}) {  // 4: a short last pass
        RenderControl control;
        control.passSamples = pass;
        const ReferenceImage r = tracer.render(camera, 20, 12, 10, control);
        EXPECT_EQ(r.samplesPerPixel, 10);
        EXPECT_FALSE(r.cancelled);
        EXPECT_EQ(r.paths, 20u * 12u * 10u);
        EXPECT_EQ(std::memcmp(r.radiance.data.data(), whole.radiance.data.data(),
                              whole.radiance.data.size() * sizeof(float)), 0) << "pass " << pass;
        EXPECT_EQ(std::memcmp(r.standardError.data.data(), whole.standardError.data.data(),
                              whole.standardError.data.size() * sizeof(float)), 0) << "pass " << pass;
    }
    // Stopped after the first pass (the stop is set by the progress call
    // that ends it): that pass is kept whole, the next one dropped.
    std::atomic<bool> stop{false};
    RenderControl control;
    control.passSamples = 2;
    control.stop = &stop;
    control.progress = [&](uint64_t done, uint64_t) {
        if (done >= 20u * 12u * 2u) stop = true;
    };
    const ReferenceImage partial = tracer.render(camera, 20, 12, 10, control);
    EXPECT_TRUE(partial.cancelled);
    EXPECT_EQ(partial.samplesPerPixel % 2, 0);
    EXPECT_GE(partial.samplesPerPixel, 2);
    EXPECT_LT(partial.samplesPerPixel, 10);
    EXPECT_EQ(partial.paths, 20u * 12u * uint64_t(partial.samplesPerPixel));
    // Stopped before anything: no sample, a black image.
    stop = true;
    control.progress = {};
    const ReferenceImage none = tracer.render(camera, 20, 12, 10, control);
    EXPECT_EQ(none.samplesPerPixel, 0);
    EXPECT_EQ(none.radiance.at(10, 6), Rgb(0.0));
    control.passSamples = 3;
    EXPECT_THROW(tracer.render(camera, 20, 12, 10, control), InputError);
}

TEST(PathTracer, PixelsFollowTheCompositorsProjection) {
    // The compositor (viewer/Compositor.cpp) maps a point through
    // Camera::view() (glm::lookAtRH) and x_ndc = f/aspect·x/(−z),
    // y_ndc = f·y/(−z), f = 1/tan(fov/2), its GL rows flipped so that row 0
    // is the top. Eight emitting unit squares tile exactly what a 4×2 image
    // with a 90° field of view sees on the plane z = 1, one square per
    // pixel; each pixel must hold exactly its square's Ke (every jittered
    // sample of the pixel lands on that square; depth 1, nothing reflects).
    Scene scene;
    scene.name = "tiles";
    Mesh mesh;
    mesh.name = "tiles";
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 4; ++i) {
            Material m;
            m.name = concat("tile", i, j);
            m.kd = Rgb(0.0);
            m.ke = Rgb(1.0 + i + 4 * j, 0.5, 0.25);
            scene.materials.push_back(m);
            const double x0 = -2.0 + i, y0 = -1.0 + j;
            std::array<Vec3, 4> q{Vec3(x0, y0, 1), Vec3(x0 + 1, y0, 1), Vec3(x0 + 1, y0 + 1, 1), Vec3(x0, y0 + 1, 1)};
            if (glm::dot(glm::cross(q[1] - q[0], q[2] - q[0]), -q[0]) < 0) std::swap(q[1], q[3]);  // face the camera
            const uint32_t base = uint32_t(mesh.positions.size());
            mesh.positions.insert(mesh.positions.end(), q.begin(), q.end());
            mesh.triangles.push_back({base, base + 1, base + 2});
            mesh.triangles.push_back({base, base + 2, base + 3});
            mesh.materials.insert(mesh.materials.end(), 2, uint32_t(scene.materials.size() - 1));
            mesh.sourceLines.insert(mesh.sourceLines.end(), 2, 0);
        }
    computeShadingNormals(mesh, 0.0);
    scene.meshes.push_back(mesh);
    scene.finalize();
    Camera camera;
    camera.position = Vec3(0.0);
    camera.target = Vec3(0, 0, 1);
    camera.up = Vec3(0, 1, 0);
    camera.fovYDegrees = 90;
    const EmbreeScene rays(scene);
    PathTracerSettings settings;
    settings.maxDepth = 1;
    const ReferenceImage r = PathTracer(rays, settings).render(camera, 4, 2, 16);
    const double f = 1.0 / std::tan(glm::radians(camera.fovYDegrees) / 2), aspect = 2.0;
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 4; ++i) {
            const Vec4 v = camera.view() * Vec4(-1.5 + i, -0.5 + j, 1.0, 1.0);
            const double ndcX = f / aspect * v.x / -v.z, ndcY = f * v.y / -v.z;
            const int px = int(std::floor((ndcX + 1) / 2 * 4)), py = int(std::floor((1 - ndcY) / 2 * 2));
            ASSERT_TRUE(px >= 0 && px < 4 && py >= 0 && py < 2);
            EXPECT_EQ(r.radiance.at(px, py), Rgb(1.0 + i + 4 * j, 0.5, 0.25)) << "tile " << i << "," << j;
            EXPECT_EQ(r.standardError.at(px, py), Rgb(0.0));
        }
}

TEST(PathTracer, BadSettingsAreInputErrors) {
    const Scene scene = makeCornellBox();
    const EmbreeScene rays(scene);
    PathTracerSettings s;
    s.maxDepth = 0;
    EXPECT_THROW(PathTracer(rays, s), InputError);
    const PathTracer tracer(rays, PathTracerSettings{});
    EXPECT_THROW(tracer.render(*scene.camera, 8, 8, 1), InputError);   // no halves
    EXPECT_THROW(tracer.render(*scene.camera, 0, 8, 4), InputError);
    EXPECT_THROW(tracer.irradiance(Vec3(0.0), Vec3(0.0), 16, 0), InputError);
}

// --- the BSDF -------------------------------------------------------------------

TEST(PhongBsdf, ImportanceSamplingIsUnbiasedAndThePdfIntegratesToAtMostOne) {
    // Directional albedo ∫ f·cosθ dω two ways: the BSDF's own sampling
    // (f·cosθ/pdf) and uniform hemisphere sampling (2π·f·cosθ). Both are
    // unbiased estimates of the same integral; they must agree within 4
    // standard errors of their difference. At normal incidence the glossy
    // lobe's albedo is exactly Ks (its normalisation), the diffuse one's Kd.
    // ∫ pdf dω over the upper hemisphere is the chance a draw lands above
    // the surface: ≤ 1, and 1 at normal incidence without glossy loss.
    std::mt19937_64 rng(2024);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const Vec3 n(0, 0, 1);
    Material m;
    m.kd = Rgb(0.3, 0.2, 0.1);
    m.ks = Rgb(0.5);
    m.ns = 20;
    const PhongBsdf bsdf(m, n);
    for (double thetaDeg : {0.0, 60.0}) {
        const double th = glm::radians(thetaDeg);
        const Vec3 wo(std::sin(th), 0, std::cos(th));
        constexpr int kN = 200000;
        double sumI = 0, sumI2 = 0, sumU = 0, sumU2 = 0, sumPdf = 0, sumPdf2 = 0;
        for (int k = 0; k < kN; ++k) {
            Vec3 wi;
            double vi = 0;
            if (bsdf.sample(wo, u(rng), u(rng), u(rng), wi)) vi = bsdf.eval(wo, wi).g * wi.z / bsdf.pdf(wo, wi);
            sumI += vi;
            sumI2 += vi * vi;
            const double z = u(rng), phi = 2 * kPi * u(rng), r = std::sqrt(1 - z * z);
            const Vec3 w(r * std::cos(phi), r * std::sin(phi), z);
            const double vu = 2 * kPi * bsdf.eval(wo, w).g * z, vp = 2 * kPi * bsdf.pdf(wo, w);
            sumU += vu;
            sumU2 += vu * vu;
            sumPdf += vp;
            sumPdf2 += vp * vp;
        }
        auto se = [](double s, double s2) { return std::sqrt((s2 / kN - (s / kN) * (s / kN)) / kN); };
        const double importance = sumI / kN, uniform = sumU / kN, pdfMass = sumPdf / kN;
        const double tolerance = 4 * std::hypot(se(sumI, sumI2), se(sumU, sumU2));
        EXPECT_NEAR(importance, uniform, tolerance) << "at " << thetaDeg << "°";
        EXPECT_LE(pdfMass, 1.0 + 4 * se(sumPdf, sumPdf2)) << "at " << thetaDeg << "°";
        if (thetaDeg == 0.0) {
            EXPECT_NEAR(importance, m.kd.g + m.ks.g, tolerance);
            EXPECT_NEAR(pdfMass, 1.0, 4 * se(sumPdf, sumPdf2));
        }
    }
    // Below the surface: nothing.
    EXPECT_EQ(bsdf.eval(Vec3(0, 0, 1), Vec3(0, 0.6, -0.8)), Rgb(0.0));
    EXPECT_EQ(bsdf.pdf(Vec3(0, 0, 1), Vec3(0, 0.6, -0.8)), 0.0);
}

// --- the commands ---------------------------------------------------------------

using Commands = test::TempDirTest;
using test::CommandResult;
using test::csvColumn;
using test::runMeshlight;

TEST_F(Commands, ReferenceRejectsBadOptionsWithoutWritingAnything) {
    const std::string out = " --out " + path("ref.exr");
    for (const std::string& bad : {"reference cornell --spp 0" + out, "reference cornell --spp 1" + out,
                                   "reference cornell --spp 4 --frobnicate 2" + out,
                                   "reference cornell --spp 4 --max-depth 0" + out,
                                   "reference cornell --spp 4 --pass 3" + out,
                                   "reference cornell --spp 4 --out " + path("ref.png"),
                                   "reference cornell" + out, "reference nowhere.obj --spp 4" + out}) {
        const CommandResult r = runMeshlight(bad);
        EXPECT_EQ(r.status, 2) << bad << "\n" << r.output;
        EXPECT_NE(r.output.find("error:"), std::string::npos) << r.output;
        EXPECT_EQ(files(), 0u) << bad;
    }
}

TEST_F(Commands, ReferenceWritesTheImageAndItsNoise) {
    const CommandResult r = runMeshlight(
        "reference bench --width 24 --height 16 --spp 4 --max-depth 2 --threads 2 --out " + path("ref.exr"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("paths/s"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("mean relative standard error"), std::string::npos) << r.output;
    const ImageRgb image = readImageLinear(path("ref.exr"));
    const ImageRgb noise = readImageLinear(path("ref.noise.exr"));
    EXPECT_EQ(image.width, 24);
    EXPECT_EQ(image.height, 16);
    EXPECT_EQ(noise.width, 24);
    EXPECT_EQ(files(), 2u);  // no temporary left behind
}

TEST_F(Commands, ProbePathAndRaytraceAgreeWithExact) {
    write("points.csv", "x,y,z,nx,ny,nz\n0,0,0,0,1,0\n1.2,0,1.2,0,1,0\n");
    const std::string common = "probe bench --points " + path("points.csv");
    // Direct light only: the columns compared are direct light (the path
    // tracer at depth 1); the exact method's indirect caches, refined with
    // the exact sampler, took 28 of this test's 34 s.
    ASSERT_EQ(runMeshlight(common + " --method exact --direct-only --out " + path("exact.csv")).status, 0);
    const CommandResult p = runMeshlight(common + " --method path --spp 4096 --max-depth 1 --out " + path("path.csv"));
    ASSERT_EQ(p.status, 0) << p.output;
    const CommandResult t = runMeshlight(common + " --method raytrace --out " + path("rt.csv"));
    ASSERT_EQ(t.status, 0) << t.output;
    for (int row = 0; row < 2; ++row) {
        const double e = csvColumn(path("exact.csv"), row, "E_g");
        ASSERT_GT(e, 0);
        EXPECT_NEAR(csvColumn(path("path.csv"), row, "E_g"), e, 4 * csvColumn(path("path.csv"), row, "E_se_g"));
        EXPECT_EQ(csvColumn(path("path.csv"), row, "E_indirect_g"), 0.0);
        // (1.2, 1.2) sees the whole light: the control variate is Lambert's
        // value (1e-9: summation order); (0, 0) is in penumbra, within the
        // jittered sampler's one-pass error (well under 1 % there).
        EXPECT_NEAR(csvColumn(path("rt.csv"), row, "E_g"), e, row == 1 ? 1e-9 * e : 0.01 * e);
        // lux: RADIANCE's photometry of all the light computed.
        auto lux = [&](const std::string& file, const std::string& prefix) {
            return 179 * (0.265 * csvColumn(file, row, prefix + "_r") + 0.670 * csvColumn(file, row, prefix + "_g") +
                          0.065 * csvColumn(file, row, prefix + "_b"));
        };
        EXPECT_NEAR(csvColumn(path("rt.csv"), row, "lux"), lux(path("rt.csv"), "E"), 1e-7 * lux(path("rt.csv"), "E"));
        EXPECT_NEAR(csvColumn(path("path.csv"), row, "lux"),
                    lux(path("path.csv"), "E") + lux(path("path.csv"), "E_indirect"), 1e-7 * e * 179);
        EXPECT_EQ(csvColumn(path("path.csv"), row, "lux_indirect"), 0.0);
    }
    // Options of other methods are refused, not ignored.
    const CommandResult bad = runMeshlight(common + " --method path --bits 4 --out " + path("bad.csv"));
    EXPECT_EQ(bad.status, 2) << bad.output;
    const CommandResult bad2 = runMeshlight(common + " --spp 64 --out " + path("bad.csv"));
    EXPECT_EQ(bad2.status, 2) << bad2.output;
    EXPECT_FALSE(fs::exists(path("bad.csv")));
}
