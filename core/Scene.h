// The scene: triangle meshes with a material per face, emissive area lights
// derived from them, and an optional camera.
#pragma once

#include "Camera.h"
#include "Math.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace ml {

// Lambertian + Phong material with emission (MTL semantics).
struct Material {
    std::string name;
    Rgb kd{0.8};   // diffuse reflectance (albedo) in [0,1]
    Rgb ks{0.0};   // Phong specular reflectance in [0,1]; > 0 asks for a specular pass
    double ns = 1; // Phong exponent, typical 10..1000
    Rgb ke{0.0};   // emitted radiance, W·sr⁻¹·m⁻², leaving the front (CCW) face only

    bool emissive() const { return ke.r > 0 || ke.g > 0 || ke.b > 0; }
    // A Lambertian material (no Ks) emitting `ke` from its front face.
    static Material diffuse(std::string name, const Rgb& kd, const Rgb& ke = Rgb(0.0)) {
        Material m;
        m.name = std::move(name);
        m.kd = kd;
        m.ke = ke;
        return m;
    }
    bool glossy() const { return ks.r > 0 || ks.g > 0 || ks.b > 0; }
};

using Triangle3 = std::array<Vec3, 3>;

// One object: an indexed triangle mesh. Vertices are split where shading
// normals differ (a crease), so positions may repeat.
struct Mesh {
    std::string name;
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;              // unit shading normal per vertex
    std::vector<glm::uvec3> triangles;      // counter-clockwise = front face
    std::vector<uint32_t> materials;        // per triangle, index into Scene::materials
    std::vector<int> sourceLines;           // per triangle, line in the source file (0 if built in)

    Triangle3 triangle(size_t t) const {
        const glm::uvec3 i = triangles[t];
        return {positions[i.x], positions[i.y], positions[i.z]};
    }
    // Unnormalised geometric normal: its length is twice the area.
    Vec3 areaNormal(size_t t) const {
        const Triangle3 p = triangle(t);
        return glm::cross(p[1] - p[0], p[2] - p[0]);
    }
    double area(size_t t) const { return 0.5 * glm::length(areaNormal(t)); }
};

// A light is planar when every vertex lies within this fraction of the
// light's bounding diagonal from its mean plane.
constexpr double kLightPlanarTolerance = 1e-6;

// Two triangles face the same way when their unit normals differ by at most
// this (about 1e-3 radians); see Scene::finalize's two-sided panels.
constexpr double kLightNormalTolerance = 1e-3;

// A connected set of emissive triangles of one material and one mesh, all
// facing one way when they lie in one plane (Scene::finalize).
struct AreaLight {
    std::string name;                 // "<material>" or "<material>#k" when a material makes several
    uint32_t mesh = 0;                // index into Scene::meshes
    uint32_t material = 0;            // index into Scene::materials
    std::vector<uint32_t> triangles;  // triangle indices in that mesh
    std::vector<Triangle3> geometry;  // the same triangles' world positions, CCW = emitting side
    Rgb radiance{0.0};                // Ke, uniform over the light
    double area = 0;                  // total area (scene units²)
    Vec3 centroid{0.0};               // area-weighted centroid
    Vec3 normal{0.0};                 // unit area-weighted mean normal (emitting side)
    bool planar = false;              // every triangle in one plane (kLightPlanarTolerance)
    Bounds3 bounds;

    // Power emitted, W·(scene unit)²/m² (Φ = π L A for a Lambertian emitter).
    Rgb power() const { return kPi * radiance * area; }
};

struct Scene {
    std::string name;
    std::vector<Material> materials;
    std::vector<Mesh> meshes;
    std::vector<AreaLight> lights;   // filled by finalize()
    std::optional<Camera> camera;    // from the file, if it has one
    Bounds3 bounds;                  // filled by finalize()
    std::vector<std::string> warnings;

    // Computes bounds and area lights. Call once after the meshes are complete.
    //
    // A light is a connected set of emissive triangles (sharing a vertex
    // position) of one mesh and one material, with one exception: a
    // two-sided panel. A connected set that lies in one plane (every vertex
    // within kLightPlanarTolerance of its size from the plane of its largest
    // triangle) but faces both ways (every triangle's unit normal within
    // kLightNormalTolerance of n or of −n, some of each) is split into its
    // front and its back, each grouped again by connection: two coincident
    // quads facing opposite ways (exported double-sided panels) become two
    // planar lights rather than one whose normals cancel. Every other set
    // stays one light as before, planar or not: a sphere, a fold, a closed
    // cube (its six faces are not in one plane) or a double-sided room. Lights
    // are ordered by mesh, then by a representative triangle of the set, and
    // named "<material>", or "<material>#k" (k from 0 in that order) when a
    // material makes several in one mesh.
    void finalize();

    size_t triangleCount() const;
    // The file's camera or, failing that, one framing the whole scene.
    Camera cameraOrDefault(double aspect) const;
    // True when any material has Ks > 0 (a specular pass is needed).
    bool hasGlossy() const;
};

}  // namespace ml
