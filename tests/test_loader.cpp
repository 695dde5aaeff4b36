// OBJ/MTL loading (textures included), mesh clean-up and the built-in Cornell box.
#include "TempDirTest.h"

#include "core/Error.h"
#include "core/MeshUtil.h"
#include "core/loaders/ObjLoader.h"
#include "core/scenes/CornellBox.h"

#include <gtest/gtest.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using namespace ml;

namespace {

std::string dataFile(const std::string& name) {
    return std::string(MESHLIGHT_TEST_DATA) + "/" + name;
}

// A fresh folder for files a test writes (CRLF files, one-line error cases).
fs::path scratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const fs::path dir = fs::temp_directory_path() / "meshlight_test_loader" /
                         (std::string(info->test_suite_name()) + "." + info->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string writeFile(const fs::path& dir, const std::string& name, const std::string& text) {
    const fs::path path = dir / name;
    std::ofstream(path, std::ios::binary) << text;
    return path.string();
}

std::string joined(const std::vector<std::string>& lines) {
    std::string s;
    for (const std::string& l : lines) s += l + "\n";
    return s;
}

const Mesh& meshNamed(const Scene& scene, const std::string& name) {
    for (const Mesh& m : scene.meshes)
        if (m.name == name) return m;
    throw std::runtime_error("no mesh " + name);
}

Vec3 triangleCentroid(const Mesh& m, size_t t) {
    const Triangle3 p = m.triangle(t);
    return (p[0] + p[1] + p[2]) / 3.0;
}

void expectNear(const Vec3& actual, const Vec3& expected, double tol) {
    EXPECT_NEAR(actual.x, expected.x, tol);
    EXPECT_NEAR(actual.y, expected.y, tol);
    EXPECT_NEAR(actual.z, expected.z, tol);
}

// The InputError loadObj throws for `path` (a test failure when it throws none).
InputError loadError(const std::string& path) {
    try {
        loadObj(path);
    } catch (const InputError& e) {
        return e;
    }
    ADD_FAILURE() << "no error for " << path;
    return InputError("no error");
}

// Every corner's shading normal is its triangle's geometric normal.
void expectFlatNormals(const Mesh& m) {
    ASSERT_EQ(m.normals.size(), m.positions.size()) << m.name;
    for (size_t t = 0; t < m.triangles.size(); ++t) {
        const Vec3 n = glm::normalize(m.areaNormal(t));
        for (int k = 0; k < 3; ++k) expectNear(m.normals[m.triangles[t][k]], n, 1e-12);
    }
}

}  // namespace

// --- Well-formed files -------------------------------------------------------

TEST(ObjLoader, QuadLight) {
    const std::string path = dataFile("loader_quad_light.obj");
    const Scene scene = loadObj(path);
    EXPECT_EQ(scene.name, path);
    EXPECT_TRUE(scene.warnings.empty()) << joined(scene.warnings);
    ASSERT_EQ(scene.meshes.size(), 2u);
    EXPECT_EQ(scene.meshes[0].name, "floor");
    EXPECT_EQ(scene.meshes[1].name, "lamp");
    EXPECT_EQ(scene.triangleCount(), 4u);
    EXPECT_FALSE(scene.camera.has_value());

    // Only the materials faces use enter the scene.
    ASSERT_EQ(scene.materials.size(), 2u);
    const Material& white = scene.materials[scene.meshes[0].materials[0]];
    const Material& lamp = scene.materials[scene.meshes[1].materials[0]];
    EXPECT_EQ(white.name, "white");
    EXPECT_EQ(white.kd, Rgb(0.5));
    EXPECT_FALSE(white.emissive());
    EXPECT_EQ(lamp.name, "lamp");
    EXPECT_EQ(lamp.kd, Rgb(0.78));
    EXPECT_EQ(lamp.ks, Rgb(0.1));
    EXPECT_EQ(lamp.ns, 20.0);
    EXPECT_EQ(lamp.ke, Rgb(10, 8, 6));

    ASSERT_EQ(scene.lights.size(), 1u);
    const Light& light = scene.lights[0];
    EXPECT_EQ(light.name, "lamp");
    EXPECT_EQ(light.radiance, Rgb(10, 8, 6));
    EXPECT_NEAR(light.area, 0.5, 1e-15);
    expectNear(light.normal, Vec3(0, -1, 0), 1e-15);
    expectNear(light.centroid, Vec3(1, 1, 0.75), 1e-15);
    EXPECT_TRUE(light.planar);

    // Face lines are kept per triangle; the floor faces up.
    EXPECT_EQ(scene.meshes[0].sourceLines, (std::vector<int>{10, 10}));
    EXPECT_EQ(scene.meshes[1].sourceLines, (std::vector<int>{18, 18}));
    for (const Vec3& n : scene.meshes[0].normals) EXPECT_EQ(n, Vec3(0, 1, 0));
}

TEST(ObjLoader, NegativeIndicesAndDefaultMaterial) {
    const Scene scene = loadObj(dataFile("loader_negative.obj"));
    ASSERT_EQ(scene.meshes.size(), 1u);
    const Mesh& m = scene.meshes[0];
    EXPECT_EQ(m.name, "loader_negative");  // faces before any o/g
    ASSERT_EQ(m.triangles.size(), 2u);
    const Triangle3 a = m.triangle(0), b = m.triangle(1);
    EXPECT_EQ(a[0], Vec3(0, 0, 0));
    EXPECT_EQ(a[1], Vec3(1, 0, 0));
    EXPECT_EQ(a[2], Vec3(1, 1, 0));
    EXPECT_EQ(b[0], Vec3(0, 0, 1));
    EXPECT_EQ(b[1], Vec3(1, 0, 1));
    EXPECT_EQ(b[2], Vec3(1, 1, 1));
    ASSERT_EQ(scene.materials.size(), 1u);
    EXPECT_EQ(scene.materials[0].name, "default");
    EXPECT_EQ(scene.materials[0].kd, Rgb(0.8));
    EXPECT_TRUE(scene.lights.empty());
}

TEST(ObjLoader, PolygonsAreFanTriangulated) {
    const std::string path = dataFile("loader_polygon.obj");
    const Scene scene = loadObj(path);
    const Mesh& hexagon = meshNamed(scene, "hexagon");
    const Mesh& ell = meshNamed(scene, "ell");
    EXPECT_EQ(hexagon.triangles.size(), 4u);
    EXPECT_EQ(ell.triangles.size(), 4u);
    double hexagonArea = 0;
    for (size_t t = 0; t < hexagon.triangles.size(); ++t) {
        hexagonArea += hexagon.area(t);
        EXPECT_GT(hexagon.areaNormal(t).z, 0);
    }
    EXPECT_NEAR(hexagonArea, 6 * std::sqrt(3.0), 1e-12);
    // The L shape is not convex as seen from its first corner: one warning.
    EXPECT_EQ(scene.warnings,
              (std::vector<std::string>{
                  path + ": 1 polygon is not convex as seen from the first corner, so the fan "
                         "triangulation overlaps (first at line 21)"}));
}

TEST(ObjLoader, CubeWithoutNormalsSplitsAtCreases) {
    const Scene scene = loadObj(dataFile("loader_cube.obj"));
    ASSERT_EQ(scene.meshes.size(), 1u);
    const Mesh& m = scene.meshes[0];
    EXPECT_EQ(m.triangles.size(), 12u);
    EXPECT_EQ(m.positions.size(), 24u);  // 8 corners x 3 faces at 90 degrees > 30
    expectFlatNormals(m);

    ObjOptions smooth;
    smooth.creaseAngleDegrees = 180;
    const Mesh round = loadObj(dataFile("loader_cube.obj"), smooth).meshes[0];
    ASSERT_EQ(round.positions.size(), 8u);
    // Equal angles (90 degrees per face) at every corner: the diagonal.
    for (size_t v = 0; v < 8; ++v)
        expectNear(round.normals[v], glm::normalize(round.positions[v] - Vec3(0.5)), 1e-12);
}

TEST(ObjLoader, GivenNormalsAreUsedPerFace) {
    const Scene scene = loadObj(dataFile("loader_cube_vn.obj"));
    const Mesh& m = scene.meshes[0];
    ASSERT_EQ(m.triangles.size(), 12u);
    // 8 smooth vertices from vn, plus the top face's 4 with computed normals.
    EXPECT_EQ(m.positions.size(), 12u);
    for (size_t t = 0; t < m.triangles.size(); ++t) {
        const bool top = m.sourceLines[t] == 23;
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = m.triangles[t][k];
            const Vec3 expected = top ? Vec3(0, 1, 0) : glm::normalize(m.positions[v] - Vec3(0.5));
            expectNear(m.normals[v], expected, 1e-12);
        }
    }
    // The triangles stay in file order.
    EXPECT_TRUE(std::is_sorted(m.sourceLines.begin(), m.sourceLines.end()));
}

