// The display-time specular pass (issue 16): mirrors, glass and Phong
// highlights read from the cache (viewer/compositor/SpecularPaths.h,
// gpu_sampling/indirect/CachedRadiance.h). Caches are filled with closed
// forms, so each expected value is known exactly.
#include "RunCommand.h"
#include "TempDirTest.h"
#include "TestSamplers.h"
#include "TestScenes.h"
#include "cache/IrradianceCache.h"
#include "core/SmoothSpecular.h"
#include "core/image/Image.h"
#include "core/raytrace/PhongBsdf.h"
#include "core/reference/Lambert.h"
#include "viewer/compositor/Compositor.h"
#include "viewer/compositor/SpecularPaths.h"

#include "GlTestContext.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

using namespace ml;
using test::kX;
using test::kY;
using test::kZ;
using test::quadMesh;

namespace {

Material emitter() {
    Material m;
    m.name = "light";
    m.kd = Rgb(0.0);
    m.ke = Rgb(1.0);
    return m;
}

Material diffuse(const std::string& name, double kd) {
    Material m;
    m.name = name;
    m.kd = Rgb(kd);
    return m;
}

// A cache of `scene` whose every light gives f(x, n) at every vertex.
template <class F>
std::vector<IrradianceMeshCopy> cacheOf(const Scene& scene, F f, double edgeFraction = 1.0 / 8.0) {
    CacheSettings cs;
    cs.maxEdgeFraction = edgeFraction;
    IrradianceCache cache(scene, cs);
    test::sampleEveryVertex(
        cache, [&](size_t light, const Vec3& x, const Vec3& n, uint32_t) { return f(light, x, n); }, 1, 1);
    return cache.copyMeshes();
}

// The eye ray of sub-pixel (x, y) (row 0 at the top), as the compositor's
// projection makes it: the centre of the sub-pixel, no shift.
Vec3 eyeRay(const Camera& c, int width, int height, int x, int y) {
    Vec3 forward, right, up;
    c.basis(forward, right, up);
    const double t = std::tan(glm::radians(c.fovYDegrees) / 2), aspect = double(width) / height;
    return glm::normalize(forward + (2 * (x + 0.5) / width - 1) * t * aspect * right +
                          (1 - 2 * (y + 0.5) / height) * t * up);
}

CompositorSettings settingsOf(int width, int height) {
    CompositorSettings s;
    s.width = width;
    s.height = height;
    s.supersample = 1;
    return s;
}

// A glass slab 20 × 20 × 0.2 (z ∈ [0, 0.2], faces outward) over a grey
// wall at z = −1 facing it; the light below the wall, facing away.
Scene slabScene(const SmoothSpecular& glass) {
    Material g = diffuse("glass", 0.0);
    g.smooth = glass;
    std::vector<Mesh> meshes = {quadMesh("light", 0, Vec3(-0.5, -0.5, -2), kY, kX),
                                quadMesh("wall", 1, Vec3(-30, -30, -1), 60.0 * kX, 60.0 * kY)};
    Mesh slab;
    slab.name = "slab";
    const Vec3 lo(-10, -10, 0), size(20, 20, 0.2);
    test::addQuad(slab, 2, lo + Vec3(0, 0, size.z), size.x * kX, size.y * kY);  // top, +z
    test::addQuad(slab, 2, lo, size.y * kY, size.x * kX);                        // bottom, −z
    test::addQuad(slab, 2, lo, size.x * kX, size.z * kZ);                        // −y
    test::addQuad(slab, 2, lo + Vec3(0, size.y, 0), size.z * kZ, size.x * kX);   // +y
    test::addQuad(slab, 2, lo, size.z * kZ, size.y * kY);                        // −x
    test::addQuad(slab, 2, lo + Vec3(size.x, 0, 0), size.y * kY, size.z * kZ);  // +x
    meshes.push_back(slab);
    return test::sceneOf("slab", {emitter(), diffuse("wall", 0.5), g}, meshes);
}

}  // namespace

