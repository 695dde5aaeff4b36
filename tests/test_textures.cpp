// Textures drawn per pixel (issue 13): the compositor multiplies the cached
// irradiance by the texture, mipmapped; the path tracer samples it at its
// hits; the radiance proxy and the bounce count take each triangle's mean
// over its texture footprint. Small headless images.
#include "TempDirTest.h"
#include "TestSamplers.h"
#include "cache/IrradianceCache.h"
#include "core/loaders/GltfLoader.h"
#include "core/loaders/ObjLoader.h"
#include "core/loaders/TextureMean.h"
#include "core/raytrace/BounceCount.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "gpu_sampling/indirect/RadianceProxy.h"
#include "gpu_sampling/indirect/VoxelGrid.h"
#include "viewer/compositor/Compositor.h"

#include "GlTestContext.h"

#include <gtest/gtest.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_image_write.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>

using namespace ml;

namespace {

// sRGB-encoded 8-bit texels, `channels` 3, top row first.
std::shared_ptr<Texture> makeTexture(int width, int height, const std::vector<unsigned char>& rgb, bool nearest,
                                     TextureWrap wrap) {
    auto t = std::make_shared<Texture>();
    t->name = "test";
    t->width = width;
    t->height = height;
    for (size_t i = 0; i < rgb.size(); i += 3) t->rgba.insert(t->rgba.end(), {rgb[i], rgb[i + 1], rgb[i + 2], 255});
    t->nearest = nearest;
    t->wrapS = t->wrapT = wrap;
    return t;
}

// 4 × 4 texels of varied colours, magnified to the nearest, clamped.
std::shared_ptr<Texture> fourByFour() {
    return makeTexture(4, 4,
                       {200, 120, 90,  110, 220, 130, 140, 150, 230, 250, 250, 250,  //
                        180, 100, 200, 120, 240, 240, 90,  200, 140, 160, 110, 100,  //
                        230, 190, 120, 100, 100, 100, 210, 110, 180, 130, 230, 170,  //
                        150, 150, 150, 170, 200, 230, 240, 160, 100, 120, 140, 200},
                       true, TextureWrap::ClampToEdge);
}

// A 2 × 2 floor in y = 0 facing up, uv = ((x + 1) / 2, (z + 1) / 2) × uvScale,
// under a 0.5 × 0.5 light at y = 2 facing down. `texture` null: untextured,
// Kd = `factor`.
Scene floorScene(std::shared_ptr<Texture> texture, const Rgb& factor, double uvScale = 1) {
    Scene s;
    s.name = "floor";
    Material floor = Material::diffuse("floor", factor);
    if (texture) {
        floor.kdMap.image = texture;
        floor.kdMap.factor = factor;
        floor.kd = glm::clamp(factor * texture->imageMean(), Rgb(0.0), Rgb(1.0));
    }
    s.materials = {floor, Material::diffuse("light", Rgb(0.0), Rgb(10.0, 9.0, 8.0))};
    Mesh f;
    f.name = "floor";
    f.positions = {{-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}};
    f.normals.assign(4, Vec3(0, 1, 0));
    f.triangles = {{0, 1, 2}, {0, 2, 3}};
    f.materials = {0, 0};
    f.sourceLines = {0, 0};
    if (texture)
        for (const Vec3& p : f.positions) f.texcoords.push_back(Vec2((p.x + 1) / 2, (p.z + 1) / 2) * uvScale);
    Mesh l;
    l.name = "light";
    l.positions = {{-0.25, 2, -0.25}, {0.25, 2, -0.25}, {0.25, 2, 0.25}, {-0.25, 2, 0.25}};
    l.normals.assign(4, Vec3(0, -1, 0));
    l.triangles = {{0, 1, 2}, {0, 2, 3}};
    l.materials = {1, 1};
    l.sourceLines = {0, 0};
    s.meshes = {f, l};
    s.finalize();
    return s;
}

// Looking straight down at the floor from `height`; the view sees floor only.
Camera downCamera(double height, double fov) {
    Camera c;
    c.position = Vec3(0, height, 0);
    c.target = Vec3(0, 0, 0);
    c.up = Vec3(0, 0, -1);
    c.fovYDegrees = fov;
    return c;
}

// Where the ray through image point (px, py) (pixels, row 0 at the top)
// meets y = 0: the floor's uv there.
Vec2 floorUv(const Camera& c, int width, int height, double px, double py, double uvScale = 1) {
    Vec3 forward, right, up;
    c.basis(forward, right, up);
    const double t = std::tan(glm::radians(c.fovYDegrees) / 2);
    const double aspect = double(width) / height;
    const Vec3 d = forward + (2 * px / width - 1) * t * aspect * right + (1 - 2 * py / height) * t * up;
    const Vec3 p = c.position + (-c.position.y / d.y) * d;
    return Vec2((p.x + 1) / 2, (p.z + 1) / 2) * uvScale;
}

// The cache of `scene` filled with a smooth closed form, as meshes for the compositor.
std::vector<IrradianceMeshCopy> smoothCache(const Scene& scene) {
    CacheSettings cs;
    cs.maxEdgeFraction = 1.0 / 8.0;
    IrradianceCache cache(scene, cs);
    test::sampleEveryVertex(
        cache,
        [](size_t, const Vec3& x, const Vec3&, uint32_t) { return (2.0 + x.x + 0.5 * x.z) * Rgb(1.0, 0.9, 0.8); }, 1,
        1);
    return cache.copyMeshes();
}

ImageRgb composite(const Scene& scene, const Camera& camera, const std::vector<IrradianceMeshCopy>& meshes, int size,
                   CompositeQuantity quantity = CompositeQuantity::Radiance) {
    Compositor compositor(test::glContext(), scene);
    CompositorSettings s;
    s.width = s.height = size;
    s.supersample = 1;
    s.quantity = quantity;
    return compositor.render(camera, meshes, s);
}

}  // namespace

