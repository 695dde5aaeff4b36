// glTF import: transforms, winding, materials and their texture means,
// emitters, cameras, .glb, and errors that name the file and the field.
#include "TempDirTest.h"

#include "core/Error.h"
#include "core/loaders/GltfLoader.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_image_write.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

namespace fs = std::filesystem;
using namespace ml;
using json = nlohmann::json;

namespace {

using Gltf = test::TempDirTest;

std::string base64(const std::vector<unsigned char>& bytes) {
    static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < bytes.size(); i += 3) {
        const uint32_t n = (uint32_t(bytes[i]) << 16) | (i + 1 < bytes.size() ? bytes[i + 1] << 8 : 0) |
                           (i + 2 < bytes.size() ? bytes[i + 2] : 0);
        out += digits[n >> 18 & 63];
        out += digits[n >> 12 & 63];
        out += i + 1 < bytes.size() ? digits[n >> 6 & 63] : '=';
        out += i + 2 < bytes.size() ? digits[n & 63] : '=';
    }
    return out;
}

void writeBytes(const std::string& path, const std::vector<unsigned char>& bytes) {
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                                static_cast<std::streamsize>(bytes.size()));
}

// A glTF document and its one buffer, built a piece at a time.
struct GltfFile {
    json doc = {{"asset", {{"version", "2.0"}}}};
    std::vector<unsigned char> bin;

    // Appends raw bytes as a buffer view (4-byte aligned); returns its index.
    int addView(const void* data, size_t size) {
        bin.resize((bin.size() + 3) / 4 * 4);
        const size_t offset = bin.size();
        bin.insert(bin.end(), static_cast<const unsigned char*>(data),
                   static_cast<const unsigned char*>(data) + size);
        doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}});
        return static_cast<int>(doc["bufferViews"].size()) - 1;
    }
    int addAccessor(json accessor) {
        doc["accessors"].push_back(std::move(accessor));
        return static_cast<int>(doc["accessors"].size()) - 1;
    }
    // Float VEC2/VEC3 data: one element per `components` values.
    int addFloats(const std::vector<float>& v, int components) {
        const int view = addView(v.data(), v.size() * sizeof(float));
        return addAccessor({{"bufferView", view},
                            {"componentType", 5126},
                            {"count", v.size() / components},
                            {"type", components == 2 ? "VEC2" : "VEC3"}});
    }
    int addIndices(const std::vector<uint16_t>& v) {
        const int view = addView(v.data(), v.size() * sizeof(uint16_t));
        return addAccessor({{"bufferView", view}, {"componentType", 5123}, {"count", v.size()}, {"type", "SCALAR"}});
    }
    int add(const char* array, json value) {
        doc[array].push_back(std::move(value));
        return static_cast<int>(doc[array].size()) - 1;
    }
    // A mesh of one primitive; returns the mesh index.
    int addMesh(json primitive, const std::string& name = "") {
        json mesh = {{"primitives", json::array({std::move(primitive)})}};
        if (!name.empty()) mesh["name"] = name;
        return add("meshes", std::move(mesh));
    }
    void setRoots(const std::vector<int>& nodes) { doc["scenes"] = json::array({{{"nodes", nodes}}}); }

    std::string writeGltf(const std::string& path) {
        doc["buffers"] = json::array({{{"byteLength", bin.size()},
                                       {"uri", "data:application/octet-stream;base64," + base64(bin)}}});
        std::ofstream(path) << doc.dump(1);
        return path;
    }
    // The buffer as a .bin file next to the .gltf.
    std::string writeGltfAndBin(const std::string& path, const std::string& binName) {
        doc["buffers"] = json::array({{{"byteLength", bin.size()}, {"uri", binName}}});
        writeBytes((fs::path(path).parent_path() / binName).string(), bin);
        std::ofstream(path) << doc.dump(1);
        return path;
    }
    std::string writeGlb(const std::string& path) {
        doc["buffers"] = json::array({{{"byteLength", bin.size()}}});
        std::string text = doc.dump();
        text.resize((text.size() + 3) / 4 * 4, ' ');
        std::vector<unsigned char> data = bin;
        data.resize((data.size() + 3) / 4 * 4, 0);
        std::vector<unsigned char> glb;
        auto u32 = [&](uint32_t v) {
            glb.insert(glb.end(), reinterpret_cast<unsigned char*>(&v), reinterpret_cast<unsigned char*>(&v) + 4);
        };
        auto chars = [&](const char* s) { glb.insert(glb.end(), s, s + 4); };
        chars("glTF");
        u32(2);
        u32(static_cast<uint32_t>(12 + 8 + text.size() + 8 + data.size()));
        u32(static_cast<uint32_t>(text.size()));
        chars("JSON");
        glb.insert(glb.end(), text.begin(), text.end());
        u32(static_cast<uint32_t>(data.size()));
        chars("BIN\0");
        glb.insert(glb.end(), data.begin(), data.end());
        writeBytes(path, glb);
        return path;
    }
};