TEST(ObjLoader, TessellatedCylinderIsSmooth) {
    // 64 side quads (5.625 degrees apart), radius 1, height 2, no caps.
    const int n = 64;
    std::ostringstream obj;
    obj.precision(17);
    for (int i = 0; i < n; ++i) {
        const double a = 2 * kPi * i / n;
        obj << "v " << std::cos(a) << " 0 " << -std::sin(a) << "\n";
        obj << "v " << std::cos(a) << " 2 " << -std::sin(a) << "\n";
    }
    for (int i = 0; i < n; ++i) {
        const int j = (i + 1) % n;
        obj << "f " << 2 * i + 1 << " " << 2 * j + 1 << " " << 2 * j + 2 << " " << 2 * i + 2
            << "\n";
    }
    const std::string path = writeFile(scratchDir(), "cylinder.obj", obj.str());

    const Mesh m = loadObj(path).meshes[0];
    EXPECT_EQ(m.positions.size(), size_t(2 * n));  // no vertex split
    for (size_t v = 0; v < m.positions.size(); ++v) {
        const Vec3 p = m.positions[v];
        expectNear(m.normals[v], glm::normalize(Vec3(p.x, 0, p.z)), 1e-12);
    }
    ObjOptions sharp;
    sharp.creaseAngleDegrees = 5;  // below the 5.625 degrees between faces
    EXPECT_EQ(loadObj(path, sharp).meshes[0].positions.size(), size_t(4 * n));
}

TEST(ObjLoader, CrlfLineEndings) {
    // Written here rather than stored: Git may normalise a stored file's line
    // endings, and the test would silently read LF.
    const fs::path dir = scratchDir();
    writeFile(dir, "crlf.mtl", "newmtl lamp\r\nKd 0.5\t# grey\r\nKe 1 2 3\r\n");
    const std::string path = writeFile(
        dir, "crlf.obj",
        "mtllib crlf.mtl\r\nv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\n\r\ng tri\r\nusemtl lamp\r\n"
        "f 1 2 3\r\n");
    const Scene scene = loadObj(path);
    EXPECT_TRUE(scene.warnings.empty()) << joined(scene.warnings);
    ASSERT_EQ(scene.meshes.size(), 1u);
    EXPECT_EQ(scene.meshes[0].name, "tri");
    EXPECT_EQ(scene.meshes[0].sourceLines, (std::vector<int>{8}));
    EXPECT_EQ(scene.materials[0].name, "lamp");
    EXPECT_EQ(scene.materials[0].kd, Rgb(0.5));
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_EQ(scene.lights[0].radiance, Rgb(1, 2, 3));
}

