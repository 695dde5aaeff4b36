// Scenes built by hand for the tests: quads, the bench's light and floor
// alone, and the closed furnace box whose radiance is known in closed form.
#pragma once

#include "core/MeshUtil.h"
#include "core/Scene.h"

#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace ml::test {

inline const Vec3 kX(1, 0, 0), kY(0, 1, 0), kZ(0, 0, 1);

// Appends the parallelogram corner + [0,1]·u + [0,1]·v to `mesh` as two
// triangles of `material`, facing u × v (counter-clockwise seen from there),
// with that face normal at its four corners.
inline void addQuad(Mesh& mesh, uint32_t material, const Vec3& corner, const Vec3& u, const Vec3& v) {
    const uint32_t base = uint32_t(mesh.positions.size());
    const Vec3 normal = glm::normalize(glm::cross(u, v));
    for (const Vec3& p : {corner, corner + u, corner + u + v, corner + v}) {
        mesh.positions.push_back(p);
        mesh.normals.push_back(normal);
    }
    mesh.triangles.push_back({base, base + 1, base + 2});
    mesh.triangles.push_back({base, base + 2, base + 3});
    mesh.materials.insert(mesh.materials.end(), 2, material);
    mesh.sourceLines.insert(mesh.sourceLines.end(), 2, 0);
}

// A mesh of one quad (addQuad).
inline Mesh quadMesh(const std::string& name, uint32_t material, const Vec3& corner, const Vec3& u, const Vec3& v) {
    Mesh mesh;
    mesh.name = name;
    addQuad(mesh, material, corner, u, v);
    return mesh;
}

// A finalized scene (lights found, bounds known) of `materials` and `meshes`.
inline Scene sceneOf(std::string name, std::vector<Material> materials, std::vector<Mesh> meshes) {
    Scene scene;
    scene.name = std::move(name);
    scene.materials = std::move(materials);
    scene.meshes = std::move(meshes);
    scene.finalize();
    return scene;
}

// Material 0 emits `ke` (Kd 0), material 1 is grey (Kd 0.5): the pair
// unitLight() and floorMesh() are drawn with.
inline std::vector<Material> lightAndGrey(double ke = 1.0) {
    Material light, grey;
    light.name = "light";
    light.kd = Rgb(0.0);
    light.ke = Rgb(ke);
    grey.name = "grey";
    grey.kd = Rgb(0.5);
    return {light, grey};
}

// The bench's parts (core/scenes/BenchScene.h) as meshes of their own, for
// scenes whose material 0 emits and material 1 is grey: the light, 1 × 1 at
// y = 1 (x, z ∈ [−0.5, 0.5]) facing down, and the floor, 3 × 3 at y = 0
// facing up.
inline Mesh unitLight() { return quadMesh("light", 0, Vec3(-0.5, 1.0, -0.5), kX, kZ); }
inline Mesh floorMesh() { return quadMesh("floor", 1, Vec3(-1.5, 0.0, -1.5), 3.0 * kZ, 3.0 * kX); }

// A UV sphere of `material`: 2 poles and (stacks-1) rings of `slices`
// vertices, shared around the seam, each with its exact normal as shading
// normal; 2·slices·(stacks-1) triangles, counter-clockwise from outside.
inline Mesh uvSphere(const Vec3& center, double radius, int stacks, int slices, uint32_t material = 0) {
    Mesh m;
    m.name = "sphere";
    auto add = [&](const Vec3& n) {
        m.positions.push_back(center + radius * n);
        m.normals.push_back(n);
    };
    add(Vec3(0, 0, 1));
    for (int i = 1; i < stacks; ++i) {
        const double th = kPi * i / stacks;
        for (int j = 0; j < slices; ++j) {
            const double ph = 2 * kPi * j / slices;
            add(Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
        }
    }
    add(Vec3(0, 0, -1));
    const unsigned south = unsigned(m.positions.size() - 1);
    auto ring = [&](int i, int j) { return unsigned(1 + (i - 1) * slices + (j % slices)); };
    for (int j = 0; j < slices; ++j) {
        m.triangles.push_back({0u, ring(1, j), ring(1, j + 1)});
        for (int i = 1; i + 1 < stacks; ++i) {
            m.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
            m.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
        }
        m.triangles.push_back({ring(stacks - 1, j), south, ring(stacks - 1, j + 1)});
    }
    m.materials.assign(m.triangles.size(), material);
    m.sourceLines.assign(m.triangles.size(), 0);
    return m;
}

// A furnace: the closed cube centre ± halfSide (scene units) on every axis,
// one mesh of one material, every face inward (counter-clockwise seen from
// inside), reflecting `albedo` and emitting `emission` (W·sr⁻¹·m⁻²). Inside,
// paths of depth D carry emission·(1 + albedo + … + albedo^D); light that
// reflects off its walls all reaches them again.
inline Scene furnaceBox(double albedo, double emission, double halfSide = 1.0, const Vec3& centre = Vec3(0.0)) {
    Scene scene;
    scene.name = "furnace";
    Material wall;
    wall.name = "wall";
    wall.kd = Rgb(albedo);
    wall.ke = Rgb(emission);
    scene.materials = {wall};
    Mesh mesh;
    mesh.name = "box";
    auto corner = [&](int i) {
        return centre + halfSide * Vec3(i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 1.0 : -1.0);
    };
    const int faces[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
    for (const auto& f : faces) {
        std::array<Vec3, 4> q{corner(f[0]), corner(f[1]), corner(f[2]), corner(f[3])};
        const Vec3 faceCentre = 0.25 * (q[0] + q[1] + q[2] + q[3]);
        if (glm::dot(glm::cross(q[1] - q[0], q[2] - q[0]), centre - faceCentre) < 0) std::swap(q[1], q[3]);
        const uint32_t base = uint32_t(mesh.positions.size());
        mesh.positions.insert(mesh.positions.end(), q.begin(), q.end());
        mesh.triangles.push_back({base, base + 1, base + 2});
        mesh.triangles.push_back({base, base + 2, base + 3});
    }
    mesh.materials.assign(mesh.triangles.size(), 0);
    mesh.sourceLines.assign(mesh.triangles.size(), 0);
    computeShadingNormals(mesh, 0.0);
    scene.meshes.push_back(std::move(mesh));
    scene.finalize();
    return scene;
}

}  // namespace ml::test