// The unit quad in z = 0, counter-clockwise seen from +z, with texture
// coordinates over [0, 1]²; `normals` adds NORMAL (0, 0, 1).
json unitQuad(GltfFile& f, bool normals = true, int material = -1) {
    json attributes = {{"POSITION", f.addFloats({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, 3)},
                       {"TEXCOORD_0", f.addFloats({0, 0, 1, 0, 1, 1, 0, 1}, 2)}};
    if (normals) attributes["NORMAL"] = f.addFloats({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, 3);
    json p = {{"attributes", attributes}, {"indices", f.addIndices({0, 1, 2, 0, 2, 3})}};
    if (material >= 0) p["material"] = material;
    return p;
}

// One quad under one node; returns the file ready to write.
GltfFile quadScene(json node = json::object(), json material = nullptr) {
    GltfFile f;
    const int m = material.is_null() ? -1 : f.add("materials", std::move(material));
    node["mesh"] = f.addMesh(unitQuad(f, true, m), "quad");
    f.setRoots({f.add("nodes", std::move(node))});
    return f;
}

std::string joined(const std::vector<std::string>& lines) {
    std::string s;
    for (const std::string& l : lines) s += l + "\n";
    return s;
}

bool hasWarning(const Scene& scene, const std::string& text) {
    for (const std::string& w : scene.warnings)
        if (w.find(text) != std::string::npos) return true;
    return false;
}

void expectClose(const Vec3& actual, const Vec3& expected, double relTol) {
    const double scale = std::max(1.0, glm::length(expected));
    EXPECT_LE(glm::length(actual - expected), relTol * scale) << actual.x << " " << actual.y << " " << actual.z;
}

// The InputError a load throws (fails the test when there is none).
std::string loadError(const std::string& path) {
    try {
        loadGltf(path);
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no InputError for " << path;
    return {};
}

const json kQuarterTurnZ = {0, 0, std::sin(kPi / 4), std::cos(kPi / 4)};

// A PNG of width × height RGBA texels, in memory (for data URIs).
std::vector<unsigned char> pngBytes(int width, int height, const unsigned char* rgba) {
    std::vector<unsigned char> png;
    stbi_write_png_to_func(
        [](void* out, void* data, int size) {
            auto* v = static_cast<std::vector<unsigned char>*>(out);
            v->insert(v->end(), static_cast<unsigned char*>(data), static_cast<unsigned char*>(data) + size);
        },
        &png, width, height, 4, rgba, 4 * width);
    return png;
}

}  // namespace

// --- Transforms and winding -----------------------------------------------------

TEST_F(Gltf, TranslationRotationScalePlaceTheQuad) {
    const Scene scene = loadGltf(
        quadScene({{"translation", {1, 2, 3}}, {"rotation", kQuarterTurnZ}, {"scale", {2, 3, 4}}})
            .writeGltf(path("trs.gltf")));
    ASSERT_EQ(scene.meshes.size(), 1u);
    const Mesh& m = scene.meshes[0];
    EXPECT_EQ(m.name, "quad");
    ASSERT_EQ(m.triangles.size(), 2u);
    // Scale, then a quarter turn about z ((x, y) -> (-y, x)), then translate.
    auto expected = [](double x, double y) { return Vec3(1 - 3 * y, 2 + 2 * x, 3); };
    const Vec3 corners[4] = {expected(0, 0), expected(1, 0), expected(1, 1), expected(0, 1)};
    const glm::uvec3 quad[2] = {{0, 1, 2}, {0, 2, 3}};
    for (int t = 0; t < 2; ++t)
        for (int k = 0; k < 3; ++k) expectClose(m.triangle(t)[k], corners[quad[t][k]], 1e-9);
    for (const Vec3& n : m.normals) expectClose(n, Vec3(0, 0, 1), 1e-12);
    EXPECT_NEAR(m.area(0) + m.area(1), 6, 1e-9);
    EXPECT_TRUE(hasWarning(scene, "no emissive surface and no light: the image will be black")) << joined(scene.warnings);
}

TEST_F(Gltf, MirroringNodeKeepsCounterClockwiseFrontFaces) {
    for (const bool normals : {true, false}) {
        GltfFile f;
        const int mesh = f.addMesh(unitQuad(f, normals));
        f.setRoots({f.add("nodes", {{"mesh", mesh}, {"scale", {-1, 1, 1}}})});
        const Scene scene = loadGltf(f.writeGltf(path("mirror.gltf")));
        ASSERT_EQ(scene.meshes.size(), 1u);
        const Mesh& m = scene.meshes[0];
        for (size_t t = 0; t < m.triangles.size(); ++t) {
            EXPECT_GT(m.areaNormal(t).z, 0) << "triangle " << t << (normals ? " with" : " without") << " NORMAL";
            EXPECT_LT(m.triangle(t)[1].x + m.triangle(t)[2].x, 0);  // mirrored to x <= 0
        }
        for (const Vec3& n : m.normals) expectClose(n, Vec3(0, 0, 1), 1e-12);
    }
}

TEST_F(Gltf, ParentAndChildTransformsCompose) {
    GltfFile f;
    const int mesh = f.addMesh(unitQuad(f));
    const int child = f.add("nodes", {{"mesh", mesh}, {"translation", {0, 1, 0}}});
    // The parent as a column-major matrix: scale 2, then translate (10, 0, 0).
    const int parent = f.add("nodes", {{"children", {child}},
                                       {"matrix", {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 10, 0, 0, 1}}});
    f.setRoots({parent});
    const Scene scene = loadGltf(f.writeGltf(path("tree.gltf")));
    ASSERT_EQ(scene.meshes.size(), 1u);
    expectClose(scene.meshes[0].triangle(0)[2], Vec3(12, 4, 0), 1e-12);  // corner (1, 1, 0)
    expectClose(scene.meshes[0].triangle(0)[0], Vec3(10, 2, 0), 1e-12);  // corner (0, 0, 0)
}

TEST_F(Gltf, StripsAndFansBecomeFrontFacingTriangles) {
    GltfFile f;
    const int positions = f.addFloats({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, 3);
    // Strip 0 1 3 2 and fan 0 1 2 3 both cover the quad counter-clockwise.
    const int strip = f.addMesh({{"attributes", {{"POSITION", positions}}}, {"indices", f.addIndices({0, 1, 3, 2})}, {"mode", 5}});
    const int fan = f.addMesh({{"attributes", {{"POSITION", positions}}}, {"mode", 6}});
    const int points = f.addMesh({{"attributes", {{"POSITION", positions}}}, {"mode", 0}});
    f.setRoots({f.add("nodes", {{"mesh", strip}}), f.add("nodes", {{"mesh", fan}}), f.add("nodes", {{"mesh", points}})});
    const Scene scene = loadGltf(f.writeGltf(path("modes.gltf")));
    ASSERT_EQ(scene.meshes.size(), 2u);
    for (const Mesh& m : scene.meshes) {
        ASSERT_EQ(m.triangles.size(), 2u);
        EXPECT_NEAR(m.area(0) + m.area(1), 1, 1e-12);
        for (size_t t = 0; t < 2; ++t) EXPECT_GT(m.areaNormal(t).z, 0);
    }
    EXPECT_TRUE(hasWarning(scene, "1 primitive of points or lines skipped (first meshes[2].primitives[0])"))
        << joined(scene.warnings);
}

TEST_F(Gltf, SparseAccessorReplacesVertices) {
    GltfFile f;
    // A triangle whose third corner is (0, 0, 0) in the buffer, moved by the sparse part.
    const int view = f.addView(std::vector<float>{0, 0, 0, 1, 0, 0, 0, 0, 0}.data(), 36);
    const uint8_t index = 2;
    const float corner[3] = {0, 2, 0};
    const int indices = f.addView(&index, 1), values = f.addView(corner, sizeof corner);
    const int positions = f.addAccessor(
        {{"bufferView", view}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"},
         {"sparse", {{"count", 1}, {"indices", {{"bufferView", indices}, {"componentType", 5121}}},
                     {"values", {{"bufferView", values}}}}}});
    f.setRoots({f.add("nodes", {{"mesh", f.addMesh({{"attributes", {{"POSITION", positions}}}})}})});
    const Scene scene = loadGltf(f.writeGltf(path("sparse.gltf")));
    ASSERT_EQ(scene.triangleCount(), 1u);
    EXPECT_NEAR(scene.meshes[0].area(0), 1, 1e-12);
}

// --- Materials and emitters --------------------------------------------------------

TEST_F(Gltf, BaseColorFactorBecomesKd) {
    const Scene scene = loadGltf(
        quadScene({}, {{"name", "paint"},
                       {"pbrMetallicRoughness", {{"baseColorFactor", {0.2, 0.4, 0.6, 1}}, {"metallicFactor", 0}}}})
            .writeGltf(path("kd.gltf")));
    ASSERT_EQ(scene.materials.size(), 1u);
    EXPECT_EQ(scene.materials[0].name, "paint");
    EXPECT_EQ(scene.materials[0].kd, Rgb(0.2, 0.4, 0.6));
    EXPECT_EQ(scene.materials[0].ke, Rgb(0.0));
    EXPECT_EQ(scene.warnings.size(), 1u) << joined(scene.warnings);  // no emissive surface
}

TEST_F(Gltf, MissingMaterialIsDefaultAndMetalIsDiffuseWithAWarning) {
    GltfFile f;
    const int metal = f.add("materials", {{"name", "steel"}, {"extensions", {{"KHR_materials_clearcoat", json::object()}}}});
    const int plain = f.addMesh(unitQuad(f)), shiny = f.addMesh(unitQuad(f, true, metal));
    f.setRoots({f.add("nodes", {{"mesh", plain}}), f.add("nodes", {{"mesh", shiny}, {"translation", {0, 0, 1}}})});
    const Scene scene = loadGltf(f.writeGltf(path("metal.gltf")));
    ASSERT_EQ(scene.materials.size(), 2u);
    EXPECT_EQ(scene.materials[0].name, "default");
    EXPECT_EQ(scene.materials[0].kd, Rgb(0.8));
    EXPECT_EQ(scene.materials[1].kd, Rgb(1.0));  // baseColorFactor's default
    EXPECT_TRUE(hasWarning(scene, "materials[0] 'steel': metallic 1 (roughness 1), KHR_materials_clearcoat not "
                                  "rendered; rendered as diffuse"))
        << joined(scene.warnings);
}

// Smooth metals become mirrors and transmitting materials glass
// (core/SmoothSpecular.h); what those cannot show is reported once per material.
TEST_F(Gltf, SmoothMetalIsAMirrorAndTransmissionIsGlass) {
    GltfFile f;
    const int chrome = f.add("materials", {{"name", "chrome"},
                                           {"pbrMetallicRoughness",
                                            {{"baseColorFactor", {0.9, 0.8, 0.7, 1}},
                                             {"metallicFactor", 1},
                                             {"roughnessFactor", 0.05}}}});
    const int brushed = f.add("materials", {{"name", "brushed"},
                                            {"pbrMetallicRoughness", {{"metallicFactor", 1}, {"roughnessFactor", 0.3}}}});
    const int water = f.add("materials", {{"name", "water"},
                                          {"pbrMetallicRoughness",
                                           {{"baseColorFactor", {0.5, 1, 1, 1}},
                                            {"metallicFactor", 0},
                                            {"roughnessFactor", 0}}},
                                          {"extensions",
                                           {{"KHR_materials_transmission", {{"transmissionFactor", 0.8}}},
                                            {"KHR_materials_ior", {{"ior", 1.33}}}}}});
    const int frosted = f.add("materials", {{"name", "frosted"},
                                            {"pbrMetallicRoughness", {{"metallicFactor", 0}, {"roughnessFactor", 0.5}}},
                                            {"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 1}}}}}});
    const int opaque = f.add("materials", {{"name", "opaque"},
                                           {"pbrMetallicRoughness", {{"metallicFactor", 0}}},
                                           {"extensions", {{"KHR_materials_transmission", json::object()}}}});
    std::vector<int> nodes;
    for (int m : {chrome, brushed, water, frosted, opaque})
        nodes.push_back(f.add("nodes", {{"mesh", f.addMesh(unitQuad(f, true, m))}, {"translation", {0, 0, m}}}));
    f.setRoots(nodes);
    const Scene scene = loadGltf(f.writeGltf(path("smooth.gltf")));
    ASSERT_EQ(scene.materials.size(), 5u);
    const Material& c = scene.materials[0];
    EXPECT_EQ(c.smooth.kind, SpecularKind::Mirror);
    EXPECT_EQ(c.smooth.reflectance, Rgb(0.9, 0.8, 0.7));  // the base colour is a metal's F0
    EXPECT_TRUE(c.smooth.schlick);
    EXPECT_EQ(c.kd, Rgb(0.0));  // a metal scatters nothing diffusely
    EXPECT_FALSE(scene.materials[1].specular());  // rough: still reported, drawn diffuse
    const Material& w = scene.materials[2];
    EXPECT_EQ(w.smooth.kind, SpecularKind::Glass);
    EXPECT_EQ(w.smooth.ior, 1.33);
    EXPECT_NEAR(w.smooth.transmission.r, 0.4, 1e-15);  // transmissionFactor × base colour
    EXPECT_NEAR(w.smooth.transmission.g, 0.8, 1e-15);
    EXPECT_NEAR(w.kd.r, 0.1, 1e-15);  // base colour × (1 − transmissionFactor)
    EXPECT_NEAR(w.kd.g, 0.2, 1e-15);
    const Material& fr = scene.materials[3];
    EXPECT_EQ(fr.smooth.kind, SpecularKind::Glass);
    EXPECT_EQ(fr.smooth.ior, 1.5);  // KHR_materials_ior's default
    EXPECT_EQ(fr.smooth.transmission, Rgb(1.0));
    EXPECT_EQ(fr.kd, Rgb(0.0));
    EXPECT_FALSE(scene.materials[4].specular());  // transmissionFactor's default is 0
    EXPECT_FALSE(hasWarning(scene, "'chrome'")) << joined(scene.warnings);
    EXPECT_FALSE(hasWarning(scene, "'water'")) << joined(scene.warnings);
    EXPECT_TRUE(hasWarning(scene, "materials[1] 'brushed': metallic 1 (roughness 0.3) not rendered; rendered as "
                                  "diffuse"))
        << joined(scene.warnings);
    EXPECT_TRUE(hasWarning(scene, "materials[3] 'frosted': roughness 0.5 of transmission (smooth glass) not "
                                  "rendered; rendered as glass"))
        << joined(scene.warnings);
}

TEST_F(Gltf, BadTransmissionOrIorIsAnInputError) {
    auto glass = [&](json extensions, const std::string& name) {
        return quadScene({}, {{"name", "glass"}, {"extensions", std::move(extensions)}}).writeGltf(path(name));
    };
    EXPECT_NE(loadError(glass({{"KHR_materials_transmission", {{"transmissionFactor", 1.5}}}}, "factor.gltf"))
                  .find("materials[0].extensions.KHR_materials_transmission.transmissionFactor is not a number in "
                        "[0, 1]"),
              std::string::npos);
    EXPECT_NE(loadError(glass({{"KHR_materials_transmission", {{"transmissionFactor", 1}}},
                               {"KHR_materials_ior", {{"ior", -1}}}},
                              "ior.gltf"))
                  .find("materials[0].extensions.KHR_materials_ior.ior is not a positive number"),
              std::string::npos);
}

TEST_F(Gltf, EmissiveStrengthScalesKeAndMakesOneLight) {
    const Scene scene = loadGltf(
        quadScene({{"scale", {2, 3, 1}}},
                  {{"name", "lamp"},
                   {"emissiveFactor", {1, 0.5, 0.25}},
                   {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 5}}}}}})
            .writeGltf(path("lamp.gltf")));
    ASSERT_EQ(scene.materials.size(), 1u);
    EXPECT_EQ(scene.materials[0].ke, Rgb(5, 2.5, 1.25));
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_EQ(scene.lights[0].name, "lamp");
    EXPECT_NEAR(scene.lights[0].area, 6, 1e-12);
    expectClose(scene.lights[0].normal, Vec3(0, 0, 1), 1e-12);
    EXPECT_FALSE(hasWarning(scene, "no emissive surface")) << joined(scene.warnings);

    GltfOptions brighter;
    brighter.emissionScale = 2;
    EXPECT_EQ(loadGltf(path("lamp.gltf"), brighter).lights[0].radiance, Rgb(10, 5, 2.5));
}

TEST_F(Gltf, DoubleSidedEmitterEmitsBothWays) {
    const Scene scene = loadGltf(
        quadScene({}, {{"name", "panel"}, {"emissiveFactor", {1, 1, 1}}, {"doubleSided", true}})
            .writeGltf(path("panel.gltf")));
    ASSERT_EQ(scene.meshes.size(), 2u);
    EXPECT_EQ(scene.meshes[1].name, "quad (back)");
    ASSERT_EQ(scene.lights.size(), 2u);
    for (const Light& l : scene.lights) {
        EXPECT_NEAR(l.area, 1, 1e-12);
        EXPECT_TRUE(l.planar);
        EXPECT_EQ(l.radiance, Rgb(1.0));
    }
    expectClose(scene.lights[0].normal, Vec3(0, 0, 1), 1e-12);
    expectClose(scene.lights[1].normal, Vec3(0, 0, -1), 1e-12);
    for (const Vec3& n : scene.meshes[1].normals) expectClose(n, Vec3(0, 0, -1), 1e-12);
}

TEST_F(Gltf, MaskedMaterialBelowCutoffIsRemoved) {
    GltfFile f;
    const int hidden = f.add("materials", {{"name", "hidden"}, {"alphaMode", "MASK"},
                                           {"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 0.2}}}}});
    const int a = f.addMesh(unitQuad(f)), b = f.addMesh(unitQuad(f, true, hidden));
    f.setRoots({f.add("nodes", {{"mesh", a}}), f.add("nodes", {{"mesh", b}})});
    const Scene scene = loadGltf(f.writeGltf(path("mask.gltf")));
    EXPECT_EQ(scene.triangleCount(), 2u);
    EXPECT_TRUE(hasWarning(scene, "materials[0] 'hidden': baseColorFactor alpha 0.2 is below alphaCutoff 0.5 "
                                  "(alphaMode MASK): its 2 triangles are removed"))
        << joined(scene.warnings);
}

TEST_F(Gltf, SrgbTextureMeanBecomesKd) {
    // 2 x 2 texels: red, green, blue and sRGB grey 128 (linear 0.2158605).
    const unsigned char texels[16] = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 128, 128, 128, 255};
    const std::vector<unsigned char> png = pngBytes(2, 2, texels);
    GltfFile f = quadScene({}, {{"name", "tiles"},
                                {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0}}}});
    f.add("images", {{"uri", "data:image/png;base64," + base64(png)}, {"name", "tiles.png"}});
    f.add("samplers", {{"wrapS", 10497}, {"wrapT", 10497}});
    f.add("textures", {{"source", 0}, {"sampler", 0}});
    const Scene scene = loadGltf(f.writeGltf(path("texture.gltf")));
    const double grey = std::pow((128 / 255.0 + 0.055) / 1.055, 2.4);
    const Rgb expected = (Rgb(1, 0, 0) + Rgb(0, 1, 0) + Rgb(0, 0, 1) + Rgb(grey)) / 4.0;
    ASSERT_EQ(scene.materials.size(), 1u);
    expectClose(scene.materials[0].kd, expected, 2e-3);
    EXPECT_TRUE(hasWarning(scene, "materials[0] 'tiles': texture tiles.png averaged to Kd (0.304, 0.304, 0.304)"))
        << joined(scene.warnings);
}

TEST_F(Gltf, MaskedAlphaTextureIsACutOutPerPixel) {
    // 2 x 1 texels, opaque | transparent, magnified to the nearest: the
    // material keeps the texture as its cut-out (factor alpha 0.9 × the
    // texel's alpha against the cut-off 0.6), its triangles all kept.
    const unsigned char texels[8] = {200, 100, 50, 255, 200, 100, 50, 0};
    const std::vector<unsigned char> png = pngBytes(2, 1, texels);
    GltfFile f = quadScene({}, {{"name", "leaf"}, {"alphaMode", "MASK"}, {"alphaCutoff", 0.6},
                                {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}},
                                                          {"baseColorFactor", {1, 1, 1, 0.9}}, {"metallicFactor", 0}}}});
    f.add("images", {{"uri", "data:image/png;base64," + base64(png)}});
    f.add("samplers", {{"magFilter", 9728}});
    f.add("textures", {{"source", 0}, {"sampler", 0}});
    const Scene scene = loadGltf(f.writeGltf(path("leaf.gltf")));
    ASSERT_EQ(scene.materials.size(), 1u);
    const Material& m = scene.materials[0];
    ASSERT_TRUE(bool(m.alphaMap));
    EXPECT_EQ(m.alphaCutoff, 0.6);
    EXPECT_FALSE(m.cutAway(Vec2(0.25, 0.5)));  // 0.9 × 1 >= 0.6
    EXPECT_TRUE(m.cutAway(Vec2(0.75, 0.5)));   // 0.9 × 0 < 0.6
    EXPECT_EQ(scene.triangleCount(), 2u);
    EXPECT_FALSE(hasWarning(scene, "materials[0] 'leaf': alpha texture ignored, rendered opaque"));
}