// (a) A flat mirror shows what faces it: the composite of the mirror equals
// R × the composite, from the camera mirrored in its plane, of the scene
// without the mirror, with x flipped (a mirror swaps left and right). The
// wall's cached irradiance is linear in position, which the GPU's Gouraud
// interpolation and the paths' lookups both reproduce exactly; what is left
// is float rounding of the two interpolations (the GPU's perspective-correct
// one in float, the lookup's in double): 1e-4 of the value bounds it.
TEST(SpecularDisplay, FlatMirrorShowsTheMirroredCamerasView) {
    Material mirror = diffuse("mirror", 0.0);
    mirror.smooth.kind = SpecularKind::Mirror;
    mirror.smooth.reflectance = Rgb(0.9, 0.8, 0.7);
    const std::vector<Material> materials = {emitter(), diffuse("wall", 0.6), mirror};
    const Mesh light = quadMesh("light", 0, Vec3(-0.5, -0.5, 3), kX, kY);  // behind the wall, facing away
    const Mesh wall = quadMesh("wall", 1, Vec3(-4, -4, 2), 8.0 * kY, 8.0 * kX);  // facing −z, the mirror
    const Scene withMirror =
        test::sceneOf("mirror", materials, {light, wall, quadMesh("mirror", 2, Vec3(-2, -2, 0), 4.0 * kX, 4.0 * kY)});
    const Scene without = test::sceneOf("no mirror", materials, {light, wall});
    const auto e = [](size_t, const Vec3& x, const Vec3&) { return (2.0 + 0.3 * x.x + 0.2 * x.y) * Rgb(1.0, 0.9, 0.8); };

    Camera camera;
    camera.position = Vec3(0.3, 0.2, 1.5);
    camera.target = Vec3(0.0);
    camera.fovYDegrees = 40;
    Camera mirrored = camera;
    mirrored.position.z = -camera.position.z;
    const int w = 48, h = 36;
    Compositor a(test::glContext(), withMirror), b(test::glContext(), without);
    ASSERT_TRUE(a.hasSpecularPass());
    EXPECT_FALSE(b.hasSpecularPass());
    const ImageRgb reflected = a.render(camera, cacheOf(withMirror, e), {}, settingsOf(w, h));
    const ImageRgb direct = b.render(mirrored, cacheOf(without, e), {}, settingsOf(w, h));
    double worst = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Rgb expected = mirror.smooth.reflectance * direct.at(w - 1 - x, y);
            const Rgb got = reflected.at(x, y);
            ASSERT_GT(expected.g, 0.0) << "the wall fills the mirrored view";
            for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(got[c] - expected[c]) / expected[c]);
        }
    EXPECT_LT(worst, 1e-4) << "worst relative difference over the mirror";
    RecordProperty("worst_relative_difference", std::to_string(worst));
}

