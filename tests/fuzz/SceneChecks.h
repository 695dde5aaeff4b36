// What every scene loader promises about the Scene it returns (Scene.h,
// Texture.h), checked by the loaders' fuzz targets: a broken promise is a
// finding, as a crash is. Each target adds what its own format promises.
#pragma once

#include "core/Error.h"
#include "core/Scene.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace ml::fuzz {

inline bool finite2(const Vec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }

// Reports `what` and aborts: libFuzzer saves the input as a crash artifact.
[[noreturn]] inline void finding(const char* target, const std::string& what) {
    std::fprintf(stderr, "%s: %s\n", target, what.c_str());
    std::abort();
}

#define ML_FUZZ_EXPECT(target, cond, ...) \
    if (!(cond)) ::ml::fuzz::finding(target, ::ml::concat("broken promise: " #cond " ", ##__VA_ARGS__))

// A texture map's image, when it has one, is decoded: a positive size and
// four bytes a texel; its factor and transform are finite.
inline void checkTextureMap(const char* target, const TextureMap& map, const std::string& material) {
    if (!map) return;
    const Texture& t = *map.image;
    ML_FUZZ_EXPECT(target, t.width > 0 && t.height > 0, material, " ", t.name);
    ML_FUZZ_EXPECT(target, t.rgba.size() == size_t(4) * size_t(t.width) * size_t(t.height), material, " ", t.name);
    ML_FUZZ_EXPECT(target, t.minAlpha >= 0 && t.minAlpha <= 1, material);
    ML_FUZZ_EXPECT(target, isFinite(map.factor) && finite2(map.scale) && finite2(map.offset), material);
}

// Scene.h's promises: finite materials (Kd and Ks in [0, 1], Ke >= 0),
// meshes with unit normals, consistent per-triangle and per-vertex arrays,
// no degenerate triangle, lights that point at emissive triangles.
inline void checkScene(const char* target, const Scene& scene) {
    ML_FUZZ_EXPECT(target, !scene.meshes.empty());
    for (const Material& m : scene.materials) {
        ML_FUZZ_EXPECT(target, isFinite(m.kd) && isFinite(m.ks) && isFinite(m.ke) && std::isfinite(m.ns), m.name);
        ML_FUZZ_EXPECT(target, glm::all(glm::greaterThanEqual(m.kd, Rgb(0.0))) && glm::all(glm::lessThanEqual(m.kd, Rgb(1.0))),
                       m.name);
        ML_FUZZ_EXPECT(target, glm::all(glm::greaterThanEqual(m.ks, Rgb(0.0))) && glm::all(glm::lessThanEqual(m.ks, Rgb(1.0))),
                       m.name);
        ML_FUZZ_EXPECT(target, glm::all(glm::greaterThanEqual(m.ke, Rgb(0.0))) && m.ns >= 0, m.name);
        checkTextureMap(target, m.kdMap, m.name);
        checkTextureMap(target, m.keMap, m.name);
    }
    for (const Mesh& mesh : scene.meshes) {
        ML_FUZZ_EXPECT(target, !mesh.triangles.empty(), mesh.name);
        ML_FUZZ_EXPECT(target, mesh.normals.size() == mesh.positions.size(), mesh.name);
        ML_FUZZ_EXPECT(target, mesh.materials.size() == mesh.triangles.size(), mesh.name);
        ML_FUZZ_EXPECT(target, mesh.sourceLines.size() == mesh.triangles.size(), mesh.name);
        ML_FUZZ_EXPECT(target, mesh.texcoords.empty() || mesh.texcoords.size() == mesh.positions.size(), mesh.name);
        ML_FUZZ_EXPECT(target, mesh.albedo.empty() || mesh.albedo.size() == mesh.triangles.size(), mesh.name);
        for (const Vec2& uv : mesh.texcoords) ML_FUZZ_EXPECT(target, finite2(uv), mesh.name);
        for (size_t v = 0; v < mesh.positions.size(); ++v) {
            ML_FUZZ_EXPECT(target, isFinite(mesh.positions[v]), mesh.name, " vertex ", v);
            // "unit shading normal per vertex": 1e-9 is a million times the
            // rounding of a normalisation in double.
            const double len = glm::length(mesh.normals[v]);
            ML_FUZZ_EXPECT(target, std::abs(len - 1) <= 1e-9, mesh.name, " vertex ", v, " normal length ", len);
        }
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            for (int k = 0; k < 3; ++k) ML_FUZZ_EXPECT(target, mesh.triangles[t][k] < mesh.positions.size(), mesh.name);
            ML_FUZZ_EXPECT(target, mesh.materials[t] < scene.materials.size(), mesh.name);
            // Degenerate triangles are dropped.
            const double area = mesh.area(t);
            ML_FUZZ_EXPECT(target, area > 0 && std::isfinite(area), mesh.name, " triangle ", t, " area ", area);
        }
    }
    for (const Light& light : scene.lights) {
        if (light.punctual()) {
            ML_FUZZ_EXPECT(target, isFinite(light.power()) && glm::all(glm::greaterThanEqual(light.power(), Rgb(0.0))),
                           light.name);
            continue;
        }
        ML_FUZZ_EXPECT(target, light.area > 0 && std::isfinite(light.area), light.name);
        ML_FUZZ_EXPECT(target, light.mesh < scene.meshes.size() && light.material < scene.materials.size(), light.name);
        ML_FUZZ_EXPECT(target, scene.materials[light.material].emissive() && isFinite(light.radiance), light.name);
        ML_FUZZ_EXPECT(target, isFinite(light.centroid) && isFinite(light.normal), light.name);
        ML_FUZZ_EXPECT(target, light.geometry.size() == light.triangles.size() && !light.triangles.empty(), light.name);
        for (uint32_t t : light.triangles)
            ML_FUZZ_EXPECT(target, t < scene.meshes[light.mesh].triangles.size(), light.name);
    }
}

}  // namespace ml::fuzz