TEST_F(Gltf, AnImageStbFailsWithoutAReasonIsAnError) {
    // fuzz_gltf_loader's first finding: a data-URI image stb_image fails on
    // without saying why was taken as decoded, a texture of no texels whose
    // lookups then looped for ever.
    const std::string finding = MESHLIGHT_TEST_DATA "/../fuzz/corpus_gltf/finding_image_without_reason.gltf";
    EXPECT_NE(loadError(finding).find("cannot decode"), std::string::npos) << loadError(finding);
}

// --- Cameras and lights -------------------------------------------------------------

TEST_F(Gltf, FirstPerspectiveCameraBecomesTheScenesCamera) {
    GltfFile f = quadScene();
    f.add("cameras", {{"type", "orthographic"}, {"orthographic", {{"xmag", 1}, {"ymag", 1}, {"zfar", 10}, {"znear", 0.1}}}});
    f.add("cameras", {{"type", "perspective"}, {"perspective", {{"yfov", 0.5}, {"znear", 0.1}}}});
    // A quarter turn about +y takes the camera's -z to -x.
    const json turnY = {0, std::sin(kPi / 4), 0, std::cos(kPi / 4)};
    const int ortho = f.add("nodes", {{"camera", 0}});
    const int first = f.add("nodes", {{"camera", 1}, {"translation", {1, 2, 3}}, {"rotation", turnY}});
    const int second = f.add("nodes", {{"camera", 1}});
    f.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    f.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array({{{"name", "bulb"}, {"type", "point"}}});
    const int light = f.add("nodes", {{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    f.setRoots({0, ortho, first, second, light});
    const Scene scene = loadGltf(f.writeGltf(path("camera.gltf")));
    ASSERT_TRUE(scene.camera.has_value());
    expectClose(scene.camera->position, Vec3(1, 2, 3), 1e-12);
    expectClose(glm::normalize(scene.camera->target - scene.camera->position), Vec3(-1, 0, 0), 1e-12);
    expectClose(scene.camera->up, Vec3(0, 1, 0), 1e-12);
    EXPECT_NEAR(scene.camera->fovYDegrees, 0.5 * 180 / kPi, 1e-12);
    EXPECT_NO_THROW(scene.camera->validate());
    EXPECT_TRUE(hasWarning(scene, "cameras[0] '': orthographic camera not supported; ignored")) << joined(scene.warnings);
    ASSERT_EQ(scene.lights.size(), 1u);  // the point light at the origin
    EXPECT_EQ(scene.lights[0].kind, LightKind::Point);
    EXPECT_EQ(scene.lights[0].name, "bulb");
}

// KHR_lights_punctual: placed by the node's world transform, shining along
// its −Z; candela (lux for directional) to W·sr⁻¹ (W·m⁻²) by 179 lm/W.
TEST_F(Gltf, PunctualLightsArePlacedAimedAndConvertedFromCandela) {
    GltfFile f = quadScene();
    f.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    f.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"name", "bulb"}, {"type", "point"}, {"intensity", 1790}, {"color", {1, 0.5, 0.25}}},
         {{"name", "spot"}, {"type", "spot"}, {"intensity", 179}, {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.5}}}},
         {{"name", "sun"}, {"type", "directional"}, {"intensity", 358}, {"range", 5}}});
    // −90° about x takes a node's −z to −y: aimed down.
    const json downX = {-std::sin(kPi / 4), 0, 0, std::cos(kPi / 4)};  // −90° about x: −z -> −y
    const int parent = f.add("nodes", {{"translation", {0, 1, 0}}, {"children", json::array()}});
    const int bulb = f.add("nodes", {{"name", "Panel.001"}, {"translation", {0.5, 1, 0.5}},
                                     {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    const int spot = f.add("nodes", {{"name", "Panel.002"}, {"rotation", downX},
                                     {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
    const int sun = f.add("nodes", {{"rotation", downX}, {"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}});
    f.doc["nodes"][parent]["children"] = {bulb, spot};
    f.setRoots({0, parent, sun});
    const Scene scene = loadGltf(f.writeGltf(path("lights.gltf")));
    ASSERT_EQ(scene.lights.size(), 3u);
    const Light& b = scene.lights[0];
    EXPECT_EQ(b.kind, LightKind::Point);
    EXPECT_EQ(b.name, "Panel.001");
    EXPECT_EQ(b.group, "Panel");
    expectClose(b.emission.position, Vec3(0.5, 2, 0.5), 1e-12);
    expectClose(b.emission.intensity, Vec3(10, 5, 2.5), 1e-12);  // 1790 cd × colour / 179
    EXPECT_EQ(b.emission.profile.shape, IntensityProfile::Shape::Isotropic);
    const Light& s = scene.lights[1];
    EXPECT_EQ(s.group, "Panel");
    expectClose(s.emission.position, Vec3(0, 1, 0), 1e-12);
    expectClose(s.emission.axis, Vec3(0, -1, 0), 1e-12);
    EXPECT_EQ(s.emission.profile.shape, IntensityProfile::Shape::Spot);
    EXPECT_NEAR(s.emission.profile.cosInner, std::cos(0.2), 1e-15);
    EXPECT_NEAR(s.emission.profile.cosOuter, std::cos(0.5), 1e-15);
    expectClose(s.emission.intensity, Vec3(1, 1, 1), 1e-12);
    const Light& d = scene.lights[2];
    EXPECT_EQ(d.kind, LightKind::Directional);
    expectClose(d.emission.axis, Vec3(0, -1, 0), 1e-12);
    expectClose(d.emission.intensity, Vec3(2, 2, 2), 1e-12);  // 358 lx / 179
    EXPECT_TRUE(hasWarning(scene, "range 5 m ignored")) << joined(scene.warnings);
    EXPECT_EQ(scene.metresPerUnit, 1.0);
}

// A photometric luminaire on a node's extras, placed like a glTF light.
TEST_F(Gltf, LuminaireOnANodesExtras) {
    std::ofstream(path("iso.ies")) << "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 10\n0 180\n0\n100 100\n";
    GltfFile f = quadScene();
    const json downX = {-std::sin(kPi / 4), 0, 0, std::cos(kPi / 4)};
    const int lum = f.add("nodes", {{"name", "Downlight.004"}, {"translation", {1, 3, 1}}, {"rotation", downX},
                                    {"extras", {{"photometry", "iso.ies"}, {"multiplier", 2}}}});
    f.setRoots({0, lum});
    const Scene scene = loadGltf(f.writeGltf(path("lum.gltf")));
    ASSERT_EQ(scene.lights.size(), 1u);
    const Light& l = scene.lights[0];
    EXPECT_EQ(l.name, "Downlight.004");
    EXPECT_EQ(l.group, "Downlight");
    EXPECT_EQ(l.emission.profile.shape, IntensityProfile::Shape::Table);
    expectClose(l.emission.position, Vec3(1, 3, 1), 1e-12);
    expectClose(l.emission.axis, Vec3(0, -1, 0), 1e-12);
    EXPECT_NEAR(l.emission.intensityToward(Vec3(0, -1, 0)).g * 179, 200, 1e-9);  // 100 cd × 2
    // A missing file names itself.
    GltfFile g = quadScene();
    const int bad = g.add("nodes", {{"extras", {{"photometry", "none.ies"}}}});
    g.setRoots({0, bad});
    EXPECT_NE(loadError(g.writeGltf(path("bad.gltf"))).find("none.ies"), std::string::npos);
}

TEST_F(Gltf, BadPunctualLightsNameTheField) {
    auto withLight = [&](json light, const std::string& name) {
        GltfFile f = quadScene();
        f.doc["extensionsUsed"] = {"KHR_lights_punctual"};
        f.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array({std::move(light)});
        const int node = f.add("nodes", {{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
        f.setRoots({0, node});
        return f.writeGltf(path(name));
    };
    EXPECT_NE(loadError(withLight({{"type", "area"}}, "type.gltf")).find("KHR_lights_punctual.lights[0].type 'area' is not"),
              std::string::npos);
    EXPECT_NE(loadError(withLight({{"type", "spot"}, {"spot", {{"innerConeAngle", 0.6}, {"outerConeAngle", 0.5}}}}, "cone.gltf"))
                  .find("KHR_lights_punctual.lights[0].spot: cone angles"),
              std::string::npos);
    EXPECT_NE(loadError(withLight({{"type", "point"}, {"intensity", -1}}, "negative.gltf")).find(".intensity -1 is not"),
              std::string::npos);
    EXPECT_NE(loadError(withLight({{"type", "point"}, {"color", {1, 1}}}, "colour.gltf")).find(".color has 2 values"),
              std::string::npos);
}

// --- .glb ---------------------------------------------------------------------------

TEST_F(Gltf, GlbLoadsLikeGltfWithBin) {
    GltfFile f = quadScene({{"rotation", kQuarterTurnZ}}, {{"name", "lamp"}, {"emissiveFactor", {3, 2, 1}}});
    const Scene a = loadGltf(f.writeGltfAndBin(path("scene.gltf"), "scene.bin"));
    const Scene b = loadGltf(f.writeGlb(path("scene.glb")));
    ASSERT_EQ(a.meshes.size(), b.meshes.size());
    for (size_t i = 0; i < a.meshes.size(); ++i) {
        EXPECT_EQ(a.meshes[i].positions, b.meshes[i].positions);
        EXPECT_EQ(a.meshes[i].normals, b.meshes[i].normals);
        EXPECT_EQ(a.meshes[i].triangles, b.meshes[i].triangles);
        EXPECT_EQ(a.meshes[i].materials, b.meshes[i].materials);
    }
    ASSERT_EQ(a.lights.size(), 1u);
    ASSERT_EQ(b.lights.size(), 1u);
    EXPECT_EQ(a.lights[0].radiance, b.lights[0].radiance);
    EXPECT_EQ(a.lights[0].area, b.lights[0].area);
    EXPECT_EQ(a.materials[0].kd, b.materials[0].kd);
}

// --- Errors --------------------------------------------------------------------------

TEST_F(Gltf, BadJsonIsAnInputError) {
    const std::string message = loadError(write("bad.gltf", "{ \"asset\": { \"version\": \"2.0\" }, "));
    EXPECT_NE(message.find("bad.gltf"), std::string::npos) << message;
    EXPECT_NE(message.find("JSON"), std::string::npos) << message;
}

TEST_F(Gltf, MissingBinIsNamed) {
    GltfFile f = quadScene();
    f.writeGltfAndBin(path("scene.gltf"), "geometry.bin");
    fs::remove(path("geometry.bin"));
    const std::string message = loadError(path("scene.gltf"));
    EXPECT_NE(message.find("scene.gltf: buffers[0].uri: file 'geometry.bin' not found"), std::string::npos) << message;
}

TEST_F(Gltf, IndexOutOfRangeIsNamed) {
    GltfFile f;
    const int positions = f.addFloats({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, 3);
    f.setRoots({f.add("nodes", {{"mesh", f.addMesh({{"attributes", {{"POSITION", positions}}},
                                                     {"indices", f.addIndices({0, 1, 9})}})}})});
    const std::string message = loadError(f.writeGltf(path("index.gltf")));
    EXPECT_NE(message.find("index.gltf: meshes[0].primitives[0].indices (accessors[1]): index 9 at position 2 "
                           "is out of range (4 vertices)"),
              std::string::npos)
        << message;
}

TEST_F(Gltf, UnknownRequiredExtensionIsNamed) {
    GltfFile f = quadScene();
    f.doc["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    f.doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    const std::string message = loadError(f.writeGltf(path("draco.gltf")));
    EXPECT_NE(message.find("draco.gltf: extensionsRequired: 'KHR_draco_mesh_compression' is not supported"),
              std::string::npos)
        << message;
}

TEST_F(Gltf, MalformedFilesAreInputErrors) {
    struct Case {
        const char* name;
        std::function<void(GltfFile&)> spoil;
        const char* expected;
    };
    const Case cases[] = {
        {"range", [](GltfFile& f) { f.doc["accessors"][0]["count"] = 100; },
         "meshes[0].primitives[0].attributes.POSITION (accessors[0]): 100 elements of 12 bytes every 12 bytes "
         "from byteOffset 0 do not fit in bufferViews[0] (48 bytes)"},
        {"view", [](GltfFile& f) { f.doc["bufferViews"][0]["byteLength"] = 4096; },
         "bufferViews[0]: bytes 0 to 4096 are outside buffers[0]"},
        {"nan", [](GltfFile& f) { float nan = NAN; std::memcpy(f.bin.data() + 4, &nan, 4); },
         "(accessors[0]): element 0 is not finite"},
        {"cycle", [](GltfFile& f) { f.doc["nodes"][0]["children"] = {0}; },
         "nodes[0].children: nodes[0] is reached a second time"},
        {"mesh", [](GltfFile& f) { f.doc["nodes"][0]["mesh"] = 7; },
         "nodes[0].mesh: meshes[7] does not exist (the file has 1)"},
        {"type", [](GltfFile& f) { f.doc["accessors"][0]["componentType"] = 5123; },
         "componentType 5123 (unsigned short) is not allowed here (float)"},
        {"image", [](GltfFile& f) { f.add("images", {{"uri", "gone.png"}}); },
         "images[0].uri: file 'gone.png' not found"},
        {"empty", [](GltfFile& f) { f.doc["nodes"][0].erase("mesh"); }, "no triangles in the scene's nodes"},
    };
    for (const Case& c : cases) {
        GltfFile f = quadScene();
        c.spoil(f);
        const std::string file = std::string(c.name) + ".gltf";
        const std::string message = loadError(f.writeGltf(path(file)));
        EXPECT_NE(message.find(file + ": "), std::string::npos) << message;
        EXPECT_NE(message.find(c.expected), std::string::npos) << c.name << ": " << message;
    }
    EXPECT_NE(loadError(path("absent.gltf")).find("absent.gltf: cannot open glTF file"), std::string::npos);
}

// --- A public scene --------------------------------------------------------------------

TEST(GltfPublicScene, BackRooms) {
    const std::string path = std::string(MESHLIGHT_SHARED_SCENES) + "/backrooms-gltf/scene.gltf";
    if (!fs::exists(path)) GTEST_SKIP() << path << " is absent";
    const Scene scene = loadGltf(path);
    EXPECT_EQ(scene.triangleCount(), 9185u) << joined(scene.warnings);
    EXPECT_GE(scene.lights.size(), 1u);
}
