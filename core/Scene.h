// The scene: triangle meshes with a material per face, emissive area lights
// derived from them, and an optional camera.
#pragma once

#include "Camera.h"
#include "Math.h"
#include "PunctualLight.h"
#include "SmoothSpecular.h"
#include "Texture.h"

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
    // Textures drawn per pixel (empty: none). kd and ke stay the factor ×
    // the texture's area-weighted mean over the faces that use it: the
    // cache, the light sampler and the bounce count work with means; the
    // compositor and the path tracer show kdMap.value(uv) (clamped to
    // [0, 1]) and keMap.value(uv) on the faces of meshes with texcoords.
    TextureMap kdMap;
    TextureMap keMap;
    // A cut-out (glTF alphaMode MASK with an alpha in its base colour
    // texture, MTL map_d): the surface is absent where its coverage,
    // alphaMap.factor.r × the image's Texture::coverage at uv, is below
    // alphaCutoff: for shading (the compositor discards the pixel) and for
    // shadows (Embree and the GPU direct sampler's occluders skip the point).
    // The cache's meshes still cover the whole face. Empty: opaque.
    TextureMap alphaMap;
    double alphaCutoff = 0.5;  // in (0, 1]; glTF's default 0.5
    // A mirror or glass layer over Kd (SmoothSpecular.h); none by default.
    SmoothSpecular smooth;

    bool emissive() const { return ke.r > 0 || ke.g > 0 || ke.b > 0; }
    // Whether the cut-out removes the surface at mesh coordinate `uv`.
    bool cutAway(Vec2 uv) const {
        return alphaMap && alphaMap.factor.r * alphaMap.image->coverage(alphaMap.lookup(uv)) < alphaCutoff;
    }
    // A Lambertian material (no Ks) emitting `ke` from its front face.
    static Material diffuse(std::string name, const Rgb& kd, const Rgb& ke = Rgb(0.0)) {
        Material m;
        m.name = std::move(name);
        m.kd = kd;
        m.ke = ke;
        return m;
    }
    // A Phong lobe (Ks > 0) on a surface without a smooth layer: the
    // compositor's specular pass and the path tracer's glossy lobe.
    bool glossy() const { return !smooth.active() && (ks.r > 0 || ks.g > 0 || ks.b > 0); }
    // A mirror or glass surface: its rays are followed, never cached.
    bool specular() const { return smooth.active(); }
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
    // Per vertex, glTF's convention (Texture.h), for the materials' texture
    // maps; empty when the mesh has none (its textured faces show kd, ke).
    std::vector<Vec2> texcoords;
    // Per triangle, the mean of its material's Kd over its own texture
    // footprint (clamp(factor × footprint mean)); empty when no face of the
    // mesh is textured: Scene::albedo() then gives the material's kd.
    std::vector<Rgb> albedo;

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

// What kind of emitter a light is.
enum class LightKind {
    Area,         // emissive triangles of the scene (Ke), sampled by rasterising them from the receiver
    Point,        // a point with an intensity profile (isotropic, spot cone, photometric table): one shadow ray
    Directional,  // parallel light from infinitely far (the sun, glTF's directional): one shadow ray
};

// A light: a connected set of emissive triangles of one material and one
// mesh, all facing one way when they lie in one plane (Scene::finalize), or
// a punctual light (point, spot, photometric luminaire, directional) that
// a loader or a luminaire layout adds to Scene::lights before finalize().
struct Light {
    std::string name;                 // "<material>", or "<material>#k" when a material makes several in the scene; unique
    LightKind kind = LightKind::Area;
    std::string group;                // lights that switch together share a group name; empty: its own

    // --- Area lights ----------------------------------------------------------
    uint32_t mesh = 0;                // index into Scene::meshes
    uint32_t material = 0;            // index into Scene::materials
    std::vector<uint32_t> triangles;  // triangle indices in that mesh
    std::vector<Triangle3> geometry;  // the same triangles' world positions, CCW = emitting side
    Rgb radiance{0.0};                // Ke, uniform over the light
    double area = 0;                  // total area (scene units²); 0 for punctual lights
    // Area-weighted centroid (a point light's position; a directional light's
    // is the scene's centre).
    Vec3 centroid{0.0};
    // Unit area-weighted mean normal (emitting side); a punctual light's
    // axis (PunctualEmission::axis).
    Vec3 normal{0.0};
    bool planar = false;              // every triangle in one plane (kLightPlanarTolerance); false for punctual lights
    Bounds3 bounds;                   // a point light's is its position

    // --- Punctual lights ------------------------------------------------------
    PunctualEmission emission;        // kind Point or Directional (PunctualLight.h)

    bool punctual() const { return kind != LightKind::Area; }
    // Power emitted, W·(scene unit)²/m², the same for every kind so that
    // lights can be weighed against each other: π L A for a Lambertian area
    // light; ∫ I dω / s² for a point light (s = metres per unit); for a
    // directional light, its irradiance times the cross-section of the
    // scene's bounding sphere (what it can deliver to the scene). Watts are
    // this × s² (Scene::metresPerUnit).
    Rgb power() const;
};

// A punctual light's irradiance at x (unit normal n) with nothing in the way,
// and where the shadow ray goes (PunctualLight.h). Every part of Meshlight
// that lights a point with a punctual light calls this.
PunctualIncidence punctualIncidence(const Light& light, const Vec3& x, const Vec3& n);

// The group a light of this name switches with (Light::group): the name
// without a numbered suffix, as modelling tools number copies: "Panel.003",
// "Panel_3", "Panel 3" and "Panel#3" are all in group "Panel"; a name
// without such a suffix is a group of its own, named as the light.
std::string lightGroupOf(const std::string& name);

struct Scene {
    std::string name;
    std::vector<Material> materials;
    std::vector<Mesh> meshes;
    // Area lights found by finalize(), then the punctual lights a loader or
    // a luminaire layout put here before it, in their order.
    std::vector<Light> lights;
    std::optional<Camera> camera;    // from the file, if it has one
    Bounds3 bounds;                  // filled by finalize(): the triangles' bounds (not the point lights')
    // Metres per scene unit: how the inverse-square law of punctual lights
    // (candela, W·sr⁻¹) meets the scene's lengths. 1 for metres (glTF, the
    // office), 0.001 for the built-in Cornell box (millimetres). Area
    // lights do not need it: their irradiance is L × a solid angle.
    double metresPerUnit = 1;
    std::vector<std::string> warnings;

    // Computes bounds and area lights. Call once after the meshes (and any
    // punctual lights) are complete. Punctual lights already in `lights`
    // are kept, after the area lights, and checked: a finite position, a
    // unit axis, finite non-negative intensity (InputError naming the light).
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
    // The mean chord length 4V/S (Cauchy's formula for a convex enclosure):
    // V the bounds' volume, S the triangles' one-sided area; how far a ray
    // leaving a surface goes before it meets another, on average, in a room
    // the bounds enclose. 0 when the bounds are flat or there is no area.
    double meanFreePath() const;
    // The file's camera or, failing that, one framing the whole scene.
    Camera cameraOrDefault(double aspect) const;
    // True when any material has Ks > 0 (a specular pass is needed).
    bool hasGlossy() const;
    // A triangle's mean diffuse reflectance: Mesh::albedo's, or its material's kd.
    Rgb albedo(size_t mesh, size_t triangle) const {
        const Mesh& m = meshes[mesh];
        return m.albedo.empty() ? materials[m.materials[triangle]].kd : m.albedo[triangle];
    }
    // True when a material draws a texture on a mesh with coordinates.
    bool hasTextures() const;
};

}  // namespace ml
