// Emitters' outlines (viewer/compositor/EmitterOutlines.h): a pixel an
// emitter covers in part is rebuilt from the surface-only passes' coverage
// and emission and the full passes' other sub-pixels. First the rebuild on
// hand-made sub-pixels (exact arithmetic), then the compositor on a light
// seen from above, against the pixels' exact coverage.
#include "TestSamplers.h"
#include "TestScenes.h"
#include "cache/IrradianceCache.h"
#include "viewer/compositor/Compositor.h"
#include "viewer/compositor/EmitterOutlines.h"

#include "GlTestContext.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

using namespace ml;

namespace {

// One 2×2-sub-pixel pass: a = what each sees (0 nothing, 1 a surface,
// 2 + l light l), GL rows from the bottom.
EmitterOutlines::SubPixels seen(const std::vector<float>& a) {
    EmitterOutlines::SubPixels p;
    for (float v : a) p.surface.insert(p.surface.end(), {0.5f, 0.5f, 0.5f, v});
    return p;
}
std::vector<float> grey(const std::vector<float>& v) {
    std::vector<float> rgba;
    for (float x : v) rgba.insert(rgba.end(), {x, x, x, 1.0f});
    return rgba;
}

}  // namespace

TEST(EmitterOutlines, RebuildsAPixelFromCoverageEmissionAndTheRest) {
    // One pixel, 2×2 sub-pixels, light 0 of radiance 10. The full pass: two
    // sub-pixels on the light (radiance 10.5: 0.5 besides the emission),
    // two off it (1 and 3). Surface passes: the light covers 3 sub-pixels in
    // the odd one, 1 in the even one. c = 4/8, E = 10·c, R = 0.5, B = 2:
    // 5 + 0.25 + 1 = 6.25. Each half alone: c = 3/4 gives 8.375, c = 1/4
    // gives 4.125, so the spread is 2.125.
    // Surface passes added before and cleared (clearSurfacePasses) are
    // forgotten: the same pixel, bit for bit.
    for (bool cleared : {false, true}) {
        EmitterOutlines o(1, 1, 2, {Rgb(10.0)});
        o.addFullPass(grey({10.5f, 1.0f, 10.5f, 3.0f}), seen({2, 1, 2, 1}));
        if (cleared) {
            o.addSurfacePass(seen({0, 0, 0, 0}), true);
            o.addSurfacePass(seen({2, 2, 2, 2}), false);
            o.clearSurfacePasses();
        }
        o.addSurfacePass(seen({2, 2, 2, 1}), true);
        o.addSurfacePass(seen({2, 1, 0, 1}), false);
        ImageRgb image(1, 1, Rgb(99.0)), spread(1, 1);
        EXPECT_EQ(o.apply(image, &spread), 1u);
        EXPECT_NEAR(image.at(0, 0).r, 6.25, 1e-12);
        EXPECT_NEAR(spread.at(0, 0).g, 2.125, 1e-12);
    }
}

TEST(EmitterOutlines, PixelsThatSeeNoEmitterKeepTheFullPassesMean) {
    // Two pixels side by side; only the right one has light 1 in it.
    EmitterOutlines o(2, 1, 2, {Rgb(5.0), Rgb(8.0)});
    // Sub-pixels, bottom row first: x = 0..3 across both pixels.
    o.addFullPass(grey({1, 1, 8, 1, 1, 1, 1, 1}), seen({1, 1, 3, 1, 1, 1, 1, 1}));
    o.addSurfacePass(seen({1, 1, 3, 3, 1, 1, 1, 1}), false);
    ImageRgb image(2, 1, Rgb(7.0));
    EXPECT_EQ(o.apply(image), 1u);
    EXPECT_EQ(image.at(0, 0).r, 7.0f);
    // c = 2/4, E = 8·c, R = 0, B = 1.
    EXPECT_NEAR(image.at(1, 0).r, 4.5, 1e-12);
}

