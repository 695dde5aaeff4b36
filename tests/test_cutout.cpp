// Cut-outs (issue 13: glTF alphaMode MASK, MTL map_d): a face is absent
// where its alpha texture is below the cut-off, for shadows and for shading.
// The scene: a 0.5 × 0.5 light 2 above a floor, a 2 × 2 "leaf" at height 1
// between them whose alpha is an 8 × 8 checker (nearest texels: sharp
// 0.25-wide squares, half of them open). Its shadow is exact: ExactDirect
// on the scene with the leaf replaced by its 32 opaque squares. Every
// sampler (ray-traced, raster, path tracer) must agree with it; the
// composited image must show the floor through the holes and the leaf
// elsewhere.
#include "TestSamplers.h"
#include "cache/IrradianceCache.h"
#include "core/Random.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "core/reference/ExactIrradiance.h"
#include "core/reference/Lambert.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/direct/RayTracedLightSampler.h"
#include "viewer/compositor/Compositor.h"

#include "GlTestContext.h"
#include "MeanAndError.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>

using namespace ml;

namespace {

const Vec3 kUp(0, 1, 0);
constexpr int kCells = 8;  // checker squares along each side of the leaf

// kCells × kCells texels, RGBA, alpha 255 where (i + j) is even, else 0.
std::shared_ptr<Texture> checker() {
    auto t = std::make_shared<Texture>();
    t->name = "checker alpha";
    t->width = t->height = kCells;
    for (int j = 0; j < kCells; ++j)
        for (int i = 0; i < kCells; ++i)
            t->rgba.insert(t->rgba.end(), {40, 200, 40, (i + j) % 2 == 0 ? (unsigned char)255 : (unsigned char)0});
    t->hasAlpha = true;
    t->minAlpha = 0;
    t->nearest = true;
    t->wrapS = t->wrapT = TextureWrap::ClampToEdge;
    return t;
}

Mesh quad(const std::string& name, double x0, double x1, double z0, double z1, double y, bool down, uint32_t material) {
    Mesh m;
    m.name = name;
    m.positions = {{x0, y, z0}, {x0, y, z1}, {x1, y, z1}, {x1, y, z0}};
    m.normals.assign(4, down ? -kUp : kUp);
    m.triangles = down ? std::vector<glm::uvec3>{{0, 2, 1}, {0, 3, 2}} : std::vector<glm::uvec3>{{0, 1, 2}, {0, 2, 3}};
    m.materials = {material, material};
    m.sourceLines = {0, 0};
    return m;
}

// Materials: 0 floor (grey), 1 light, 2 leaf (green; the cut-out when `masked`).
Scene baseScene() {
    Scene s;
    s.name = "cut-out leaf";
    s.materials = {Material::diffuse("floor", Rgb(0.6)), Material::diffuse("light", Rgb(0.0), Rgb(10.0, 9.0, 8.0)),
                   Material::diffuse("leaf", Rgb(0.1, 0.7, 0.1))};
    s.meshes = {quad("floor", -4, 4, -4, 4, 0, false, 0), quad("light", -0.25, 0.25, -0.25, 0.25, 2, true, 1)};
    return s;
}

// The leaf as one quad with the checker as its cut-out, uv = ((x + 1) / 2, (z + 1) / 2).
Scene maskedScene() {
    Scene s = baseScene();
    Material& leaf = s.materials[2];
    leaf.alphaMap.image = checker();
    leaf.alphaCutoff = 0.5;
    Mesh m = quad("leaf", -1, 1, -1, 1, 1, false, 2);
    for (const Vec3& p : m.positions) m.texcoords.push_back(Vec2((p.x + 1) / 2, (p.z + 1) / 2));
    s.meshes.push_back(m);
    s.finalize();
    return s;
}

// The leaf as its opaque squares only: the exact geometry the mask leaves.
Scene squaresScene() {
    Scene s = baseScene();
    const double w = 2.0 / kCells;
    for (int j = 0; j < kCells; ++j)
        for (int i = 0; i < kCells; ++i)
            if ((i + j) % 2 == 0)
                s.meshes.push_back(quad("square", -1 + i * w, -1 + (i + 1) * w, -1 + j * w, -1 + (j + 1) * w, 1, false, 2));
    s.finalize();
    return s;
}

// Floor points: under the light's middle, under an edge, off to the side.
const std::vector<Vec3> kPoints = {{0.0, 0, 0.0}, {0.1, 0, -0.2}, {0.37, 0, 0.11}, {-0.8, 0, 0.5}, {1.3, 0, 1.1}};

// Samplers at their defaults but for a 32 × 32 image (the leaf's squares
// are still 6 pixels wide in it).
DirectSamplerSettings settingsFor(DirectEstimator e) {
    DirectSamplerSettings s;
    s.estimator = e;
    s.imageSize = 32;
    return s;
}

// The mean over 32 seeds of `sample(x, seed)` at every point within 4
// standard errors of the exact shadow (MeanAndError.h), plus 2e-4 of it for
// the eye's lift (samplingEyeLift).
void expectExactShadow(const std::function<double(const Vec3&, uint32_t)>& sample, const std::string& what) {
    const ExactDirect exact(squaresScene());
    for (size_t i = 0; i < kPoints.size(); ++i) {
        const double truth = exact.irradiance(0, kPoints[i], kUp).r;
        std::vector<double> r;
        for (uint32_t seed = 0; seed < 32; ++seed) r.push_back(sample(kPoints[i], seedFor(3, uint32_t(i), seed)));
        test::expectUnbiased(r, truth, 2e-4 * truth, concat(what, " point ", i));
    }
}

}  // namespace