// The test: a textured floor's image is the untextured one (Kd = the
// factor) times the texture, within 1/255. Texels about 9 pixels wide,
// magnified to the nearest texel, compared at pixel centres (supersample
// 1) a pixel or more away from texel edges, so filtering cannot spoil the
// comparison: the reference is the texel, decoded on the CPU. (With
// bilinear magnification llvmpipe's interpolation weights are coarse:
// Kd came out up to 0.04 away from the exact bilinear value.)
TEST(Textures, TexturedFloorIsTheUntexturedTimesTheTexture) {
    const auto texture = fourByFour();
    const Rgb factor(0.9, 1.0, 0.8);
    const Scene textured = floorScene(texture, factor);
    const Scene plain = floorScene(nullptr, factor);
    ASSERT_TRUE(textured.hasTextures());
    ASSERT_FALSE(plain.hasTextures());
    const std::vector<IrradianceMeshCopy> meshes = smoothCache(plain);
    const Camera camera = downCamera(1.5, 60);
    const int size = 32;
    const ImageRgb a = composite(textured, camera, meshes, size);
    const ImageRgb b = composite(plain, camera, meshes, size);
    const ImageRgb kd = composite(textured, camera, meshes, size, CompositeQuantity::Reflectance);
    double worst = 0;
    int checked = 0;
    auto texel = [&](double px, double py) {
        const Vec2 uv = glm::clamp(floorUv(camera, size, size, px, py), Vec2(0.0), Vec2(0.999999));
        return int(uv.x * 4) + 4 * int(uv.y * 4);
    };
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const int own = texel(x + 0.5, y + 0.5);
            if (texel(x - 0.5, y + 0.5) != own || texel(x + 1.5, y + 0.5) != own || texel(x + 0.5, y - 0.5) != own ||
                texel(x + 0.5, y + 1.5) != own)
                continue;
            ++checked;
            const Rgb t = glm::clamp(factor * texture->sample(floorUv(camera, size, size, x + 0.5, y + 0.5)),
                                     Rgb(0.0), Rgb(1.0));
            // The untextured image per unit of Kd: Kd is compared in its own units.
            const Rgb perKd = b.at(x, y) / factor;
            const Rgb expected = perKd * t;
            const Rgb got = a.at(x, y);
            for (int c = 0; c < 3; ++c) {
                ASSERT_GT(b.at(x, y)[c], 0) << x << "," << y;
                worst = std::max(worst, std::abs(got[c] - expected[c]) / perKd[c]);
                // The reflectance layer is the textured Kd too.
                EXPECT_NEAR(kd.at(x, y)[c], t[c], 1.0 / 255) << x << "," << y << " channel " << c << " uv "
                                                             << floorUv(camera, size, size, x + 0.5, y + 0.5).x << ","
                                                             << floorUv(camera, size, size, x + 0.5, y + 0.5).y;
            }
        }
    EXPECT_GT(checked, size * size / 2);
    EXPECT_LT(worst, 1.0 / 255);
    std::printf("textured - untextured x texture: worst %.2e of Kd over %d pixels\n", worst,
                checked);
}