TEST(EmitterOutlines, PassesWithinABudgetAreAllOrTheMostPowerOfTwoThatFits) {
    EXPECT_EQ(outlinePassesWithin(16, 0.01, 0.5), 16);  // 0.16 s: all
    EXPECT_EQ(outlinePassesWithin(16, 0.16, 0.52), 2);  // the back rooms' at 5 s: 0.32 s
    EXPECT_EQ(outlinePassesWithin(16, 0.1, 0.8), 8);
    EXPECT_EQ(outlinePassesWithin(16, 0.75, 0.5), 1);  // at least one
    EXPECT_EQ(outlinePassesWithin(12, 0.1, 1.25), 12);  // all fit: any count
    EXPECT_EQ(outlinePassesWithin(12, 0.1, 1.0), 8);   // else a power of two
}

TEST(EmitterOutlines, APixelTheFullPassesSawOnlyOnTheLightTakesItsNeighboursRest) {
    // The left pixel is all light in the full pass; the surface pass finds a
    // quarter of it off the light: its B comes from the 3×3 around it (here
    // the right pixel's sub-pixels off the light, radiance 2).
    EmitterOutlines o(2, 1, 2, {Rgb(4.0)});
    o.addFullPass(grey({4, 4, 2, 2, 4, 4, 2, 2}), seen({2, 2, 1, 1, 2, 2, 1, 1}));
    o.addSurfacePass(seen({2, 2, 1, 1, 1, 2, 1, 1}), false);
    ImageRgb image(2, 1, Rgb(0.0));
    EXPECT_EQ(o.apply(image), 1u);
    EXPECT_NEAR(image.at(0, 0).r, 0.75 * 4 + 0.25 * 2, 1e-12);
}

namespace {

// A grey floor (y = 0, 8 × 8) with a light lying on it, facing up: the
// rectangle [x0, x1] × [z0, z1] at y = 0.001, radiance kLe, no reflectance.
constexpr double kLe = 50.0;
constexpr double kX0 = -0.3137, kX1 = 0.2291, kZ0 = -0.1719, kZ1 = 0.3493;

// Facing up (+y): z × x.
Mesh upQuad(const std::string& name, double x0, double x1, double z0, double z1, double y, uint32_t material) {
    return test::quadMesh(name, material, Vec3(x0, y, z0), Vec3(0, 0, z1 - z0), Vec3(x1 - x0, 0, 0));
}

Scene lightOnFloor() {
    return test::sceneOf("light on a floor",
                         {Material::diffuse("grey", Rgb(0.5)), Material::diffuse("light", Rgb(0.0), Rgb(kLe))},
                         {upQuad("floor", -4, 4, -4, 4, 0, 0), upQuad("light", kX0, kX1, kZ0, kZ1, 0.001, 1)});
}

// `scene`'s cache at base edges of `edgeFraction` of its diagonal, every
// vertex sampled once from a smooth field that differs per channel.
std::vector<IrradianceMeshCopy> smoothCache(const Scene& scene, double edgeFraction) {
    CacheSettings cs;
    cs.maxEdgeFraction = edgeFraction;
    IrradianceCache cache(scene, cs);
    test::sampleEveryVertex(
        cache, [](size_t, const Vec3& x, const Vec3&, uint32_t) { return Rgb(2.0 + x.x, 1.0, 0.5 + x.z * x.z); }, 1,
        1);
    return cache.copyMeshes();
}

// A cache of E = 2 at every vertex, base edges 1/8 of the scene.
std::vector<IrradianceMeshCopy> uniformCache(const Scene& scene) {
    CacheSettings cs;
    cs.maxEdgeFraction = 1.0 / 8.0;
    IrradianceCache cache(scene, cs);
    test::sampleEveryVertex(cache, [](size_t, const Vec3&, const Vec3&, uint32_t) { return Rgb(2.0); }, 1, 1);
    return cache.copyMeshes();
}

// A camera at `position` looking at the light's centre, z down the image.
Camera towardsTheLight(const Vec3& position, double fovYDegrees) {
    Camera camera;
    camera.position = position;
    camera.target = Vec3(0, 0.001, 0);
    camera.up = Vec3(0, 0, -1);
    camera.fovYDegrees = fovYDegrees;
    return camera;
}
// Looking straight down from 1.001 above the light (90° view: the plane
// y = 0.001 spans [−1, 1]², x right, z down).
Camera straightDown() { return towardsTheLight(Vec3(0, 1.001, 0), 90); }
// The light and the floor around it seen from above and to the side.
Camera obliqueView() { return towardsTheLight(Vec3(0.3, 1.5, 0.2), 70); }

// A width × height composite of 4×4 sub-pixels, 2 sub-pixel passes and 8
// outline passes: both halves of the passes, and the outlines' own.
CompositorSettings twoPassesWithOutlines(int width, int height) {
    CompositorSettings s;
    s.width = width, s.height = height;
    s.supersample = 4;
    s.passes = 2;
    s.outlinePasses = 8;
    return s;
}

// Of [a0, a1] the share inside [b0, b1].
double overlap(double a0, double a1, double b0, double b1) {
    return std::max(0.0, std::min(a1, b1) - std::max(a0, b0)) / (a1 - a0);
}

}  // namespace

