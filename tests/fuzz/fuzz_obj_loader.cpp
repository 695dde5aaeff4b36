// libFuzzer target for the OBJ/MTL loader (loadObj) and what it runs on the
// meshes it reads: degenerate-triangle removal, shading normals, lights.
//
// Input: the OBJ text, optionally followed by a NUL byte and the MTL text.
// Both are served from memory (loadObj's reader overload), the OBJ as
// "fuzz/scene.obj" and the MTL as every library it names; without a NUL,
// no library can be opened. The crease angle (0, 30, 90 or 180 degrees)
// follows the input's length, so every corpus file meets several of them as
// it is mutated.
//
// An InputError is the loader refusing bad input: a normal outcome. Any other
// exception, a broken promise of ObjLoader.h or Scene.h about the scene it
// returns, a crash, a sanitizer report, a leak or a hang is a finding.
#include "core/Error.h"
#include "core/loaders/ObjLoader.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

namespace {

[[noreturn]] void finding(const std::string& what) {
    std::fprintf(stderr, "fuzz_obj_loader: %s\n", what.c_str());
    std::abort();  // libFuzzer saves the input as a crash artifact
}

#define EXPECT(cond, ...) \
    if (!(cond)) finding(ml::concat("broken promise: " #cond " ", ##__VA_ARGS__))

bool finiteRgb(const ml::Rgb& c) { return ml::isFinite(c); }

// What ObjLoader.h and Scene.h promise about a scene loadObj returns.
void checkScene(const ml::Scene& scene, size_t inputLines) {
    using namespace ml;
    EXPECT(!scene.meshes.empty());
    for (const Material& m : scene.materials) {
        EXPECT(finiteRgb(m.kd) && finiteRgb(m.ks) && finiteRgb(m.ke) && std::isfinite(m.ns), m.name);
        // Kd and Ks are clamped to [0, 1]; negative values are errors.
        EXPECT(glm::all(glm::greaterThanEqual(m.kd, Rgb(0.0))) && glm::all(glm::lessThanEqual(m.kd, Rgb(1.0))));
        EXPECT(glm::all(glm::greaterThanEqual(m.ks, Rgb(0.0))) && glm::all(glm::lessThanEqual(m.ks, Rgb(1.0))));
        EXPECT(glm::all(glm::greaterThanEqual(m.ke, Rgb(0.0))) && m.ns >= 0);
    }
    for (const Mesh& mesh : scene.meshes) {
        EXPECT(!mesh.triangles.empty(), mesh.name);
        EXPECT(mesh.normals.size() == mesh.positions.size(), mesh.name);
        EXPECT(mesh.materials.size() == mesh.triangles.size(), mesh.name);
        EXPECT(mesh.sourceLines.size() == mesh.triangles.size(), mesh.name);
        for (size_t v = 0; v < mesh.positions.size(); ++v) {
            EXPECT(isFinite(mesh.positions[v]), mesh.name, " vertex ", v);
            // "unit shading normal per vertex": 1e-9 is a million times the
            // rounding of a normalisation in double.
            const double len = glm::length(mesh.normals[v]);
            EXPECT(std::abs(len - 1) <= 1e-9, mesh.name, " vertex ", v, " normal length ", len);
        }
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            for (int k = 0; k < 3; ++k) EXPECT(mesh.triangles[t][k] < mesh.positions.size(), mesh.name);
            EXPECT(mesh.materials[t] < scene.materials.size(), mesh.name);
            EXPECT(mesh.sourceLines[t] >= 1 && size_t(mesh.sourceLines[t]) <= inputLines, mesh.name);
            // Degenerate triangles are dropped.
            const double area = mesh.area(t);
            EXPECT(area > 0 && std::isfinite(area), mesh.name, " triangle ", t, " area ", area);
        }
    }
    for (const Light& light : scene.lights) {
        EXPECT(light.area > 0 && std::isfinite(light.area), light.name);
        EXPECT(light.mesh < scene.meshes.size() && light.material < scene.materials.size(), light.name);
        EXPECT(scene.materials[light.material].emissive() && finiteRgb(light.radiance), light.name);
        EXPECT(isFinite(light.centroid) && isFinite(light.normal), light.name);
        EXPECT(light.geometry.size() == light.triangles.size() && !light.triangles.empty(), light.name);
        for (uint32_t t : light.triangles) EXPECT(t < scene.meshes[light.mesh].triangles.size(), light.name);
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string_view input(reinterpret_cast<const char*>(data), size);
    const size_t cut = input.find('\0');
    const bool hasMtl = cut != std::string_view::npos;
    const std::string obj(input.substr(0, cut));
    const std::string mtl = hasMtl ? std::string(input.substr(cut + 1)) : std::string();
    const std::string objPath = "fuzz/scene.obj";
    const ml::ObjFileReader read = [&](const std::string& path, std::string& text) {
        if (path == objPath) text = obj;
        else if (hasMtl) text = mtl;
        else return false;
        return true;
    };
    static const double kCreaseAngles[] = {30, 0, 90, 180};
    ml::ObjOptions options;
    options.creaseAngleDegrees = kCreaseAngles[size % 4];
    size_t objLines = 1;
    for (char c : obj) objLines += c == '\n';
    try {
        checkScene(ml::loadObj(objPath, options, read), objLines);
    } catch (const ml::InputError&) {
        // Refused with file:line and a reason: what bad input should get.
    } catch (const std::exception& e) {
        finding(std::string("unexpected exception: ") + e.what());
    } catch (...) {
        finding("unexpected exception of unknown type");
    }
    return 0;
}