// A high-frequency checker (1-texel squares of black and white, 8 texels a
// pixel) averages to its linear mean 0.5 through the mipmaps: no aliasing.
// Without mipmaps each pixel would read one texel, 0 or 1. Tolerance 0.03:
// llvmpipe's sRGB decode and filtering work in 8 bits.
TEST(Textures, MipmapsAverageAFarCheckerToItsMean) {
    const int n = 256;
    std::vector<unsigned char> rgb;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            for (int c = 0; c < 3; ++c) rgb.push_back((x + y) % 2 ? 255 : 0);
    const auto checker = makeTexture(n, n, rgb, false, TextureWrap::Repeat);
    EXPECT_NEAR(checker->imageMean().r, 0.5, 1e-12);
    const Scene textured = floorScene(checker, Rgb(1.0));
    const Scene plain = floorScene(nullptr, Rgb(1.0));
    const Camera camera = downCamera(1.5, 60);
    const int size = 24;  // 256 texels over 2 units, 24 pixels over 1.73: 9 texels a pixel
    const std::vector<IrradianceMeshCopy> meshes = smoothCache(plain);
    const ImageRgb a = composite(textured, camera, meshes, size);
    const ImageRgb b = composite(plain, camera, meshes, size);
    double lo = 1, hi = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            for (int c = 0; c < 3; ++c) {
                const double ratio = a.at(x, y)[c] / b.at(x, y)[c];
                lo = std::min(lo, ratio);
                hi = std::max(hi, ratio);
            }
    EXPECT_NEAR(lo, 0.5, 0.03);
    EXPECT_NEAR(hi, 0.5, 0.03);
    std::printf("far checker: textured / untextured in [%.4f, %.4f] (mean 0.5)\n", lo, hi);
}

// A texture atlas without room between its charts, seen at a grazing
// angle: the floor reads a long thin grey chart of a 1024² texture (along
// the view texels 0..1023, across it texels 0..15 and 2 texels of grey
// beyond: a thin gutter), the rest of the texture
// white. Every texel the floor covers is grey, as the path tracer reads
// it; a filter adds white only by reaching past the gutter. One pass (the
// viewer: the trilinear level, from the footprint's longer axis) reads a
// square as long as the grazing footprint, across the chart; several
// passes filter over half their samples' spacing along the shorter axis
// (textureLodShiftFor). Measured here (llvmpipe): +35.8% with one pass,
// +0.36% with 4 passes of 4 × 4 sub-pixels; the GL's isotropic filter over
// the same half spacing gave +3.5%. Bound: 1% for 4 passes (the
// chart is 16 texels wide: the back rooms' floor came out 0.3% off). The
// one pass is printed, not bounded: a GL that filters anisotropically
// reads that footprint as it is (Compositor's textureAnisotropy).
TEST(Textures, SeveralPassesFilterAnAtlasOverTheirSamplesNotAcrossItsCharts) {
    const int n = 1024, chart = 16 + 2;
    std::vector<unsigned char> rgb;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            for (int c = 0; c < 3; ++c) rgb.push_back(x < chart ? 128 : 255);
    const auto atlas = makeTexture(n, n, rgb, false, TextureWrap::Repeat);
    const double grey = atlas->sample(Vec2(0.005, 0.5)).r;  // sRGB 128, decoded: 0.2158
    EXPECT_NEAR(grey, 0.2158, 1e-3);
    Scene textured = floorScene(atlas, Rgb(1.0));
    textured.materials[0].kdMap.scale = Vec2(16.0 / n, 1.0);  // u = (x + 1)/2: the chart's 16 texels across
    const Scene plain = floorScene(nullptr, Rgb(1.0));
    Camera camera;  // 10 cm above the floor, looking along z: along the chart
    camera.position = Vec3(0, 0.1, 1.3);
    camera.target = Vec3(0, 0, -1);
    camera.fovYDegrees = 40;
    const std::vector<IrradianceMeshCopy> meshes = smoothCache(plain);
    const auto reflectance = [&](const Scene& scene, int passes) {
        Compositor compositor(test::glContext(), scene);
        CompositorSettings s;
        s.width = s.height = 64;
        s.supersample = 4;
        s.passes = passes;
        s.quantity = CompositeQuantity::Reflectance;
        return compositor.render(camera, meshes, s);
    };
    const ImageRgb covered = reflectance(plain, 1);  // Kd 1 on the floor, 0 beyond it
    double error[2] = {0, 0};
    int pixels = 0;
    const int passes[2] = {1, 4};
    for (int k = 0; k < 2; ++k) {
        const ImageRgb image = reflectance(textured, passes[k]);
        double sum = 0;
        pixels = 0;
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) {
                if (covered.at(x, y).r < 0.999) continue;  // wholly the floor
                sum += image.at(x, y).r;
                ++pixels;
            }
        error[k] = sum / pixels / grey - 1;
    }
    EXPECT_GT(pixels, 64 * 64 / 4);
    std::printf("atlas floor's mean reflectance over %d pixels: %+.2f%% (one pass), %+.2f%% (4 passes)\n", pixels,
                100 * error[0], 100 * error[1]);
    EXPECT_LT(std::abs(error[1]), 0.01);
}