TEST(EmitterOutlines, CompositeGivesEachPixelItsExactShareOfTheLight) {
    // Looking straight down from 1.001 above the light (90° view: the plane
    // y = 0.001 spans [−1, 1]² over 64×64 pixels, x right, z down). The
    // cache holds E = 2 everywhere, so off the light a pixel is 0.5/π × 2
    // and each pixel is cov·kLe + (1 − cov)·1/π, cov its exact share of the
    // rectangle. One full pass of 4×4 sub-pixels gets cov in steps of 1/16
    // (4 levels along each edge): up to ~1/8 of kLe off on the outline. With
    // 64 surface passes in a rook pattern the edges get 256 levels each way:
    // an edge's coverage within 1/256 plus the grid's own sampling, so the
    // worst outline pixel is asked within 1% of kLe; pixels off the outline
    // must equal the plain composite's exactly.
    const Scene scene = lightOnFloor();
    const std::vector<IrradianceMeshCopy> meshes = uniformCache(scene);
    const Camera camera = straightDown();
    const int size = 64;
    Compositor compositor(test::glContext(), scene);
    CompositorSettings s;
    s.width = s.height = size;
    s.supersample = 4;
    const ImageRgb plain = compositor.render(camera, meshes, s);
    s.outlinePasses = 64;
    const ImageRgb outlined = compositor.render(camera, meshes, s);
    double worstPlain = 0, worstOutlined = 0;
    int outline = 0;
    for (int py = 0; py < size; ++py)
        for (int px = 0; px < size; ++px) {
            const double cov = overlap(-1 + 2.0 * px / size, -1 + 2.0 * (px + 1) / size, kX0, kX1) *
                               overlap(-1 + 2.0 * py / size, -1 + 2.0 * (py + 1) / size, kZ0, kZ1);
            const double expected = cov * kLe + (1 - cov) / kPi;
            if (cov == 0 || cov == 1) {
                EXPECT_EQ(outlined.at(px, py).g, plain.at(px, py).g) << "pixel " << px << "," << py;
                EXPECT_NEAR(outlined.at(px, py).g, expected, 1e-4 * kLe) << "pixel " << px << "," << py;
                continue;
            }
            ++outline;
            worstPlain = std::max(worstPlain, std::abs(plain.at(px, py).g - expected) / kLe);
            worstOutlined = std::max(worstOutlined, std::abs(outlined.at(px, py).g - expected) / kLe);
        }
    std::printf("outline pixels %d, worst error of kLe: plain %.4f, outlined %.4f\n", outline, worstPlain,
                worstOutlined);
    EXPECT_GT(outline, 60);
    EXPECT_LT(worstOutlined, 0.01);
    // What the outline passes are for: one full pass is several times off.
    EXPECT_GT(worstPlain, 4 * worstOutlined);
}

