// How Scene::finalize makes area lights of emissive triangles: connected sets
// of one material, except two-sided panels, which split into front and back.
#include "core/MeshUtil.h"
#include "core/Scene.h"
#include "core/scenes/CornellBox.h"
#include "core/scenes/OfficeScene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

using namespace ml;

namespace {

const Vec3 kUp(0.0, 1.0, 0.0);

// A scene of one emissive material "lamp" (Ke 1) and the given mesh, whose
// triangles all use it; normals computed.
Scene lampScene(Mesh mesh) {
    Scene scene;
    scene.name = "lights";
    scene.materials = {Material::diffuse("lamp", Rgb(0.5), Rgb(1.0))};
    mesh.name = "lamp";
    mesh.materials.assign(mesh.triangles.size(), 0);
    mesh.sourceLines.assign(mesh.triangles.size(), 0);
    computeShadingNormals(mesh, 30);
    scene.meshes.push_back(mesh);
    scene.finalize();
    return scene;
}

// Adds the quad (o, o + u, o + u + v, o + v), counter-clockwise seen from
// u × v, as two triangles on new vertices.
void addQuad(Mesh& m, const Vec3& o, const Vec3& u, const Vec3& v) {
    const auto base = static_cast<uint32_t>(m.positions.size());
    m.positions.insert(m.positions.end(), {o, o + u, o + u + v, o + v});
    m.triangles.emplace_back(base, base + 1, base + 2);
    m.triangles.emplace_back(base, base + 2, base + 3);
}

// A 2 × 3 panel at height 1 facing down, and the same panel facing up: what
// exporters write for a double-sided light.
Mesh twoSidedPanel(const Vec3& corner = Vec3(0.0, 1.0, 0.0)) {
    Mesh m;
    addQuad(m, corner, Vec3(2, 0, 0), Vec3(0, 0, 3));  // (2,0,0) × (0,0,3): -y
    addQuad(m, corner, Vec3(0, 0, 3), Vec3(2, 0, 0));  // +y
    return m;
}

// The six faces of the cube [0, 1]³, facing out.
Mesh cube() {
    Mesh m;
    const Vec3 x(1, 0, 0), y(0, 1, 0), z(0, 0, 1), o(0.0);
    addQuad(m, o, x, z);  // y = 0, facing -y
    addQuad(m, y, z, x);  // y = 1, +y
    addQuad(m, o, z, y);  // x = 0, -x
    addQuad(m, x, y, z);  // x = 1, +x
    addQuad(m, o, y, x);  // z = 0, -z
    addQuad(m, z, x, y);  // z = 1, +z
    return m;
}

// A UV sphere of radius r: `rings` bands of `segments` quads, poles as fans.
Mesh sphere(double r, int rings, int segments) {
    Mesh m;
    auto at = [&](int i, int j) {
        const double theta = kPi * i / rings, phi = 2 * kPi * j / segments;
        return r * Vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
    };
    auto index = [&](int i, int j) { return static_cast<uint32_t>(1 + (i - 1) * segments + j % segments); };
    m.positions.push_back(at(0, 0));
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < segments; ++j) m.positions.push_back(at(i, j));
    m.positions.push_back(at(rings, 0));
    const auto south = static_cast<uint32_t>(m.positions.size() - 1);
    for (int j = 0; j < segments; ++j) {
        m.triangles.emplace_back(0, index(1, j + 1), index(1, j));
        m.triangles.emplace_back(south, index(rings - 1, j), index(rings - 1, j + 1));
        for (int i = 1; i + 1 < rings; ++i) {
            m.triangles.emplace_back(index(i, j), index(i, j + 1), index(i + 1, j + 1));
            m.triangles.emplace_back(index(i, j), index(i + 1, j + 1), index(i + 1, j));
        }
    }
    return m;
}

}  // namespace