TEST(CutOut, TheMaskMattersAtThesePoints) {
    // The exact shadow lies well away from both "no leaf" and "opaque leaf"
    // (so a sampler that ignored the mask either way fails by far more than
    // its noise), and the squares scene really is the mask's geometry.
    const Scene squares = squaresScene();
    const ExactDirect exact(squares);
    const Scene masked = maskedScene();
    int between = 0;
    for (const Vec3& x : kPoints) {
        const double open = unoccludedCosineSolidAngle(squares.lights[0], x, kUp) * squares.lights[0].radiance.r;
        const double e = exact.irradiance(0, x, kUp).r;
        if (e > 0.2 * open && e < 0.8 * open) ++between;
    }
    EXPECT_GE(between, 3);
    EXPECT_FALSE(masked.materials[2].cutAway(Vec2(0.5 / kCells, 0.5 / kCells)));  // square (0, 0): opaque
    EXPECT_TRUE(masked.materials[2].cutAway(Vec2(1.5 / kCells, 0.5 / kCells)));   // (1, 0): open
}

TEST(CutOut, RayTracedSamplerSeesThroughTheHoles) {
    // Embree's filter skips the holes.
    const Scene scene = maskedScene();
    const EmbreeScene rays(scene);
    for (DirectEstimator est : {DirectEstimator::ControlVariate, DirectEstimator::Plain}) {
        const RayTracedLightSampler sampler(rays, settingsFor(est));
        expectExactShadow([&](const Vec3& x, uint32_t seed) { return sampler.sample(0, x, kUp, seed).irradiance.r; },
                          concat("ray-traced ", directEstimatorName(est)));
    }
}

TEST(CutOut, RasterSamplerSeesThroughTheHoles) {
    // The coverage pass's MASKS variant tests each jittered sample against
    // the leaf's alpha, the texel edges decided in float (1e-7 of the leaf:
    // far below the allowance).
    const Scene scene = maskedScene();
    for (DirectEstimator est : {DirectEstimator::ControlVariate, DirectEstimator::Plain}) {
        DirectLightSampler sampler(test::glContext(), scene, settingsFor(est));
        expectExactShadow([&](const Vec3& x, uint32_t seed) { return sampler.sample(0, x, kUp, seed).irradiance.r; },
                          concat("raster ", directEstimatorName(est)));
    }
}