// CompositorSettings::outlineSeconds, on the light seen from above as in
// the test before (E = 2 on the floor: a pixel is c·kLe + (1 − c)/π, c
// the coverage its sub-pixels find). A budget all 64 passes fit in changes
// nothing: the timed first pass is the pattern's own, bit for bit. One
// that fits none leaves the timed pass alone: one grid of 4×4 sub-pixels,
// so every outline pixel's c is a whole number of sixteenths (tolerance
// 1e-3 of one: float rounding), where the 64 passes' is not, in most.
TEST(EmitterOutlines, TimedOutlinePassesKeepThePatternOrOnePass) {
    const Scene scene = lightOnFloor();
    const std::vector<IrradianceMeshCopy> meshes = uniformCache(scene);
    const Camera camera = straightDown();
    Compositor compositor(test::glContext(), scene);
    CompositorSettings s;
    s.width = s.height = 64;
    s.supersample = 4;
    s.outlinePasses = 64;
    const ImageRgb all = compositor.render(camera, meshes, s);
    s.outlineSeconds = 1e9;
    const ImageRgb fitting = compositor.render(camera, meshes, s);
    ASSERT_EQ(fitting.data.size(), all.data.size());
    for (size_t i = 0; i < all.data.size(); ++i) ASSERT_EQ(fitting.data[i], all.data[i]) << "value " << i;
    s.outlineSeconds = 1e-12;
    const ImageRgb one = compositor.render(camera, meshes, s);
    const auto offSixteenths = [](const ImageRgb& im, int px, int py) {
        const double c = 16.0 * (im.at(px, py).g - 1 / kPi) / (kLe - 1 / kPi);
        return std::abs(c - std::round(c));
    };
    int outline = 0, finer = 0;
    for (int py = 0; py < 64; ++py)
        for (int px = 0; px < 64; ++px) {
            const double c = (all.at(px, py).g - 1 / kPi) / (kLe - 1 / kPi);
            if (c < 1e-3 || c > 1 - 1e-3) continue;
            ++outline;
            EXPECT_LT(offSixteenths(one, px, py), 1e-3) << "pixel " << px << "," << py;
            finer += offSixteenths(all, px, py) > 0.05;
        }
    EXPECT_GT(outline, 60);
    EXPECT_GT(finer, outline / 2);
}

TEST(EmitterOutlines, PartsCompositedTogetherEqualEachCompositedAlone) {
    // render's EXR layers composite every part of one view together, the
    // outline passes drawn once per emission (Compositor::composite of
    // several parts): each image must be bit for bit what compositing its
    // part alone gives. The light alone (its emission), its direct light
    // without emission, everything, and nothing: two emissions, each met
    // twice, so both the drawn and the taken passes are checked.
    const Scene scene = lightOnFloor();
    const std::vector<IrradianceMeshCopy> smooth = smoothCache(scene, 1.0 / 8.0);
    const Camera camera = obliqueView();
    Compositor compositor(test::glContext(), scene);
    const CompositorSettings s = twoPassesWithOutlines(48, 40);
    const GpuCacheMeshes meshes = compositor.upload(smooth, {});
    const size_t lights = scene.lights.size();
    ASSERT_EQ(1u, lights);
    LightWeights emission = LightWeights::unit(lights), direct = LightWeights::unit(lights),
                 nothing = LightWeights::unit(lights);
    emission.light.assign(lights, Rgb(0.0));
    emission.emission.assign(lights, Rgb(1.0));  // empty: as the lights' weights
    emission.indirect = Rgb(0.0);
    direct.emission.assign(lights, Rgb(0.0));
    nothing.light.assign(lights, Rgb(0.0));
    nothing.emission.assign(lights, Rgb(0.0));
    const std::vector<LightWeights> parts = {emission, direct, LightWeights::unit(lights), nothing};
    const std::vector<ImageRgb> together = compositor.composite(camera, meshes, parts, s);
    ASSERT_EQ(parts.size(), together.size());
    for (size_t p = 0; p < parts.size(); ++p) {
        const ImageRgb alone = compositor.composite(camera, meshes, parts[p], s);
        EXPECT_TRUE(alone.data == together[p].data) << "part " << p;
    }
    // The parts differ, so the comparison could fail: the light is seen.
    EXPECT_FALSE(together[0].data == together[1].data);
    EXPECT_FALSE(together[0].data == together[3].data);
}