// (b) A glass slab in front of a wall of uniform radiance L: each sub-pixel
// shows L × (1 − F₁)·Tf × Σ_k F₂^{2k} × (1 − F₂)·Tf, F₁ the Fresnel
// reflectance where its eye ray enters, F₂ where the refracted ray meets the
// far face (internal reflections bounce between the faces, untinted: Tf
// filters what crosses an interface); the light reflected back up leaves
// the scene. Eight specular surfaces allow k = 0..3; every branch is traced
// (minWeight 0), so the sum is exact to double rounding (float storage:
// 1e-5 of the value). At normal incidence (F = 0.04) and about 70° (F up to 0.28).
TEST(SpecularDisplay, GlassSlabTransmitsWhatFresnelSays) {
    SmoothSpecular glass;
    glass.kind = SpecularKind::Glass;
    glass.ior = 1.5;
    glass.transmission = Rgb(0.9, 0.8, 1.0);
    const Scene scene = slabScene(glass);
    const Rgb e(3.0, 2.7, 2.4);
    const Rgb wallRadiance = 0.5 / kPi * e;
    SpecularSplitSettings every;
    every.minWeight = 0;
    SpecularPaths paths(scene, every);
    paths.setCache(cacheOf(scene, [&](size_t, const Vec3&, const Vec3&) { return e; }), {});
    const int w = 16, h = 12;
    for (const Vec3& position : {Vec3(0.05, 0.02, 3.0), Vec3(-3.0, 0.0, 0.2 + 3.0 / std::tan(glm::radians(70.0)))}) {
        Camera camera;
        camera.position = position;
        camera.target = Vec3(0.0, 0.0, 0.2);
        camera.fovYDegrees = 10;
        const ImageRgb image = paths.trace(camera, settingsOf(w, h), LightWeights::unit(scene.lights.size()));
        double worst = 0, fresnel = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const double cosI = -eyeRay(camera, w, h, x, y).z;
                const double f1 = fresnelDielectric(cosI, glass.ior);
                const double cosT = std::sqrt(1 - (1 - cosI * cosI) / (glass.ior * glass.ior));
                const double f2 = fresnelDielectric(cosT, 1 / glass.ior);
                double bounces = 0;
                for (int k = 0; k <= 3; ++k) bounces += std::pow(f2, 2 * k);
                const Rgb expected = wallRadiance * (1 - f1) * glass.transmission * bounces * (1 - f2) *
                                     glass.transmission;
                for (int c = 0; c < 3; ++c)
                    worst = std::max(worst, std::abs(image.at(x, y)[c] - expected[c]) / expected[c]);
                fresnel = std::max(fresnel, f1);
            }
        EXPECT_LT(worst, 1e-5) << "camera at z = " << position.z << ", Fresnel reflectance up to " << fresnel;
        RecordProperty(position.z > 2 ? "normal_worst" : "grazing_worst", std::to_string(worst));
        RecordProperty(position.z > 2 ? "normal_fresnel" : "grazing_fresnel", std::to_string(fresnel));
    }
}

// The same slab composited: the glass's Kd is 0, so the image is the
// specular pass alone, box-filtered; and a light switched off leaves the
// glass black (the weights reach the paths).
TEST(SpecularDisplay, CompositeAddsThePassAndFollowsTheLightsWeights) {
    SmoothSpecular glass;
    glass.kind = SpecularKind::Glass;
    const Scene scene = slabScene(glass);
    const std::vector<IrradianceMeshCopy> cache = cacheOf(scene, [](size_t, const Vec3&, const Vec3&) { return Rgb(2.0); });
    Camera camera;
    camera.position = Vec3(0.1, 0.2, 3.0);
    camera.target = Vec3(0.0);
    camera.fovYDegrees = 10;
    Compositor compositor(test::glContext(), scene);
    CompositorSettings s = settingsOf(8, 6);
    s.supersample = 2;
    const ImageRgb image = compositor.render(camera, cache, {}, s);
    SpecularPaths paths(scene);
    paths.setCache(cache, {});
    LightWeights weights = LightWeights::unit(scene.lights.size());
    const ImageRgb traced = paths.trace(camera, s, weights);
    const ImageRgb expected = boxDownsample(traced, 2);
    for (size_t i = 0; i < image.data.size(); ++i) {
        ASSERT_GT(expected.data[i], 0.0f);
        // The GPU adds 0 (Kd = 0) and the box filter runs on the CPU alike.
        EXPECT_NEAR(image.data[i], expected.data[i], 1e-6 * expected.data[i]) << i;
    }
    GpuCacheMeshes meshes = compositor.upload(cache, {});
    weights.light[0] = Rgb(0.0);
    const ImageRgb dark = compositor.composite(camera, meshes, weights, s);
    EXPECT_EQ(*std::max_element(dark.data.begin(), dark.data.end()), 0.0f);
}