TEST(SceneLights, TwoCoincidentOppositeQuadsMakeTwoPlanarLights) {
    const Scene scene = lampScene(twoSidedPanel());
    ASSERT_EQ(scene.lights.size(), 2u);
    const Light& down = scene.lights[0];
    const Light& up = scene.lights[1];
    EXPECT_EQ(down.name, "lamp#0");
    EXPECT_EQ(up.name, "lamp#1");
    for (const Light* l : {&down, &up}) {
        EXPECT_TRUE(l->planar) << l->name;
        EXPECT_DOUBLE_EQ(l->area, 6.0) << l->name;
        EXPECT_EQ(l->triangles.size(), 2u) << l->name;
        EXPECT_NEAR(glm::length(l->centroid - Vec3(1.0, 1.0, 1.5)), 0.0, 1e-12) << l->name;
    }
    EXPECT_EQ(down.normal, -kUp);
    EXPECT_EQ(up.normal, kUp);
    EXPECT_EQ(down.triangles, (std::vector<uint32_t>{0, 1}));
    EXPECT_EQ(up.triangles, (std::vector<uint32_t>{2, 3}));
}

TEST(SceneLights, TwoSidedPanelsSplitTheSameWayEveryTime) {
    // Two panels in one mesh, apart: four lights, numbered in the order of
    // their triangles, and the same again when finalized again.
    Mesh m = twoSidedPanel();
    const Mesh second = twoSidedPanel(Vec3(5.0, 1.0, 0.0));
    const auto offset = static_cast<uint32_t>(m.positions.size());
    m.positions.insert(m.positions.end(), second.positions.begin(), second.positions.end());
    for (const glm::uvec3& t : second.triangles) m.triangles.push_back(t + offset);
    const Scene scene = lampScene(m);
    ASSERT_EQ(scene.lights.size(), 4u);
    std::vector<std::string> names;
    for (const Light& l : scene.lights) {
        EXPECT_TRUE(l.planar) << l.name;
        EXPECT_DOUBLE_EQ(l.area, 6.0) << l.name;
        names.push_back(l.name);
    }
    EXPECT_EQ(names, (std::vector<std::string>{"lamp#0", "lamp#1", "lamp#2", "lamp#3"}));
    EXPECT_EQ(scene.lights[0].triangles, (std::vector<uint32_t>{0, 1}));
    EXPECT_EQ(scene.lights[1].triangles, (std::vector<uint32_t>{2, 3}));
    EXPECT_EQ(scene.lights[2].triangles, (std::vector<uint32_t>{4, 5}));
    EXPECT_EQ(scene.lights[3].triangles, (std::vector<uint32_t>{6, 7}));
    EXPECT_EQ(scene.lights[2].normal, -kUp);
    EXPECT_EQ(scene.lights[3].normal, kUp);

    Scene again = scene;
    again.finalize();
    for (size_t k = 0; k < scene.lights.size(); ++k) {
        EXPECT_EQ(again.lights[k].name, scene.lights[k].name);
        EXPECT_EQ(again.lights[k].triangles, scene.lights[k].triangles);
    }
}

TEST(SceneLights, SharedCornersOfBothSidesStillSplit) {
    // The back reuses the front's vertices (an indexed double-sided panel).
    Mesh m;
    m.positions = {Vec3(0, 1, 0), Vec3(0, 1, 3), Vec3(2, 1, 3), Vec3(2, 1, 0)};
    m.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 2, 1}, {0, 3, 2}};
    const Scene scene = lampScene(m);
    ASSERT_EQ(scene.lights.size(), 2u);
    EXPECT_EQ(scene.lights[0].normal, kUp);
    EXPECT_EQ(scene.lights[1].normal, -kUp);
    for (const Light& l : scene.lights) {
        EXPECT_TRUE(l.planar);
        EXPECT_DOUBLE_EQ(l.area, 6.0);
    }
}

TEST(SceneLights, OneSidedPanelStaysOneLight) {
    Mesh m;
    addQuad(m, Vec3(0.0, 1.0, 0.0), Vec3(0, 0, 3), Vec3(2, 0, 0));
    addQuad(m, Vec3(2.0, 1.0, 0.0), Vec3(0, 0, 3), Vec3(2, 0, 0));  // beside it, sharing an edge
    const Scene scene = lampScene(m);
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_EQ(scene.lights[0].name, "lamp");
    EXPECT_TRUE(scene.lights[0].planar);
    EXPECT_DOUBLE_EQ(scene.lights[0].area, 12.0);
}