TEST(CutOut, PathTracerSeesThroughTheHoles) {
    // Direct light alone, 40000 samples a point: within 4 of its own
    // standard errors of the exact value.
    const Scene scene = maskedScene();
    const EmbreeScene rays(scene);
    PathTracerSettings ps;
    ps.maxDepth = 1;
    const PathTracer tracer(rays, ps);
    const ExactDirect exact(squaresScene());
    for (size_t i = 0; i < kPoints.size(); ++i) {
        const IrradianceEstimate e = tracer.irradiance(kPoints[i], kUp, 40000, uint32_t(i));
        const double truth = exact.irradiance(0, kPoints[i], kUp).r;
        EXPECT_NEAR(e.direct.r, truth, 4 * e.directError.r + 1e-12) << "point " << i;
    }
}

TEST(CutOut, CompositeShowsTheFloorThroughTheHoles) {
    // Looking straight down from 0.5 above the leaf (90° view: the leaf's
    // middle 1 × 1, 4 × 4 squares, 16 pixels each). The cache holds a
    // linear function of position, E = (2 + x + 3y + 0.5z)·(1, 0.9, 0.8),
    // which the meshes interpolate exactly: the floor (y = 0) and the leaf
    // (y = 1) differ. At each square's centre pixel, the image must be
    // Kd/π × E of the surface in view: the leaf on opaque squares, the floor
    // 3× further along the same ray through the open ones. Tolerance 1e-3
    // relative: the G-buffer and irradiance targets are float, what remains
    // is the rasteriser's interpolation.
    const Scene scene = maskedScene();
    CacheSettings cs;
    cs.maxEdgeFraction = 1.0 / 8.0;
    IrradianceCache cache(scene, cs);
    auto field = [](const Vec3& p) { return (2.0 + p.x + 3 * p.y + 0.5 * p.z) * Rgb(1.0, 0.9, 0.8); };
    test::sampleEveryVertex(cache, [&](size_t, const Vec3& x, const Vec3&, uint32_t) { return field(x); }, 1, 1);
    const std::vector<IrradianceMeshCopy> meshes = cache.copyMeshes();
    Camera camera;
    camera.position = Vec3(0, 1.5, 0);
    camera.target = Vec3(0, 0, 0);
    camera.up = Vec3(0, 0, -1);
    camera.fovYDegrees = 90;
    const int size = 64;
    for (int supersample : {1, 2}) {
        Compositor compositor(test::glContext(), scene);
        CompositorSettings s;
        s.width = s.height = size;
        s.supersample = supersample;
        const ImageRgb image = compositor.render(camera, meshes, s);
        int holes = 0, leaves = 0;
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 4; ++i) {
                // The pixel at the square's centre (x right, z down the image:
                // up is −z), and where its centre's ray crosses the leaf.
                const int px = (2 * i + 1) * size / 8, py = (2 * j + 1) * size / 8;
                const double x = -0.5 + (px + 0.5) / size, z = -0.5 + (py + 0.5) / size;
                const Vec2 uv((x + 1) / 2, (z + 1) / 2);
                const bool open = scene.materials[2].cutAway(uv);
                const Vec3 p = open ? Vec3(3 * x, 0.0, 3 * z) : Vec3(x, 1.0, z);
                const Rgb kd = open ? scene.materials[0].kd : scene.materials[2].kd;
                const Rgb expected = kd / kPi * field(p);
                const Rgb got = image.at(px, py);
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(got[c] / expected[c], 1.0, 1e-3)
                        << "supersample " << supersample << ", square " << i << "," << j << (open ? " (hole)" : " (leaf)")
                        << " channel " << c;
                (open ? holes : leaves) += 1;
            }
        EXPECT_EQ(holes, 8);
        EXPECT_EQ(leaves, 8);
    }
}