// The path tracer reads Kd at the hit's uv: with the same seed, the
// radiance of a textured floor is Kd(uv)/π·E where the untextured floor
// (Kd 1) gives 1/π·E, wherever a pixel lies inside one texel (nearest),
// to float rounding: each sample's estimate is linear in Kd at depth 1.
TEST(Textures, PathTracerRadianceIsTheTexturesKdOverPiTimesIrradiance) {
    const auto texture = fourByFour();
    const Scene textured = floorScene(texture, Rgb(1.0));
    const Scene plain = floorScene(nullptr, Rgb(1.0));
    const EmbreeScene raysA(textured), raysB(plain);
    PathTracerSettings ps;
    ps.maxDepth = 1;
    ps.threads = 2;
    const Camera camera = downCamera(1.5, 60);
    const int size = 16;
    const ReferenceImage a = PathTracer(raysA, ps).render(camera, size, size, 4);
    const ReferenceImage b = PathTracer(raysB, ps).render(camera, size, size, 4);
    int checked = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            // Inside one texel when the pixel's four corners are.
            auto texel = [&](double px, double py) {
                const Vec2 uv = glm::clamp(floorUv(camera, size, size, px, py), Vec2(0.0), Vec2(0.999999));
                return int(uv.x * 4) + 4 * int(uv.y * 4);
            };
            const int t = texel(x, y);
            if (texel(x + 1, y) != t || texel(x, y + 1) != t || texel(x + 1, y + 1) != t) continue;
            const Rgb kd = texture->sample(floorUv(camera, size, size, x + 0.5, y + 0.5));
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(a.radiance.at(x, y)[c], kd[c] * b.radiance.at(x, y)[c], 1e-5 * b.radiance.at(x, y)[c])
                    << x << "," << y;
            ++checked;
        }
    EXPECT_GT(checked, 30);
}

// A wall textured half black, half white, each triangle covering one half:
// the triangles get their own means (Mesh::albedo), 0 and 1, where the
// material's Kd is their mean 0.5; the radiance proxy reflects with them,
// and the bounce count weighs them by the light they receive.
class TexturedWall : public test::TempDirTest {};