TEST(EmitterOutlines, ALightsPartIsCompositedOnlyOverItsMeshBitForBitTheSame) {
    // Where lights share a mesh, a light's own mesh keeps only some faces,
    // and Compositor::composite of several parts composites that light's
    // part only over its mesh's screen bounds (two pixels wider), read back
    // as zeros outside. Its own mesh here: the floor's triangles within
    // 0.15 of a point on the light's right edge, so that the clip holds part
    // of the light's outline; the shared mesh: the whole floor. Each part
    // must be bit for bit what compositing it alone (the whole image) gives,
    // its share of the image well under 1 (so that the clip is what is
    // checked), and the image must be black outside that share, as alone.
    const Scene scene = lightOnFloor();
    const std::vector<IrradianceMeshCopy> smooth = smoothCache(scene, 1.0 / 128.0);
    const IrradianceMeshCopy shared = smooth.at(0);
    IrradianceMeshCopy own = shared;
    own.triangles.clear();
    const Vec3 centre(kX1, 0, 0.1);
    for (const glm::uvec3& t : shared.triangles) {
        const Vec3 c = (shared.positions[t.x] + shared.positions[t.y] + shared.positions[t.z]) / 3.0;
        if (length(c - centre) < 0.15) own.triangles.push_back(t);
    }
    for (Rgb& e : own.irradiance) e = e * 3.0;
    ASSERT_GT(own.triangles.size(), 8u);
    ASSERT_LT(own.triangles.size(), shared.triangles.size() / 4);
    const Camera camera = obliqueView();
    Compositor compositor(test::glContext(), scene);
    const CompositorSettings s = twoPassesWithOutlines(56, 40);
    const GpuCacheMeshes meshes = compositor.upload({own, shared}, {});
    const size_t lights = scene.lights.size();
    ASSERT_EQ(1u, lights);
    LightWeights alone = LightWeights::unit(lights), rest = LightWeights::unit(lights);
    alone.emission.assign(lights, Rgb(0.0));
    alone.shared = Rgb(0.0);
    alone.indirect = Rgb(0.0);
    rest.light.assign(lights, Rgb(0.0));
    rest.emission.assign(lights, Rgb(0.0));
    // The light alone first, so that its outlines are drawn over its clip
    // and must not be taken by the part of the same emission after it.
    const std::vector<LightWeights> parts = {alone, rest, LightWeights::unit(lights)};
    const std::vector<double> shares = compositor.partShares(camera, meshes, parts, s);
    ASSERT_EQ(shares.size(), parts.size());
    EXPECT_LT(shares[0], 0.2);  // 0.054
    EXPECT_EQ(shares[1], 1.0);
    EXPECT_EQ(shares[2], 1.0);
    const std::vector<ImageRgb> together = compositor.composite(camera, meshes, parts, s);
    ASSERT_EQ(parts.size(), together.size());
    for (size_t p = 0; p < parts.size(); ++p) {
        const ImageRgb image = compositor.composite(camera, meshes, parts[p], s);
        EXPECT_TRUE(image.data == together[p].data) << "part " << p;
    }
    size_t lit = 0, black = 0;
    for (float v : together[0].data) (v > 0 ? lit : black) += 1;
    EXPECT_GT(lit, 0u);
    EXPECT_GT(black, together[0].data.size() / 2) << "the light's part covers part of the image";
}