// (c) Phong highlights against the analytic integral of the lobe over the
// light: a glossy plane (Kd 0, Ks 0.5, Ns 20) under a 5 cm square light 1 m
// above it, its direct irradiance cached in closed form (Lambert). The
// exact radiance is ∫ f(wo, wi) L cos θ dω over the light, with f the path
// tracer's own lobe (PhongBsdf::eval), by the midpoint rule on 32 × 32
// pieces of the light (each under 0.1% of a lobe width, so the rule's error
// is far below the target). The light's 0.0025 sr is small against the
// lobe's 2π/21 = 0.3 sr: the target, 3%, must hold wherever the
// highlight is at least a tenth of its peak.
TEST(SpecularDisplay, PhongHighlightAgreesWithTheLobesIntegralOverASmallLight) {
    Material glossy = diffuse("glossy", 0.0);
    glossy.ks = Rgb(0.5);
    glossy.ns = 20;
    Material light = emitter();
    light.ke = Rgb(1000.0);
    const double side = 0.05;
    const Scene scene = test::sceneOf(
        "glossy plane", {light, glossy},
        {quadMesh("light", 0, Vec3(-side / 2, 1.0, -side / 2), side * kX, side * kZ), test::floorMesh()});
    ASSERT_TRUE(scene.materials[1].glossy());
    const Light& l = scene.lights[0];
    const auto e = [&](size_t, const Vec3& x, const Vec3& n) {
        return l.radiance * unoccludedCosineSolidAngle(l, x, n);
    };
    SpecularPaths paths(scene);
    paths.setCache(cacheOf(scene, e, 1.0 / 64.0), {});
    Camera camera;
    camera.position = Vec3(1.2, 0.8, 0.05);
    camera.target = Vec3(0.6, 0.0, 0.0);
    camera.fovYDegrees = 30;
    const int w = 32, h = 24;
    const ImageRgb image = paths.trace(camera, settingsOf(w, h), LightWeights::unit(1));

    const PhongBsdf lobe(glossy, kY, Rgb(0.0));
    const int pieces = 32;
    std::vector<double> exact(size_t(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Vec3 d = eyeRay(camera, w, h, x, y);
            const Vec3 p = camera.position + (-camera.position.y / d.y) * d;
            double sum = 0;
            for (int i = 0; i < pieces; ++i)
                for (int j = 0; j < pieces; ++j) {
                    const Vec3 q(-side / 2 + (i + 0.5) * side / pieces, 1.0, -side / 2 + (j + 0.5) * side / pieces);
                    const Vec3 toLight = q - p;
                    const double r2 = glm::dot(toLight, toLight);
                    const Vec3 wi = toLight / std::sqrt(r2);
                    // dω = dA cos θ_light / r², θ_light = θ (both planes horizontal).
                    const double dOmega = side * side / (pieces * pieces) * wi.y / r2;
                    sum += lobe.eval(-d, wi).g * l.radiance.g * wi.y * dOmega;
                }
            exact[size_t(y) * w + x] = sum;
        }
    const double peak = *std::max_element(exact.begin(), exact.end());
    ASSERT_GT(peak, 0.0);
    double worst = 0;
    int compared = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double want = exact[size_t(y) * w + x];
            if (want < 0.1 * peak) continue;
            ++compared;
            worst = std::max(worst, std::abs(image.at(x, y).g - want) / want);
        }
    EXPECT_GT(compared, 20) << "the highlight covers part of the image";
    EXPECT_LT(worst, 0.03) << "worst relative difference where the highlight is over a tenth of its peak";
    RecordProperty("worst_relative_difference", std::to_string(worst));
}