TEST_F(TexturedWall, TrianglesTakeTheirOwnMeanAlbedo) {
    const std::string png = path("bw.png");
    const unsigned char texels[] = {0, 0, 0, 255, 255, 255};  // black left, white right
    ASSERT_NE(stbi_write_png(png.c_str(), 2, 1, 3, texels, 6), 0);
    write("wall.mtl", "newmtl wall\nKd 1 1 1\nmap_Kd bw.png\nnewmtl light\nKd 0 0 0\nKe 5 5 5\n");
    // Triangle 1 (lower right) reads the left, black half; triangle 2
    // (upper left) the white half. A small light just in front of the
    // white triangle's centroid, facing the wall.
    const std::string obj = write("wall.obj",
                                  "mtllib wall.mtl\no wall\n"
                                  "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                  "vt 0 0\nvt 0.5 0\nvt 0.5 1\nvt 0.6 0\nvt 1 1\nvt 0.6 1\n"
                                  "usemtl wall\nf 1/1 2/2 3/3\nf 1/4 3/5 4/6\n"
                                  "o light\nv 0.3 0.7 0.05\nv 0.3 0.6 0.05\nv 0.2 0.6 0.05\nv 0.2 0.7 0.05\n"
                                  "usemtl light\nf 5 6 7 8\n");
    const Scene scene = loadObj(obj);
    size_t wall = scene.meshes.size();
    for (size_t m = 0; m < scene.meshes.size(); ++m)
        if (scene.materials[scene.meshes[m].materials[0]].name == "wall") wall = m;
    ASSERT_LT(wall, scene.meshes.size());
    const Mesh& mesh = scene.meshes[wall];
    ASSERT_EQ(mesh.triangles.size(), 2u);
    ASSERT_EQ(mesh.albedo.size(), 2u);
    ASSERT_EQ(mesh.texcoords.size(), mesh.positions.size());
    const Material& m = scene.materials[mesh.materials[0]];
    EXPECT_NEAR(m.kd.r, 0.5, 1e-12);
    EXPECT_TRUE(bool(m.kdMap));
    EXPECT_NEAR(scene.albedo(wall, 0).r, 0.0, 1e-12);
    EXPECT_NEAR(scene.albedo(wall, 1).r, 1.0, 1e-12);

    // The proxy's pieces of each triangle reflect with its own mean.
    const RadianceProxy proxy(scene, VoxelGrid::fit(scene.bounds, 16));
    double blackPieces = 0, whitePieces = 0;
    for (const ProxyTriangle& t : proxy.triangles()) {
        if (t.kd.r == 0.0) ++blackPieces;
        if (t.kd.r == 1.0) ++whitePieces;
    }
    EXPECT_GT(blackPieces, 0);
    EXPECT_GT(whitePieces, 0);

    // Direct light falls mostly on the white triangle: the albedo it meets
    // is well above the material's mean.
    const BounceCount plan = countBounces(scene, BounceCountSettings{});
    EXPECT_GT(plan.albedo.r, 0.8);
    std::printf("albedo direct light meets: %.3f (material mean 0.5)\n", plan.albedo.r);
}

// Not a check, a measurement (run with --gtest_also_run_disabled_tests): the
// back rooms (9,185 triangles, textures up to 4096²) composited at 480 × 270
// with their textures and with them stripped (each material its mean Kd).
TEST(Textures, DISABLED_BackroomsCompositeTime) {
    const std::string file = std::string(MESHLIGHT_SHARED_SCENES) + "/backrooms-gltf/scene.gltf";
    if (!std::ifstream(file)) GTEST_SKIP() << "no " << file;
    const Scene textured = loadGltf(file);
    Scene plain = textured;
    for (Material& m : plain.materials) m.kdMap = m.keMap = TextureMap{};
    ASSERT_TRUE(textured.hasTextures());
    ASSERT_FALSE(plain.hasTextures());
    IrradianceCache cache(textured, CacheSettings{});
    const std::vector<IrradianceMeshCopy> meshes = cache.copyMeshes();
    Camera camera;
    camera.position = Vec3(199.8, 50, -40);
    camera.target = Vec3(199.8, 62, -166);
    camera.fovYDegrees = 70;
    for (const Scene* scene : {static_cast<const Scene*>(&plain), &textured}) {
        Compositor compositor(test::glContext(), *scene);
        const GpuCacheMeshes gpu = compositor.upload(meshes, {});
        for (int supersample : {1, 4}) {
            CompositorSettings s;
            s.width = 480;
            s.height = 270;
            s.supersample = supersample;
            compositor.compose(camera, gpu, LightWeights::unit(scene->lights.size()), s);
            compositor.readImage();  // warm: shaders compiled, targets made
            const int n = 10;
            const auto start = std::chrono::steady_clock::now();
            for (int i = 0; i < n; ++i) {
                compositor.compose(camera, gpu, LightWeights::unit(scene->lights.size()), s);
                compositor.readImage();
            }
            const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() / n;
            std::printf("%s, supersample %d: %.1f ms per composite and read-back\n",
                        scene == &textured ? "textured" : "means only", supersample, ms);
        }
    }
}