TEST(ObjLoader, ReenteredGroupContinuesItsMesh) {
    const std::string path = writeFile(scratchDir(), "groups.obj",
                                       "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                       "g a\nf 1 2 3\ng b\nf 1 3 2\ng a\nf 3 2 1\n");
    const Scene scene = loadObj(path);
    ASSERT_EQ(scene.meshes.size(), 2u);
    EXPECT_EQ(meshNamed(scene, "a").sourceLines, (std::vector<int>{5, 9}));
    EXPECT_EQ(meshNamed(scene, "b").sourceLines, (std::vector<int>{7}));
}

TEST(ObjLoader, DegenerateTrianglesDroppedWithOneWarning) {
    const std::string path = dataFile("loader_degenerate.obj");
    const Scene scene = loadObj(path);
    EXPECT_EQ(scene.triangleCount(), 1u);
    EXPECT_EQ(scene.meshes[0].sourceLines, (std::vector<int>{7}));
    EXPECT_EQ(scene.warnings, (std::vector<std::string>{
                                  path + ": dropped 3 degenerate triangles (first at line 8)"}));
}

TEST(ObjLoader, MissingTextureNamesTheMtlAndLine) {
    const std::string obj = dataFile("loader_textures.obj");
    const fs::path dir = fs::path(MESHLIGHT_TEST_DATA).lexically_normal();
    const std::string mtl = (dir / "loader_textures.mtl").string();
    const InputError e = loadError(obj);
    EXPECT_EQ(std::string(e.what()), mtl + ":2: map_Kd 'wood.png': cannot read: no such file or not readable (" +
                                         (dir / "wood.png").string() + ")");
    EXPECT_EQ(e.where().file, mtl);
    EXPECT_EQ(e.where().line, 2);
}

TEST(ObjLoader, RedefinedMaterialKeepsTheFirst) {
    const fs::path dir = scratchDir();
    const std::string first = writeFile(dir, "first.mtl", "newmtl stone\nKd 0.25\n");
    const std::string second = writeFile(dir, "second.mtl", "\nnewmtl stone\nKd 0.75\n");
    const std::string path = writeFile(dir, "redefined.obj",
                                       "mtllib first.mtl second.mtl\nusemtl stone\n"
                                       "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const Scene scene = loadObj(path);
    EXPECT_EQ(scene.materials.at(0).kd, Rgb(0.25));
    EXPECT_EQ(scene.warnings, (std::vector<std::string>{
                                  second + ":2: material 'stone' is defined again; the definition at " +
                                  first + ":1 is used"}));
}

TEST(ObjLoader, VertexColoursAreIgnoredWithAWarning) {
    const std::string path = writeFile(scratchDir(), "colours.obj",
                                       "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n");
    const Scene scene = loadObj(path);
    EXPECT_EQ(scene.meshes[0].triangle(0)[1], Vec3(1, 0, 0));
    EXPECT_EQ(scene.warnings, (std::vector<std::string>{
                                  path + ":1: vertex colours are not supported; ignored (3 lines)"}));
}

TEST(ObjLoader, TinyAndHugeNormalsBecomeUnit) {
    // Caught by the fuzz target's unit-normal check (tests/fuzz) on a
    // hand-written input: a vn of subnormal components was divided by a
    // length with only a few significant bits, and came out 3e-5 off unit
    // length. Each normal must be unit to rounding (1e-15) and point where
    // the file says: the subnormal components themselves hold only ~11
    // significant bits (4.9e-324 steps), hence 1e-3 there.
    const std::string path = writeFile(scratchDir(), "normals.obj",
                                       "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                       "vn 1e-320 3e-321 0\nvn 1e308 -1e308 1e308\nvn 0 0 5e-324\n"
                                       "f 1//1 2//2 3//3\n");
    const Mesh m = loadObj(path).meshes.at(0);
    ASSERT_EQ(m.normals.size(), 3u);
    for (const Vec3& n : m.normals) EXPECT_NEAR(glm::length(n), 1.0, 1e-15);
    expectNear(m.normals[m.triangles[0][0]], glm::normalize(Vec3(1.0, 0.3, 0.0)), 1e-3);
    expectNear(m.normals[m.triangles[0][1]], glm::normalize(Vec3(1.0, -1.0, 1.0)), 1e-15);
    expectNear(m.normals[m.triangles[0][2]], Vec3(0.0, 0.0, 1.0), 1e-15);
}

// --- Textures ----------------------------------------------------------------

namespace {

// A folder for an OBJ, its MTL and PNG textures.
class ObjLoaderTextures : public test::TempDirTest {
protected:
    // Writes a PNG of width × height texels of `channels` 8-bit values, top
    // row first; returns its path.
    std::string png(const std::string& name, int width, int height, int channels,
                    const std::vector<unsigned char>& texels) const {
        EXPECT_EQ(texels.size(), size_t(width) * height * channels);
        const std::string file = path(name);
        EXPECT_NE(stbi_write_png(file.c_str(), width, height, channels, texels.data(), width * channels), 0);
        return file;
    }
    // "rb.png": 2 × 1, (255, 128, 0) on the left, blue on the right.
    void redBlue() const { png("rb.png", 2, 1, 3, {255, 128, 0, 0, 0, 255}); }

    const Material& material(const Scene& scene, const std::string& name) const {
        for (const Material& m : scene.materials)
            if (m.name == name) return m;
        throw std::runtime_error("no material " + name);
    }
};

// The sRGB EOTF, as the loader decodes 8-bit texels.
double linear(int v) {
    const double e = v / 255.0;
    return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
}

// rb.png's two texels, decoded.
const Rgb kLeft(1.0, linear(128), 0.0);
const Rgb kRight(0.0, 0.0, 1.0);

// The unit square's corners and texture coordinates for its halves:
// vt 1-4 the left half (u <= 0.5) as a quad, 5-6 the right edge, 7-9 u in [1, 1.5].
constexpr const char* kSquare =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "vt 0 0\nvt 0.5 0\nvt 0.5 1\nvt 0 1\nvt 1 0\nvt 1 1\nvt 1.5 0\nvt 1.5 1\nvt 1 0.5\n";

bool hasWarning(const Scene& scene, const std::string& text) {
    return std::find(scene.warnings.begin(), scene.warnings.end(), text) != scene.warnings.end();
}

}  // namespace

TEST_F(ObjLoaderTextures, MapKdIsTheMeanOverTheVtFootprint) {
    redBlue();
    png("tb.png", 1, 2, 3, {255, 0, 0, 0, 0, 255});  // red above blue
    const std::string mtl = write("t.mtl",
                                  "newmtl left\nKd 0.5\nmap_Kd rb.png\n"
                                  "newmtl right\nKd 1\nmap_Kd rb.png\n"
                                  "newmtl whole\nmap_Kd rb.png\n"
                                  "newmtl bottom\nKd 1\nmap_Kd tb.png\n");
    const std::string obj = write("t.obj", std::string("mtllib t.mtl\n") + kSquare +
                                               "usemtl left\nf 1/1 2/2 4/4\n"
                                               "usemtl right\nf 1/2 2/5 3/6\n"
                                               "usemtl whole\nf 1/1 2/5 3/6\nf 1/1 3/6 4/4\n"
                                               "usemtl bottom\nf 1/1 2/5 3/9\n");
    const Scene scene = loadObj(obj);
    // Covering only the left texel (the right half of the triangle's footprint is empty).
    expectNear(material(scene, "left").kd, 0.5 * kLeft, 1e-15);
    expectNear(material(scene, "right").kd, kRight, 1e-15);
    // Half of each, by area; Kd 0.8 when the MTL gives none.
    expectNear(material(scene, "whole").kd, 0.8 * (0.5 * kLeft + 0.5 * kRight), 1e-12);
    // vt has v up: v in [0, 0.5] is the image's bottom row.
    expectNear(material(scene, "bottom").kd, kRight, 1e-15);
    EXPECT_TRUE(hasWarning(scene, mtl + ":3: texture map_Kd 'rb.png' averaged to Kd (0.5, 0.108, 0)"))
        << joined(scene.warnings);
    EXPECT_EQ(scene.warnings.size(), 4u) << joined(scene.warnings);
}

TEST_F(ObjLoaderTextures, OffsetScaleAndClampAreHonoured) {
    redBlue();
    fs::create_directories(path("sub dir"));
    png("sub dir/red blue.png", 2, 1, 3, {255, 128, 0, 0, 0, 255});
    const std::string mtl = write("t.mtl",
                                  "newmtl offset\nKd 1\nmap_Kd -o 0.5 0 0 rb.png\n"
                                  "newmtl scaled\nKd 1\nmap_Kd -s 0.5 1 1 rb.png\n"
                                  "newmtl repeated\nKd 1\nmap_Kd rb.png\n"
                                  "newmtl clamped\nKd 1\nmap_Kd -clamp on rb.png\n"
                                  "newmtl ignored\nKd 1\nmap_Kd -bm 0.5 -blendu off -mm 0 1 sub dir/red blue.png\n"
                                  "newmtl ignored2\nKd 1\nmap_Kd -bm 2 -clamp off rb.png\n");
    const std::string obj = write("t.obj", std::string("mtllib t.mtl\n") + kSquare +
                                               "usemtl offset\nf 1/1 2/2 4/4\n"       // left half, moved right
                                               "usemtl scaled\nf 1/1 2/5 3/6\n"       // u in [0, 1] read as [0, 0.5]
                                               "usemtl repeated\nf 1/5 2/7 3/8\n"     // u in [1, 1.5]: the left again
                                               "usemtl clamped\nf 1/5 2/7 3/8\n"      // u in [1, 1.5]: the right edge
                                               "usemtl ignored\nf 1/1 2/2 4/4\n"
                                               "usemtl ignored2\nf 1/2 2/5 3/6\n");
    const Scene scene = loadObj(obj);
    expectNear(material(scene, "offset").kd, kRight, 1e-15);
    expectNear(material(scene, "scaled").kd, kLeft, 1e-15);
    expectNear(material(scene, "repeated").kd, kLeft, 1e-15);
    expectNear(material(scene, "clamped").kd, kRight, 1e-15);
    expectNear(material(scene, "ignored").kd, kLeft, 1e-15);
    expectNear(material(scene, "ignored2").kd, kRight, 1e-15);
    // Options that are not honoured: one warning each per MTL file, with a count.
    EXPECT_TRUE(hasWarning(scene, mtl + ":15: texture option -bm is not supported; ignored (2 lines)"))
        << joined(scene.warnings);
    EXPECT_TRUE(hasWarning(scene, mtl + ":15: texture option -blendu is not supported; ignored"));
    EXPECT_TRUE(hasWarning(scene, mtl + ":15: texture option -mm is not supported; ignored"));
    EXPECT_TRUE(hasWarning(scene, mtl + ":15: texture map_Kd 'sub dir/red blue.png' averaged to Kd (1, 0.216, 0)"));
}

TEST_F(ObjLoaderTextures, MapKeWithKeZeroOrNoneMakesALight) {
    png("white.png", 1, 1, 3, {255, 255, 255});
    png("grey.png", 1, 1, 1, {128});
    const std::string mtl = write("t.mtl",
                                  "newmtl none\nKd 0\nmap_Ke white.png\n"
                                  "newmtl zero\nKe 0 0 0\nmap_Ke grey.png\n"
                                  "newmtl given\nmap_Ke grey.png\nKe 2 4 8\n");
    const std::string obj = write("t.obj",
                                  "mtllib t.mtl\nv 0 1 0\nv 1 1 0\nv 0 1 1\nv 3 1 0\nv 4 1 0\nv 3 1 1\n"
                                  "v 6 1 0\nv 7 1 0\nv 6 1 1\n"
                                  "usemtl none\nf 1 2 3\nusemtl zero\nf 4 5 6\nusemtl given\nf 7 8 9\n");
    const Scene scene = loadObj(obj);
    ASSERT_EQ(scene.lights.size(), 3u);
    const double g = linear(128);
    EXPECT_EQ(scene.lights[0].radiance, Rgb(1.0));
    expectNear(scene.lights[1].radiance, Rgb(g), 1e-15);
    expectNear(scene.lights[2].radiance, Rgb(2 * g, 4 * g, 8 * g), 1e-15);
    EXPECT_TRUE(hasWarning(scene, mtl + ":3: texture map_Ke 'white.png' averaged to Ke (1, 1, 1) "
                                        "(no Ke or Ke 0: taken as 1 1 1 under map_Ke)"))
        << joined(scene.warnings);
    EXPECT_TRUE(hasWarning(scene, mtl + ":8: texture map_Ke 'grey.png' averaged to Ke (0.432, 0.863, 1.73)"));
}

TEST_F(ObjLoaderTextures, MapDCutsOutPerPixelWhereFacesHaveVt) {
    png("alpha.png", 2, 1, 4, {255, 255, 255, 255, 255, 255, 255, 0});  // opaque | transparent
    png("mask.png", 2, 1, 1, {255, 0});                                  // a grey mask, no alpha
    png("clear.png", 2, 1, 4, {255, 255, 255, 0, 255, 255, 255, 60});     // mean coverage 0.12
    const std::string mtl = write("t.mtl",
                                  "newmtl leaf\nmap_d alpha.png\n"
                                  "newmtl masked\nmap_d -o 0.5 0 mask.png\n"
                                  "newmtl clear\nmap_d clear.png\n");
    const std::string obj = write("t.obj", std::string("mtllib t.mtl\n") + kSquare +
                                               "usemtl leaf\n"
                                               "f 1/1 2/2 4/4\n"   // line 16: on the opaque texel
                                               "f 1/2 2/5 3/6\n"   // 17: on the transparent one
                                               "usemtl masked\n"
                                               "f 1/1 2/2 4/4\n"   // 19
                                               "usemtl clear\n"
                                               "f 1/1 2/2 4/4\n"   // 21: with vt, per pixel
                                               "f 1 2 3\n");       // 22: no vt, mean coverage: removed
    const Scene scene = loadObj(obj);
    ASSERT_EQ(scene.meshes.size(), 1u);
    const Mesh& mesh = scene.meshes[0];
    EXPECT_EQ(mesh.sourceLines, (std::vector<int>{16, 17, 19, 21}));
    ASSERT_EQ(mesh.texcoords.size(), mesh.positions.size());
    const auto material = [&](const std::string& name) -> const Material& {
        return *std::find_if(scene.materials.begin(), scene.materials.end(),
                             [&](const Material& m) { return m.name == name; });
    };
    // Mesh coordinates hold (u, 1 − v); the texels split at u = 0.5.
    EXPECT_FALSE(material("leaf").cutAway(Vec2(0.25, 0.5)));
    EXPECT_TRUE(material("leaf").cutAway(Vec2(0.75, 0.5)));
    EXPECT_TRUE(material("masked").cutAway(Vec2(0.25, 0.5)));  // -o 0.5: onto the black texel
    EXPECT_FALSE(material("masked").cutAway(Vec2(0.75, 0.5)));
    EXPECT_EQ(material("leaf").alphaCutoff, 0.5);
    EXPECT_TRUE(hasWarning(scene, mtl + ":6: texture map_d 'clear.png' cuts out 1 of the 1 triangle without vt (the "
                                        "image's mean coverage is below 0.5); faces with vt are cut out per pixel"))
        << joined(scene.warnings);

    // Nothing left is an error, not an empty scene.
    const std::string all = write("all.obj", std::string("mtllib t.mtl\n") + kSquare +
                                                 "usemtl clear\nf 1 2 3\n");
    EXPECT_EQ(std::string(loadError(all).what()), all + ": map_d cuts out every triangle (1)");
}

TEST_F(ObjLoaderTextures, FacesWithoutVtUseTheWholeImage) {
    redBlue();
    const std::string mtl = write("t.mtl", "newmtl wood\nKd 1\nmap_Kd rb.png\n");
    const std::string obj = write("t.obj", std::string("mtllib t.mtl\n") + kSquare +
                                               "usemtl wood\nf 1 2 3\nf 1/1 2/2 4/4\n");
    const Scene scene = loadObj(obj);
    // Equal areas: half the image's mean, half the left texel.
    expectNear(scene.materials.at(0).kd, 0.5 * (0.5 * kLeft + 0.5 * kRight) + 0.5 * kLeft, 1e-15);
    EXPECT_TRUE(hasWarning(scene, mtl + ":3: texture map_Kd 'rb.png': 1 triangle has no vt (texture coordinates); "
                                        "the mean over the whole image is used for it"))
        << joined(scene.warnings);
}

TEST_F(ObjLoaderTextures, BrokenImageIsAnInputError) {
    // A PNG cut in the middle of its pixel data, and a file that is no image.
    std::vector<unsigned char> texels(64 * 64 * 3);
    uint32_t state = 12345;  // noise, so that the pixel data does not compress away
    for (unsigned char& t : texels) t = static_cast<unsigned char>((state = state * 1664525u + 1013904223u) >> 24);
    const std::string whole = png("whole.png", 64, 64, 3, texels);
    std::ifstream in(whole, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 1000u);
    write("cut.png", bytes.substr(0, bytes.size() / 2));
    write("text.png", "not an image\n");
    for (const std::string name : {"cut.png", "text.png"}) {
        const std::string mtl = write("t.mtl", "newmtl a\n\nmap_Ke " + name + "\n");
        const std::string obj = write("t.obj", std::string("mtllib t.mtl\n") + kSquare + "usemtl a\nf 1/1 2/2 3/3\n");
        const InputError e = loadError(obj);
        const std::string prefix =
            mtl + ":3: map_Ke '" + name + "': cannot read: not a PNG, JPEG or TGA image that stb_image can decode (";
        EXPECT_EQ(std::string(e.what()).rfind(prefix, 0), 0u) << e.what();
        EXPECT_EQ(e.where().line, 3);
    }
}

TEST_F(ObjLoaderTextures, OtherStatementsAndOptionsAreReported) {
    png("wood.png", 1, 1, 3, {255, 255, 255});
    const std::string mtl = write("t.mtl",
                                  "newmtl wood\nmap_Kd -bm 0.5 wood.png\nKd 1.5 0.5 0.25\n"
                                  "map_Ks -s 1 1 1 spec.png\nbump -bm 0.5 bumps.png\nPr 0.5\nPr 0.25\n"
                                  "d 0.5\nillum 7\n");
    const std::string lamp = write("lamp.mtl", "newmtl lamp\nKe 1\n");
    const std::string obj = write("t.obj",
                                  "# Texture statements, values out of range and statements Meshlight ignores.\n"
                                  "mtllib t.mtl lamp.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvp 0.5\nusemtl wood\n"
                                  "s off\nl 1 2\nl 2 3\nf 1 2 3\nusemtl lamp\nf 1 3 2\n");
    const Scene scene = loadObj(obj);
    const std::vector<std::string> expected = {
        mtl + ":3: Kd 1.5 0.5 0.25 exceeds 1 (reflects more than it receives); clamped to 1",
        mtl + ":4: texture map_Ks 'spec.png' is not supported yet; using Ks",
        mtl + ":5: texture bump 'bumps.png' is not supported yet; ignored",
        mtl + ":8: d 0.5 (transparency) is not supported; rendered opaque",
        mtl + ":2: texture option -bm is not supported; ignored",
        mtl + ":6: unknown statement 'Pr' ignored (2 lines)",
        obj + ":6: unknown statement 'vp' ignored",
        obj + ":9: unknown statement 'l' ignored (2 lines)",
        mtl + ":2: texture map_Kd 'wood.png': 1 triangle has no vt (texture coordinates); the mean over the "
              "whole image is used for it",
        mtl + ":2: texture map_Kd 'wood.png' averaged to Kd (1, 0.5, 0.25)",
    };
    EXPECT_EQ(scene.warnings, expected);
    // The clamped Kd is used; the second library (several per mtllib) supplies the lamp.
    ASSERT_EQ(scene.materials.size(), 2u);
    EXPECT_EQ(scene.materials[0].name, "wood");
    EXPECT_EQ(scene.materials[0].kd, Rgb(1.0, 0.5, 0.25));
    EXPECT_EQ(scene.lights.size(), 1u);
}

TEST(ObjLoader, TexturesAreReadThroughTheReader) {
    // Served from memory, at the path relative to the MTL's folder.
    std::vector<unsigned char> png;
    const std::vector<unsigned char> texel = {0, 0, 255};
    stbi_write_png_to_func([](void* out, void* data, int size) {
        auto* bytes = static_cast<std::vector<unsigned char>*>(out);
        bytes->insert(bytes->end(), static_cast<unsigned char*>(data), static_cast<unsigned char*>(data) + size);
    }, &png, 1, 1, 3, texel.data(), 3);
    std::vector<std::string> asked;
    const ObjFileReader read = [&](const std::string& path, std::string& text) {
        asked.push_back(path);
        if (path == "mem/scene.obj") text = "mtllib lib/m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
        else if (path == "mem/lib/m.mtl") text = "newmtl a\nKd 1\nmap_Kd ../tex/blue.png\n";
        else if (path == "mem/tex/blue.png") text.assign(png.begin(), png.end());
        else return false;
        return true;
    };
    const Scene scene = loadObj("mem/scene.obj", {}, read);
    EXPECT_EQ(asked, (std::vector<std::string>{"mem/scene.obj", "mem/lib/m.mtl", "mem/tex/blue.png"}));
    EXPECT_EQ(scene.materials.at(0).kd, Rgb(0.0, 0.0, 1.0));
}

// --- Errors ------------------------------------------------------------------

struct ErrorCase {
    const char* label;
    const char* obj;
    const char* mtl;      // written as case.mtl when not null
    bool inMtl;           // the error is located in case.mtl
    int line;             // 0: the whole file
    const char* keyword;  // must appear in the message
};

class ObjLoaderError : public ::testing::TestWithParam<ErrorCase> {};

constexpr const char* kTriangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

const ErrorCase kErrorCases[] = {
    {"missing_mtl", "mtllib nowhere.mtl\n", nullptr, false, 1, "cannot open material library 'nowhere.mtl'"},
    {"unknown_usemtl", "mtllib case.mtl\nusemtl stone\n", "newmtl wood\n", false, 2, "'stone': unknown material"},
    {"usemtl_without_mtllib", "usemtl stone\n", nullptr, false, 1, "unknown material"},
    {"nan", "v 0 0 0\nv 1 0 0\nv nan 1 0\n", nullptr, false, 3, "coordinate 'nan' is not a finite number"},
    {"inf", "v 0 -inf 0\n", nullptr, false, 1, "coordinate '-inf' is not a finite number"},
    {"overflow", "v 0 1e999 0\n", nullptr, false, 1, "'1e999' is out of the range"},
    {"unparsable", "v 0 0 0\nv 1 2 x\n", nullptr, false, 2, "coordinate 'x' is not a number"},
    {"vertex_values", "v 1 2\n", nullptr, false, 1, "v has 2 values"},
    {"normal_values", "vn 0 1\n", nullptr, false, 1, "vn has 2 values"},
    {"index_out_of_range", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", nullptr, false, 4, "vertex index 4 is out of range (3 vertices"},
    {"negative_out_of_range", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", nullptr, false, 4, "vertex index -4 is out of range"},
    {"index_zero", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", nullptr, false, 4, "index 0 is invalid"},
    {"normal_index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n", nullptr, false, 5, "normal index 2 is out of range"},
    {"texcoord_index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n", nullptr, false, 4, "texture coordinate index 1 is out of range"},
    {"bad_index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3x\n", nullptr, false, 4, "index '3x' is not an integer"},
    {"malformed_corner", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/1/1/1\n", nullptr, false, 4, "'3/1/1/1' is malformed"},
    {"two_vertex_face", "v 0 0 0\nv 1 0 0\nf 1 2\n", nullptr, false, 3, "face has 2 vertices, expected at least 3"},
    {"zero_normal", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nf 1//1 2//1 3//1\n", nullptr, false, 5, "normal 1 (line 4) has zero length"},
    {"no_faces", "v 0 0 0\nv 1 0 0\n", nullptr, false, 0, "no faces"},
    {"all_degenerate", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", nullptr, false, 0, "the only triangle is degenerate"},
    {"light_of_zero_area", "mtllib case.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nusemtl lamp\nf 1 2 4\nf 2 1 4\n",
     "newmtl lamp\nKe 1 1 1\n", false, 8, "light 'lamp' has zero area: all its 2 triangles are degenerate"},
    {"kd_values", "mtllib case.mtl\n", "newmtl a\nKd 0.5 0.5\n", true, 2, "Kd has 2 values, expected 1 or 3"},
    {"ks_values", "mtllib case.mtl\n", "newmtl a\nKs 0.5 0.5 0.5 0.5\n", true, 2, "Ks has 4 values"},
    {"ke_values", "mtllib case.mtl\n", "# lamp\nnewmtl a\nKe 1 1\n", true, 3, "Ke has 2 values"},
    {"ns_values", "mtllib case.mtl\n", "newmtl a\nNs 10 20\n", true, 2, "Ns has 2 values, expected 1"},
    {"ns_negative", "mtllib case.mtl\n", "newmtl a\nNs -1\n", true, 2, "Ns -1 is negative"},
    {"kd_negative", "mtllib case.mtl\n", "newmtl a\nKd 0.5 -0.1 0.5\n", true, 2, "Kd 0.5 -0.1 0.5 has a negative value"},
    {"ke_negative", "mtllib case.mtl\n", "newmtl a\nKe -1\n", true, 2, "Ke -1 -1 -1 has a negative value"},
    {"kd_not_a_number", "mtllib case.mtl\n", "newmtl a\nKd 0.5 abc 0.5\n", true, 2, "Kd value 'abc' is not a number"},
    {"kd_nan", "mtllib case.mtl\n", "newmtl a\n\nKd nan\n", true, 3, "Kd value 'nan' is not a finite number"},
    {"illum_not_integer", "mtllib case.mtl\n", "newmtl a\nillum 2.5\n", true, 2, "illum value '2.5' is not an integer"},
    {"ni_zero", "mtllib case.mtl\n", "newmtl a\nillum 7\nNi 0\n", true, 3, "Ni 0 is not positive"},
    {"ni_negative", "mtllib case.mtl\n", "newmtl a\nNi -1.5\nillum 2\n", true, 2, "Ni -1.5 is not positive"},
    {"ni_nan", "mtllib case.mtl\n", "newmtl a\nNi nan\n", true, 2, "Ni value 'nan' is not a finite number"},
    {"ni_values", "mtllib case.mtl\n", "newmtl a\nNi 1.5 1.5\n", true, 2, "Ni has 2 values, expected 1"},
    {"tf_values", "mtllib case.mtl\n", "newmtl a\nTf 0.5 0.5\n", true, 2, "Tf has 2 values, expected 1 or 3"},
    {"tf_negative", "mtllib case.mtl\n", "newmtl a\nillum 7\nTf 1 -0.5 1\n", true, 3, "Tf 1 -0.5 1 has a negative value"},
    {"before_newmtl", "mtllib case.mtl\n", "Kd 1 1 1\n", true, 1, "Kd before any newmtl"},
    {"newmtl_without_name", "mtllib case.mtl\n", "newmtl\n", true, 1, "newmtl without a name"},
    {"usemtl_without_name", "usemtl   # none\n", nullptr, false, 1, "usemtl without a material name"},
    {"texture_option_unknown", "mtllib case.mtl\n", "newmtl a\nmap_Kd -zz 1 a.png\n", true, 2, "map_Kd: unknown texture option '-zz'"},
    {"texture_option_without_value", "mtllib case.mtl\n", "newmtl a\nmap_Ke -clamp on\n", true, 2, "texture option -clamp has no value before the file name"},
    {"texture_option_number", "mtllib case.mtl\n", "newmtl a\nmap_Kd -s x.png\n", true, 2, "texture option -s has no value before the file name"},
    {"texture_clamp_value", "mtllib case.mtl\n", "newmtl a\nmap_d -clamp yes a.png\n", true, 2, "-clamp takes on or off, not 'yes'"},
    {"texture_without_file", "mtllib case.mtl\n", "newmtl a\nmap_Kd   # none\n", true, 2, "map_Kd without a file name"},
};

TEST_P(ObjLoaderError, SaysFileLineAndWhat) {
    const ErrorCase& c = GetParam();
    const fs::path dir = scratchDir();
    const std::string obj = writeFile(dir, "case.obj", c.obj);
    const std::string mtl = c.mtl ? writeFile(dir, "case.mtl", c.mtl) : std::string();
    const std::string file = c.inMtl ? mtl : obj;
    const std::string prefix = c.line > 0 ? file + ":" + std::to_string(c.line) + ": " : file + ": ";
    try {
        loadObj(obj);
        FAIL() << "no error for " << c.label;
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.rfind(prefix, 0), 0u) << what;
        EXPECT_NE(what.find(c.keyword), std::string::npos) << what;
        EXPECT_EQ(e.where().file, file);
        EXPECT_EQ(e.where().line, c.line);
    }
}

INSTANTIATE_TEST_SUITE_P(Cases, ObjLoaderError, ::testing::ValuesIn(kErrorCases),
                         [](const ::testing::TestParamInfo<ErrorCase>& info) {
                             return std::string(info.param.label);
                         });

// MTL's ray-traced illumination models become smooth layers
// (core/SmoothSpecular.h), whatever the order of the statements of a newmtl.
TEST(ObjLoader, IllumModelsBecomeMirrorsAndGlass) {
    const fs::path dir = scratchDir();
    const std::string mtl = writeFile(dir, "s.mtl",
                                      "newmtl mirror\nillum 3\nKs 0.9 0.8 0.7\n"            // 1-3
                                      "newmtl metal\nKs 0.95\nKd 0.01\nillum 5\n"          // 4-7
                                      "newmtl water\nillum 7\nNi 1.33\nTf 0.5 0.6 0.7\n"   // 8-11
                                      "newmtl glass\nKd 0.01\nillum 7\n"                    // 12-14
                                      "newmtl clear\nillum 4\nTf 1.5 1 1\nNi 1.7\n"        // 15-18
                                      "newmtl chrome\nKs 0.5\nillum 8\n"                    // 19-21
                                      "newmtl shadows\nillum 10\n"                           // 22-23
                                      "newmtl plain\nNi 2\nTf 0.1\nKs 0.3\nillum 2\n");   // 24-28
    std::string obj = "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
    for (const char* name : {"mirror", "metal", "water", "glass", "clear", "chrome", "shadows", "plain"})
        obj += std::string("usemtl ") + name + "\nf 1 2 3\n";
    const Scene scene = loadObj(writeFile(dir, "s.obj", obj));
    auto material = [&](const std::string& name) -> const Material& {
        for (const Material& m : scene.materials)
            if (m.name == name) return m;
        throw std::runtime_error("no material " + name);
    };
    const SmoothSpecular& mirror = material("mirror").smooth;
    EXPECT_EQ(mirror.kind, SpecularKind::Mirror);
    EXPECT_EQ(mirror.reflectance, Rgb(0.9, 0.8, 0.7));  // Ks, given after illum
    EXPECT_FALSE(mirror.schlick);
    const SmoothSpecular& metal = material("metal").smooth;
    EXPECT_EQ(metal.kind, SpecularKind::Mirror);
    EXPECT_EQ(metal.reflectance, Rgb(0.95));
    EXPECT_TRUE(metal.schlick);
    EXPECT_EQ(material("metal").kd, Rgb(0.01));  // the diffuse under the layer stays
    const SmoothSpecular& water = material("water").smooth;
    EXPECT_EQ(water.kind, SpecularKind::Glass);
    EXPECT_EQ(water.ior, 1.33);
    EXPECT_EQ(water.transmission, Rgb(0.5, 0.6, 0.7));
    const SmoothSpecular& glass = material("glass").smooth;  // no Ni, no Tf: the defaults
    EXPECT_EQ(glass.kind, SpecularKind::Glass);
    EXPECT_EQ(glass.ior, 1.5);
    EXPECT_EQ(glass.transmission, Rgb(1.0));
    const SmoothSpecular& clear = material("clear").smooth;  // illum 4: as 7, Tf clamped
    EXPECT_EQ(clear.kind, SpecularKind::Glass);
    EXPECT_EQ(clear.ior, 1.7);
    EXPECT_EQ(clear.transmission, Rgb(1.0));
    const SmoothSpecular& chrome = material("chrome").smooth;  // illum 8: as 3
    EXPECT_EQ(chrome.kind, SpecularKind::Mirror);
    EXPECT_EQ(chrome.reflectance, Rgb(0.5));
    EXPECT_FALSE(material("shadows").specular());
    EXPECT_FALSE(material("plain").specular());  // Ni and Tf alone make no glass
    EXPECT_TRUE(material("plain").glossy());
    EXPECT_FALSE(material("mirror").glossy());   // its Ks is the mirror's, not a Phong lobe's
    const std::vector<std::string> expected = {
        mtl + ":17: Tf 1.5 1 1 exceeds 1 (transmits more than it receives); clamped to 1",
        mtl + ":16: illum 4 is rendered as glass of index Ni and filter Tf (as illum 7)",
        mtl + ":21: illum 8 is rendered as a mirror of reflectance Ks (as illum 3)",
        mtl + ":23: illum 10 is not supported; rendered as Lambert + Phong",
    };
    EXPECT_EQ(scene.warnings, expected);
}

TEST(ObjLoader, MissingFile) {
    const std::string path = scratchDir().string() + "/absent.obj";
    EXPECT_EQ(std::string(loadError(path).what()), path + ": cannot open OBJ file");
}

TEST(ObjLoader, CreaseAngleOutOfRange) {
    ObjOptions options;
    options.creaseAngleDegrees = 200;
    EXPECT_THROW(loadObj(dataFile("loader_cube.obj"), options), InputError);
}

// --- MeshUtil ----------------------------------------------------------------

TEST(MeshUtil, RemoveDegenerateKeepsPerTriangleDataAligned) {
    Mesh m;
    m.name = "strip";
    m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1e-13, 0), Vec3(kInf, 0, 0)};
    m.triangles = {{0, 1, 2}, {0, 1, 3}, {0, 0, 2}, {0, 1, 4}, {2, 1, 0}};
    m.materials = {0, 1, 2, 3, 4};
    m.sourceLines = {10, 11, 12, 13, 14};
    std::vector<size_t> removed;
    // The sliver's area (5e-14) is below (1e-6 · diagonal)² = 2e-12.
    EXPECT_EQ(removeDegenerateTriangles(m, 1e-6, &removed), 3u);
    EXPECT_EQ(removed, (std::vector<size_t>{1, 2, 3}));
    EXPECT_EQ(m.triangles.size(), 2u);
    EXPECT_EQ(m.materials, (std::vector<uint32_t>{0, 4}));
    EXPECT_EQ(m.sourceLines, (std::vector<int>{10, 14}));
    // Scale-relative: the same mesh in units 1000 times smaller loses nothing more.
    for (Vec3& p : m.positions) p *= 1e-3;
    EXPECT_EQ(removeDegenerateTriangles(m, 1e-6), 0u);
}

TEST(MeshUtil, ShadingNormalsWeldByPosition) {
    // Two coplanar triangles given with separate (duplicated) corners weld
    // into one quad of 4 vertices; a third, folded up by 90 degrees along an
    // edge, keeps its own.
    Mesh m;
    m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0),
                   Vec3(0, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0),
                   Vec3(1, 0, 0), Vec3(1, 0, 1), Vec3(1, 1, 0)};
    m.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
    computeShadingNormals(m, 30);
    EXPECT_EQ(m.positions.size(), 7u);
    EXPECT_EQ(m.triangles[0][0], m.triangles[1][0]);
    EXPECT_EQ(m.triangles[0][2], m.triangles[1][1]);
    for (size_t t = 0; t < 3; ++t)
        for (int k = 0; k < 3; ++k)
            expectNear(m.normals[m.triangles[t][k]], glm::normalize(m.areaNormal(t)), 1e-15);
    EXPECT_THROW(computeShadingNormals(m, -1), std::invalid_argument);
}

TEST(MeshUtil, BisectLongEdgesStaysConformingAcrossSeams) {
    // A unit cube whose six faces have corners of their own (a seam along
    // every edge, as flat-shaded files give): bisected to edges of at most
    // 0.3, it stays closed (a T-vertex on a seam would leave an edge used
    // once), keeps its area to rounding (1e-12), each half keeps its face's
    // material, source line and winding, and the new vertices their face's
    // normal and texture coordinates between their edge's ends.
    Mesh m;
    const Vec3 n[6] = {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, 1), Vec3(0, 0, -1)};
    for (uint32_t f = 0; f < 6; ++f) {
        // Two axes u, v with u × v = n, and the face's corner at the origin's side.
        const Vec3 u = std::abs(n[f].x) > 0 ? Vec3(0, 1, 0) : Vec3(1, 0, 0);
        const Vec3 v = glm::cross(n[f], u);
        const Vec3 c = 0.5 * (Vec3(1) + n[f] - u - v);
        const uint32_t b = uint32_t(m.positions.size());
        for (const Vec2& t : {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)}) {
            m.positions.push_back(c + t.x * u + t.y * v);
            m.normals.push_back(n[f]);
            m.texcoords.push_back(t);
        }
        m.triangles.push_back({b, b + 1, b + 2});
        m.triangles.push_back({b, b + 2, b + 3});
        m.materials.insert(m.materials.end(), {f, f});
        m.sourceLines.insert(m.sourceLines.end(), {int(f) + 1, int(f) + 1});
    }
    ASSERT_TRUE(isClosedMesh(m));
    const size_t before = m.positions.size();
    const size_t added = bisectLongEdges(m, 0.3);
    EXPECT_EQ(added, m.positions.size() - before);
    EXPECT_GT(added, 0u);
    EXPECT_TRUE(isClosedMesh(m));
    ASSERT_EQ(m.materials.size(), m.triangles.size());
    ASSERT_EQ(m.sourceLines.size(), m.triangles.size());
    ASSERT_EQ(m.texcoords.size(), m.positions.size());
    double area = 0;
    for (size_t t = 0; t < m.triangles.size(); ++t) {
        area += m.area(t);
        const Vec3 face = n[m.materials[t]];
        EXPECT_GT(glm::dot(glm::normalize(m.areaNormal(t)), face), 1 - 1e-12) << t;
        EXPECT_EQ(m.sourceLines[t], int(m.materials[t]) + 1);
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = m.triangles[t][k], b = m.triangles[t][(k + 1) % 3];
            EXPECT_LE(glm::length(m.positions[b] - m.positions[a]), 0.3 + 1e-12);
            EXPECT_EQ(m.normals[a], face);
            // A corner's texture coordinate is where it lies in its face.
            const Vec3 off = m.positions[a] - 0.5 * (Vec3(1) + face);
            EXPECT_NEAR(glm::length(off), glm::length(m.texcoords[a] - Vec2(0.5)), 1e-12);
        }
    }
    EXPECT_NEAR(area, 6.0, 1e-12);
    EXPECT_THROW(bisectLongEdges(m, 0), std::invalid_argument);
    EXPECT_THROW(bisectLongEdges(m, std::nan("")), std::invalid_argument);
}

// --- Built-in Cornell box ----------------------------------------------------

TEST(CornellBox, Geometry) {
    const Scene scene = makeCornellBox();
    EXPECT_EQ(scene.name, "cornell");
    EXPECT_TRUE(scene.warnings.empty());
    const std::vector<std::string> names = {"floor", "ceiling",    "back",      "left",
                                            "right", "shortBlock", "tallBlock", "light"};
    ASSERT_EQ(scene.meshes.size(), names.size());
    for (size_t i = 0; i < names.size(); ++i) EXPECT_EQ(scene.meshes[i].name, names[i]);
    // 5 walls x 2 + 2 blocks x 5 faces x 2 + light 2.
    EXPECT_EQ(scene.triangleCount(), 32u);
    for (const Mesh& m : scene.meshes) expectFlatNormals(m);

    const Vec3 boxCenter(278, 274.4, 279.6);
    for (size_t i = 0; i < 5; ++i) {
        const Mesh& wall = scene.meshes[i];
        for (size_t t = 0; t < wall.triangles.size(); ++t)
            EXPECT_GT(glm::dot(wall.areaNormal(t), boxCenter - triangleCentroid(wall, t)), 0)
                << wall.name << " triangle " << t;
    }
    for (size_t i = 5; i < 7; ++i) {
        const Mesh& block = scene.meshes[i];
        EXPECT_EQ(block.triangles.size(), 10u);
        Vec3 center(0.0);
        for (const Vec3& p : block.positions) center += p / double(block.positions.size());
        for (size_t t = 0; t < block.triangles.size(); ++t)
            EXPECT_GT(glm::dot(block.areaNormal(t), triangleCentroid(block, t) - center), 0)
                << block.name << " triangle " << t;
    }
    EXPECT_EQ(scene.materials[meshNamed(scene, "left").materials[0]].kd, Rgb(0.63, 0.065, 0.05));
    EXPECT_EQ(scene.materials[meshNamed(scene, "right").materials[0]].kd, Rgb(0.14, 0.45, 0.091));
    EXPECT_EQ(scene.materials[meshNamed(scene, "floor").materials[0]].kd, Rgb(0.725, 0.71, 0.68));
}

TEST(CornellBox, OneLightFacingDown) {
    const Scene scene = makeCornellBox();
    ASSERT_EQ(scene.lights.size(), 1u);
    const Light& light = scene.lights[0];
    EXPECT_EQ(scene.meshes[light.mesh].name, "light");
    EXPECT_NEAR(light.area, 130.0 * 105.0, 1e-9);
    EXPECT_EQ(light.normal, Vec3(0, -1, 0));
    EXPECT_EQ(light.radiance, Rgb(17, 12, 4));
    EXPECT_EQ(scene.materials[light.material].kd, Rgb(0.78));
    EXPECT_TRUE(light.planar);
    expectNear(light.centroid, Vec3(278, 548.3, 279.5), 1e-9);
}

TEST(CornellBox, Camera) {
    const Scene scene = makeCornellBox();
    ASSERT_TRUE(scene.camera.has_value());
    EXPECT_EQ(scene.camera->position, Vec3(278, 273, -800));
    EXPECT_EQ(scene.camera->target, Vec3(278, 273, 0));
    EXPECT_EQ(scene.camera->up, Vec3(0, 1, 0));
    EXPECT_NEAR(scene.camera->fovYDegrees, 39.3077, 1e-4);
    EXPECT_NO_THROW(scene.camera->validate());
}

// --- Public scene --------------------------------------------------------------

TEST(ObjLoader, McGuireCornellBox) {
    const std::string path =
        std::string(MESHLIGHT_SHARED_SCENES) + "/mcguire-cornellbox/CornellBox-Original.obj";
    if (!fs::exists(path)) GTEST_SKIP() << path << " is absent";
    const Scene scene = loadObj(path);
    EXPECT_TRUE(scene.warnings.empty()) << joined(scene.warnings);
    EXPECT_EQ(scene.triangleCount(), 36u);
    ASSERT_EQ(scene.lights.size(), 1u);
    const Light& light = scene.lights[0];
    EXPECT_EQ(light.name, "light");
    EXPECT_EQ(light.radiance, Rgb(17, 12, 4));
    EXPECT_EQ(light.triangles.size(), 2u);
    EXPECT_LT(light.normal.y, -0.99);
}

// The McGuire sphere box: a mirror (illum 5) and a dark glass (illum 7, Ni
// 2.5, Tf 0.1), with their Kd 0.01 under the layer; nothing to warn about.
TEST(ObjLoader, McGuireSpheresAreAMirrorAndGlass) {
    const std::string path = std::string(MESHLIGHT_SHARED_SCENES) + "/mcguire-cornellbox/CornellBox-Sphere.obj";
    if (!fs::exists(path)) GTEST_SKIP() << path << " is absent";
    const Scene scene = loadObj(path);
    EXPECT_TRUE(scene.warnings.empty()) << joined(scene.warnings);
    int mirrors = 0, glasses = 0;
    for (const Material& m : scene.materials) {
        if (m.name == "leftSphere") {
            ++mirrors;
            EXPECT_EQ(m.smooth.kind, SpecularKind::Mirror);
            EXPECT_TRUE(m.smooth.schlick);
            EXPECT_EQ(m.smooth.reflectance, Rgb(0.95));
            EXPECT_EQ(m.kd, Rgb(0.01));
        } else if (m.name == "rightSphere") {
            ++glasses;
            EXPECT_EQ(m.smooth.kind, SpecularKind::Glass);
            EXPECT_EQ(m.smooth.ior, 2.5);
            EXPECT_EQ(m.smooth.transmission, Rgb(0.1));
        } else {
            EXPECT_FALSE(m.specular()) << m.name;
        }
    }
    EXPECT_EQ(mirrors, 1);
    EXPECT_EQ(glasses, 1);
}