// (d) No pass unless some face's material is glossy or specular: a floor
// under a light has none (the compositor then compiles the shaders of
// before, SPECULAR 0), and a glossy surface out of view leaves the
// composite exactly what it is without the pass (it adds 0.0, bit for bit).
TEST(SpecularDisplay, NoPassWithoutGlossyOrSpecularMaterials) {
    const Scene plain = test::sceneOf("plain", {emitter(), diffuse("floor", 0.5)}, {test::unitLight(), test::floorMesh()});
    Compositor none(test::glContext(), plain);
    EXPECT_FALSE(SpecularPaths::needed(plain));
    EXPECT_FALSE(none.hasSpecularPass());
    Material glossy = diffuse("glossy", 0.3);
    glossy.ks = Rgb(0.2);
    glossy.ns = 50;
    const Scene hidden = test::sceneOf(
        "glossy behind", {emitter(), diffuse("floor", 0.5), glossy},
        {test::unitLight(), test::floorMesh(), quadMesh("behind", 2, Vec3(-0.5, 0.2, 5), kX, kY)});
    const auto e = [](size_t, const Vec3& x, const Vec3&) { return Rgb(1.0 + 0.1 * x.x); };
    Camera camera;
    camera.position = Vec3(0.0, 2.0, -3.0);
    camera.target = Vec3(0.0, 0.0, 0.0);
    Compositor compositor(test::glContext(), hidden);
    ASSERT_TRUE(compositor.hasSpecularPass());
    CompositorSettings s = settingsOf(24, 16);
    s.supersample = 2;
    const ImageRgb with = compositor.render(camera, cacheOf(hidden, e), {}, s);
    s.specular = SpecularPart::Off;
    const ImageRgb without = compositor.render(camera, cacheOf(hidden, e), {}, s);
    EXPECT_EQ(with.data, without.data);
    EXPECT_GT(*std::max_element(with.data.begin(), with.data.end()), 0.0f);
}

// Through the binary: render's EXR has a 'specular' layer on the McGuire
// spheres (a mirror and a glass ball), and the layers still add up to the
// beauty image (to float rounding of the sum, as test_layers allows).
class SpecularLayers : public test::TempDirTest {};

TEST_F(SpecularLayers, SpecularLayerIsPartOfTheSum) {
    const std::string scene = std::string(MESHLIGHT_SHARED_SCENES) + "/mcguire-cornellbox/CornellBox-Sphere.obj";
    const test::CommandResult r = test::runMeshlight("render " + scene + " --direct-only --samples 3000 --width 32 "
                                                     "--height 24 --out " + path("s.exr"));
    ASSERT_EQ(r.status, 0) << r.output;
    const ImageRgb beauty = readImageLinear(path("s.exr"));
    std::vector<ImageRgb> parts;
    for (const char* layer : {"emission", "direct", "indirect", "specular"})
        parts.push_back(readImageLayer(path("s.exr"), layer));
    EXPECT_GT(*std::max_element(parts[3].data.begin(), parts[3].data.end()), 0.0f) << "the spheres reflect";
    int bad = 0;
    for (size_t i = 0; i < beauty.data.size(); ++i) {
        double sum = 0, largest = 0;
        for (const ImageRgb& p : parts) {
            sum += p.data[i];
            largest = std::max(largest, std::abs(double(p.data[i])));
        }
        if (std::abs(sum - beauty.data[i]) > 8 * std::numeric_limits<float>::epsilon() * std::max(largest, 1e-30))
            ++bad;
    }
    EXPECT_EQ(bad, 0) << "beauty = emission + direct + indirect + specular";
}

// plan says what runs: the McGuire spheres' mirror and glass, and no pass
// for the Cornell box.
TEST(SpecularPlan, SaysWhatRunsAndWhy) {
    const std::string scene = std::string(MESHLIGHT_SHARED_SCENES) + "/mcguire-cornellbox/CornellBox-Sphere.obj";
    const test::CommandResult spheres = test::runMeshlight("plan " + scene);
    ASSERT_EQ(spheres.status, 0) << spheres.output;
    EXPECT_NE(spheres.output.find("specular: a display-time pass"), std::string::npos) << spheres.output;
    EXPECT_NE(spheres.output.find("mirrors and glass (2 materials)"), std::string::npos) << spheres.output;
    EXPECT_EQ(spheres.output.find("Phong highlights"), std::string::npos) << "no glossy material";
    const test::CommandResult cornell = test::runMeshlight("plan cornell");
    ASSERT_EQ(cornell.status, 0) << cornell.output;
    EXPECT_NE(cornell.output.find("specular: no pass"), std::string::npos) << cornell.output;
}