TEST(SceneLights, ClosedCubeStaysOneNonPlanarLight) {
    // The rule splits only what lies in one plane: a cube's faces face six
    // ways in six planes, so it is one light, not planar, as before.
    const Scene scene = lampScene(cube());
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_EQ(scene.lights[0].name, "lamp");
    EXPECT_FALSE(scene.lights[0].planar);
    EXPECT_EQ(scene.lights[0].triangles.size(), 12u);
    EXPECT_NEAR(scene.lights[0].area, 6.0, 1e-12);
}

TEST(SceneLights, TessellatedSphereStaysOneLight) {
    const double r = 0.5;
    const Scene scene = lampScene(sphere(r, 16, 32));
    ASSERT_EQ(scene.lights.size(), 1u);
    const Light& l = scene.lights[0];
    EXPECT_FALSE(l.planar);
    EXPECT_EQ(l.triangles.size(), scene.meshes[0].triangles.size());
    // Within the tessellation's shortfall of the sphere's area (about 1%).
    EXPECT_NEAR(l.area, 4 * kPi * r * r, 0.02 * 4 * kPi * r * r);
    EXPECT_NEAR(glm::length(l.centroid), 0.0, 1e-12);
}

TEST(SceneLights, PanelOutOfPlaneByMoreThanTheToleranceIsNotSplit) {
    // A corner of the back 1e-3 below the front: its triangles' normals are
    // within 1e-3 of the front's, but the set is not in one plane (1e-6 of
    // its size), so it is one light as before, not planar.
    Mesh m = twoSidedPanel();
    m.positions[5].y -= 1e-3;  // the back's own copy of the corner (0, 1, 3)
    const Scene scene = lampScene(m);
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_FALSE(scene.lights[0].planar);
}

TEST(SceneLights, NamesAreUniqueAcrossMeshesAndPunctualLights) {
    // Two objects of one emissive material, each one light: named "lamp#0"
    // and "lamp#1" (as two lights of one mesh), not "lamp" twice; two point
    // lights named "lamp": the first keeps its name, free, the second takes
    // the first free suffix, "lamp#2". Names are CSV columns of `probe` and
    // names in view scripts: each must be one light's.
    Scene scene;
    scene.name = "lights";
    scene.materials = {Material::diffuse("lamp", Rgb(0.5), Rgb(1.0))};
    for (double x : {0.0, 5.0}) {
        Mesh m;
        addQuad(m, Vec3(x, 1.0, 0.0), Vec3(2, 0, 0), Vec3(0, 0, 3));  // facing down
        m.name = "lamp";
        m.materials.assign(m.triangles.size(), 0);
        m.sourceLines.assign(m.triangles.size(), 0);
        computeShadingNormals(m, 30);
        scene.meshes.push_back(m);
    }
    Light point;
    point.name = "lamp";
    point.kind = LightKind::Point;
    point.emission.position = Vec3(0.0, 2.0, 0.0);
    point.emission.intensity = Rgb(1.0);
    scene.lights = {point, point};
    scene.finalize();
    std::vector<std::string> names;
    for (const Light& l : scene.lights) names.push_back(l.name);
    EXPECT_EQ(names, (std::vector<std::string>{"lamp#0", "lamp#1", "lamp", "lamp#2"}));
    EXPECT_EQ(scene.lights[0].mesh, 0u);
    EXPECT_EQ(scene.lights[1].mesh, 1u);
    EXPECT_TRUE(scene.lights[2].punctual() && scene.lights[3].punctual());
    for (const Light& l : scene.lights) EXPECT_EQ(lightGroupOf(l.name), "lamp") << l.name;

    Scene again = scene;  // finalized again: the same names
    again.finalize();
    for (size_t i = 0; i < names.size(); ++i) EXPECT_EQ(again.lights[i].name, names[i]);
}

TEST(SceneLights, BuiltInScenesKeepTheirLights) {
    const Scene cornell = makeCornellBox();
    ASSERT_EQ(cornell.lights.size(), 1u);
    EXPECT_TRUE(cornell.lights[0].planar);
    const Scene office = makeOfficeScene();
    ASSERT_EQ(office.lights.size(), 12u);
    std::set<std::string> names;
    for (const Light& l : office.lights) {
        EXPECT_TRUE(l.planar) << l.name;
        names.insert(l.name);
    }
    EXPECT_EQ(names.size(), 12u);
}
