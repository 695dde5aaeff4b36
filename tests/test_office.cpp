// The built-in office: its panels (area, orientation, placement, constant
// total power), its geometry and its spec parser.
#include "core/Error.h"
#include "core/reference/Lambert.h"
#include "core/scenes/OfficeScene.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

using namespace ml;

namespace {

double relativeError(double actual, double expected) { return std::abs(actual - expected) / std::abs(expected); }

Rgb totalPower(const Scene& scene) {
    Rgb sum(0.0);
    for (const Light& light : scene.lights) sum += light.power();
    return sum;
}

// Fails unless f throws an InputError whose message contains `needle`.
void expectInputError(const std::function<void()>& f, const std::string& needle) {
    try {
        f();
        ADD_FAILURE() << "no InputError; expected one mentioning '" << needle << "'";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
            << "'" << e.what() << "' does not mention '" << needle << "'";
    }
}

OfficeSettings withPanels(int nx, int nz, double size) {
    OfficeSettings s;
    s.panelsX = nx;
    s.panelsZ = nz;
    s.panelSize = size;
    return s;
}

bool isRoomSurface(const std::string& name) {
    return name == "floor" || name == "ceiling" || name.rfind("wall", 0) == 0;
}

// Settings that exercise every branch of the layout.
std::vector<OfficeSettings> variants() {
    std::vector<OfficeSettings> all{OfficeSettings{}, withPanels(16, 12, 0.4), withPanels(1, 1, 2.0)};
    for (int desks : {0, 1, 5}) {
        OfficeSettings s;
        s.desks = desks;
        all.push_back(s);
    }
    OfficeSettings bare;
    bare.desks = bare.cabinets = bare.partitions = 0;
    all.push_back(bare);
    OfficeSettings big;
    big.width = 20.3;
    big.depth = 15;
    big.height = 4;
    big.desks = 20;
    big.cabinets = 12;
    all.push_back(big);
    return all;
}

}  // namespace

TEST(Office, DefaultHasTwelveDownwardPanelsJustBelowTheCeiling) {
    const OfficeSettings settings;
    const Scene scene = makeOfficeScene();
    EXPECT_EQ(scene.name, "office");
    ASSERT_EQ(scene.lights.size(), 12u);
    const double panelY = settings.height - 0.02;
    for (const Light& light : scene.lights) {
        SCOPED_TRACE(light.name);
        EXPECT_LT(relativeError(light.area, 0.36), 1e-12) << light.area;
        EXPECT_TRUE(light.planar);
        EXPECT_EQ(light.normal, Vec3(0.0, -1.0, 0.0));
        EXPECT_NEAR(light.bounds.lo.y, panelY, 1e-12);
        EXPECT_NEAR(light.bounds.hi.y, panelY, 1e-12);
        EXPECT_EQ(light.radiance, settings.panelRadiance);  // the reference layout: unscaled
        EXPECT_EQ(light.name.rfind("panel#", 0), 0u);
    }
    // The ceiling itself is at the room's height.
    for (const Mesh& mesh : scene.meshes)
        if (mesh.name == "ceiling") {
            for (const Vec3& p : mesh.positions) EXPECT_EQ(p.y, settings.height);
        }
}

TEST(Office, DefaultSizeAndCamera) {
    const Scene scene = makeOfficeScene();
    EXPECT_EQ(scene.triangleCount(), 434u);
    EXPECT_EQ(scene.bounds.lo, Vec3(-4.0, 0.0, -3.0));
    EXPECT_EQ(scene.bounds.hi, Vec3(4.0, 2.8, 3.0));
    ASSERT_TRUE(scene.camera.has_value());
    const Camera& camera = *scene.camera;
    EXPECT_NO_THROW(camera.validate());
    EXPECT_EQ(camera.position.y, 1.6);
    EXPECT_EQ(camera.fovYDegrees, 60.0);
    // Inside the room, near the (+x, +z) corner, looking towards its centre.
    EXPECT_GT(camera.position.x, 3.0);
    EXPECT_LT(camera.position.x, 4.0);
    EXPECT_GT(camera.position.z, 2.0);
    EXPECT_LT(camera.position.z, 3.0);
    Vec3 forward, right, up;
    camera.basis(forward, right, up);
    EXPECT_LT(forward.x, 0.0);
    EXPECT_LT(forward.z, 0.0);
}

TEST(Office, TotalPowerDoesNotDependOnThePanels) {
    const OfficeSettings reference;
    // π Ke A for the reference layout: 12 panels of 0.6 × 0.6 m.
    const Rgb expected = kPi * reference.panelRadiance * (12 * 0.36);
    const Rgb defaultPower = totalPower(makeOfficeScene());
    for (int c = 0; c < 3; ++c) EXPECT_LT(relativeError(defaultPower[c], expected[c]), 1e-12);

    struct Layout { int nx, nz; double size; };
    // 16 × 12 cells are 0.5 m: 0.6 m panels do not fit there, 0.4 m ones do.
    for (const Layout& l : {Layout{3, 1, 0.6}, Layout{4, 3, 0.6}, Layout{8, 6, 0.6}, Layout{3, 1, 0.4},
                            Layout{4, 3, 0.4}, Layout{8, 6, 0.4}, Layout{16, 12, 0.4}, Layout{16, 12, 0.49}}) {
        SCOPED_TRACE(concat(l.nx, "x", l.nz, " panels of ", l.size, " m"));
        const Scene scene = makeOfficeScene(withPanels(l.nx, l.nz, l.size));
        ASSERT_EQ(scene.lights.size(), size_t(l.nx * l.nz));
        const Rgb power = totalPower(scene);
        for (int c = 0; c < 3; ++c) EXPECT_LT(relativeError(power[c], defaultPower[c]), 1e-12) << power[c];
        for (const Light& light : scene.lights)
            EXPECT_LT(relativeError(light.area, l.size * l.size), 1e-12);
        if (l.size == 0.6) {
            // For 0.6 m panels the radiance is the reference's × 12 / (NX · NZ).
            const Rgb radiance = scene.lights.front().radiance;
            const Rgb expectedRadiance = reference.panelRadiance * (12.0 / (l.nx * l.nz));
            for (int c = 0; c < 3; ++c) EXPECT_LT(relativeError(radiance[c], expectedRadiance[c]), 1e-15);
        }
    }
}

TEST(Office, EveryTriangleHasPositiveAreaAndRoomSurfacesFaceIn) {
    for (const OfficeSettings& s : variants()) {
        SCOPED_TRACE(concat(s.width, "x", s.depth, "x", s.height, " m, ", s.panelsX, "x", s.panelsZ, " panels, ",
                            s.desks, " desks, ", s.cabinets, " cabinets, ", s.partitions, " partitions"));
        const Scene scene = makeOfficeScene(s);
        const Vec3 centre(0.0, 0.5 * s.height, 0.0);
        for (const Mesh& mesh : scene.meshes)
            for (size_t t = 0; t < mesh.triangles.size(); ++t) {
                EXPECT_GT(mesh.area(t), 1e-6) << mesh.name << " triangle " << t;
                if (!isRoomSurface(mesh.name)) continue;
                const Triangle3 p = mesh.triangle(t);
                const Vec3 middle = (p[0] + p[1] + p[2]) / 3.0;
                EXPECT_GT(glm::dot(mesh.areaNormal(t), centre - middle), 0.0) << mesh.name << " triangle " << t;
            }
        // Everything lies in the room, and only the ceiling reaches the panels.
        EXPECT_EQ(scene.bounds.lo, Vec3(-0.5 * s.width, 0.0, -0.5 * s.depth));
        EXPECT_EQ(scene.bounds.hi, Vec3(0.5 * s.width, s.height, 0.5 * s.depth));
        const double panelY = s.height - s.panelDrop;
        for (const Mesh& mesh : scene.meshes) {
            if (mesh.name == "ceiling" || mesh.name == "panels" || mesh.name.rfind("wall", 0) == 0) continue;
            for (const Vec3& p : mesh.positions) EXPECT_LT(p.y, panelY - 0.1) << mesh.name;
        }
        EXPECT_EQ(scene.lights.size(), size_t(s.panelsX) * size_t(s.panelsZ));
    }
}

TEST(Office, BoxesFaceOutwards) {
    const Scene scene = makeOfficeScene();
    int boxes = 0;
    for (const Mesh& mesh : scene.meshes) {
        if (mesh.name != "partition" && mesh.name.rfind("cabinet", 0) != 0) continue;
        ++boxes;
        Bounds3 box;
        for (const Vec3& p : mesh.positions) box.extend(p);
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const Triangle3 p = mesh.triangle(t);
            const Vec3 middle = (p[0] + p[1] + p[2]) / 3.0;
            EXPECT_GT(glm::dot(mesh.areaNormal(t), middle - box.center()), 0.0) << mesh.name << " triangle " << t;
        }
    }
    EXPECT_EQ(boxes, 5);  // 4 cabinets and the partition
    int desks = 0;
    for (const Mesh& mesh : scene.meshes) {
        if (mesh.name.rfind("desk", 0) != 0) continue;
        ++desks;
        int up = 0;  // triangles of the tabletop's top: they must face up
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const Triangle3 p = mesh.triangle(t);
            if (p[0].y == 0.72 && p[1].y == 0.72 && p[2].y == 0.72) {
                ++up;
                EXPECT_GT(mesh.areaNormal(t).y, 0.0);
            }
        }
        EXPECT_EQ(up, 2) << mesh.name;
    }
    EXPECT_EQ(desks, 6);
}

TEST(Office, PanelsDoNotTouchEachOtherOrTheWalls) {
    // 16 × 12 panels of 0.49 m leave exactly the least gap, 0.01 m.
    for (const OfficeSettings& s : {OfficeSettings{}, withPanels(16, 12, 0.49), withPanels(8, 6, 0.6)}) {
        SCOPED_TRACE(concat(s.panelsX, "x", s.panelsZ, " panels of ", s.panelSize, " m"));
        const Scene scene = makeOfficeScene(s);
        ASSERT_EQ(scene.lights.size(), size_t(s.panelsX * s.panelsZ));
        for (size_t a = 0; a < scene.lights.size(); ++a) {
            const Bounds3& p = scene.lights[a].bounds;
            EXPECT_GT(p.lo.x, -0.5 * s.width);
            EXPECT_LT(p.hi.x, 0.5 * s.width);
            EXPECT_GT(p.lo.z, -0.5 * s.depth);
            EXPECT_LT(p.hi.z, 0.5 * s.depth);
            for (size_t b = a + 1; b < scene.lights.size(); ++b) {
                const Bounds3& q = scene.lights[b].bounds;
                const bool apart = p.hi.x < q.lo.x || q.hi.x < p.lo.x || p.hi.z < q.lo.z || q.hi.z < p.lo.z;
                EXPECT_TRUE(apart) << scene.lights[a].name << " overlaps " << scene.lights[b].name;
            }
        }
    }
}

TEST(Office, FloorGetsAFewHundredLux) {
    // Unoccluded direct irradiance at the floor's centre, by Lambert's formula.
    for (const OfficeSettings& s : {OfficeSettings{}, withPanels(8, 6, 0.6), withPanels(16, 12, 0.4)}) {
        const Scene scene = makeOfficeScene(s);
        Rgb e(0.0);
        for (const Light& light : scene.lights)
            for (const Triangle3& t : light.geometry)
                e += light.radiance * cosineSolidAngle(Vec3(0.0), Vec3(0.0, 1.0, 0.0), {t[0], t[1], t[2]});
        const double lux = luminance(e);
        RecordProperty(concat("floor_centre_", s.panelsX, "x", s.panelsZ), concat(lux));
        EXPECT_GT(lux, 250.0);
        EXPECT_LT(lux, 400.0);
    }
}

TEST(OfficeSpec, ReadsEveryKey) {
    const OfficeSettings defaults;
    const OfficeSettings plain = parseOfficeSpec("office");
    EXPECT_EQ(plain.panelsX, defaults.panelsX);
    EXPECT_EQ(plain.panelsZ, defaults.panelsZ);
    EXPECT_EQ(plain.width, defaults.width);
    EXPECT_EQ(plain.desks, defaults.desks);

    const OfficeSettings s = parseOfficeSpec("office:panels=8x6");
    EXPECT_EQ(s.panelsX, 8);
    EXPECT_EQ(s.panelsZ, 6);
    EXPECT_EQ(s.desks, defaults.desks);
    EXPECT_EQ(s.panelSize, defaults.panelSize);

    const OfficeSettings all =
        parseOfficeSpec("office:panels=16x12,size=10x8.5x3,desks=4,partitions=0,cabinets=2,panelsize=0.5");
    EXPECT_EQ(all.panelsX, 16);
    EXPECT_EQ(all.panelsZ, 12);
    EXPECT_EQ(all.width, 10.0);
    EXPECT_EQ(all.depth, 8.5);
    EXPECT_EQ(all.height, 3.0);
    EXPECT_EQ(all.desks, 4);
    EXPECT_EQ(all.partitions, 0);
    EXPECT_EQ(all.cabinets, 2);
    EXPECT_EQ(all.panelSize, 0.5);
    const Scene scene = makeOfficeScene(all);
    EXPECT_EQ(scene.lights.size(), 192u);
    EXPECT_EQ(scene.bounds.hi, Vec3(5.0, 3.0, 4.25));
}

TEST(OfficeSpec, RefusesBadSpecsNamingTheKey) {
    expectInputError([] { parseOfficeSpec("office:lamps=3"); }, "lamps");
    for (const char* value : {"8", "8x", "x6", "0x3", "4x0", "-1x3", "8x6x2", "8.5x6", " 8x6", "8X6", "", "axb"})
        expectInputError([&] { parseOfficeSpec(std::string("office:panels=") + value); }, "panels");
    // 0.6 m panels need cells of 0.61 m: 16 × 12 gives 0.5 m cells in 8 × 6 m.
    expectInputError([] { parseOfficeSpec("office:panels=16x12"); }, "panels");
    expectInputError([] { parseOfficeSpec("office:panels=14x3"); }, "panels");
    expectInputError([] { parseOfficeSpec("office:panels=4x10"); }, "panels");
    EXPECT_NO_THROW(parseOfficeSpec("office:panels=13x9"));
    EXPECT_NO_THROW(parseOfficeSpec("office:panels=16x12,panelsize=0.49"));
    expectInputError([] { parseOfficeSpec("office:panels=16x12,panelsize=0.5"); }, "panels");
    expectInputError([] { parseOfficeSpec("office:panelsize=0"); }, "panelsize");
    expectInputError([] { parseOfficeSpec("office:panelsize=-0.5"); }, "panelsize");
    for (const char* value : {"10x8", "10x8x3x1", "10x8xabc", "nanx8x3", "infx8x3", "10xx3", "1e999x8x3"})
        expectInputError([&] { parseOfficeSpec(std::string("office:size=") + value); }, "size");
    expectInputError([] { parseOfficeSpec("office:size=1x8x3"); }, "size");
    expectInputError([] { parseOfficeSpec("office:size=8x6x1.9"); }, "size");  // lower than 2 m
    expectInputError([] { parseOfficeSpec("office:desks=-1"); }, "desks");
    expectInputError([] { parseOfficeSpec("office:desks=two"); }, "desks");
    expectInputError([] { parseOfficeSpec("office:desks=12"); }, "desks");  // rows of 6 need 10.6 m
    expectInputError([] { parseOfficeSpec("office:partitions=2"); }, "partitions");
    expectInputError([] { parseOfficeSpec("office:cabinets=10"); }, "cabinets");  // 8.18 m long
    expectInputError([] { parseOfficeSpec("office:cabinets=1.5"); }, "cabinets");
    expectInputError([] { parseOfficeSpec("office:desks=4,desks=5"); }, "desks");
    expectInputError([] { parseOfficeSpec("office:desks"); }, "desks");
    expectInputError([] { parseOfficeSpec("office:"); }, "KEY=VALUE");
    expectInputError([] { parseOfficeSpec("office:desks=4,"); }, "KEY=VALUE");
    expectInputError([] { parseOfficeSpec("offices"); }, "office");
    expectInputError([] { parseOfficeSpec("cornell"); }, "office");
}

TEST(OfficeSettings, RefusesBadValuesNamingTheField) {
    const auto refuses = [](const std::function<void(OfficeSettings&)>& change, const std::string& field) {
        OfficeSettings s;
        change(s);
        expectInputError([&] { makeOfficeScene(s); }, field);
        expectInputError([&] { s.validate(); }, field);
    };
    refuses([](OfficeSettings& s) { s.panelSize = 0; }, "panelSize");
    refuses([](OfficeSettings& s) { s.panelSize = std::nan(""); }, "panelSize");
    refuses([](OfficeSettings& s) { s.panelsX = 0; }, "panelsX");
    refuses([](OfficeSettings& s) { s.panelsZ = -2; }, "panelsZ");
    refuses([](OfficeSettings& s) { s.width = 0; }, "width");
    refuses([](OfficeSettings& s) { s.depth = -6; }, "depth");
    refuses([](OfficeSettings& s) { s.height = kInf; }, "height");
    refuses([](OfficeSettings& s) { s.panelDrop = 0; }, "panelDrop");
    refuses([](OfficeSettings& s) { s.panelDrop = 1.5; }, "panelDrop");
    refuses([](OfficeSettings& s) { s.panelRadiance = Rgb(1.0, -1.0, 1.0); }, "panelRadiance");
    refuses([](OfficeSettings& s) { s.panelRadiance = Rgb(0.0); }, "panelRadiance");
    refuses([](OfficeSettings& s) { s.desks = -1; }, "desks");
    refuses([](OfficeSettings& s) { s.cabinets = 2000; }, "cabinets");
    refuses([](OfficeSettings& s) { s.partitions = 3; }, "partitions");
    refuses([](OfficeSettings& s) { s.panelsX = 14; }, "panels");
    EXPECT_NO_THROW(OfficeSettings{}.validate());
}

// Scene::meanFreePath, which sets the bounce meshes' base (plan): 4V/S, the
// mean chord of a convex room. A closed 4 x 2 x 1 box: V = 8, S = 2(8 + 4 +
// 2) = 28, so 32/28 exactly (up to rounding); a lone flat quad has no
// volume, so 0; the default office (V = 8 x 6 x 2.8 = 134.4 m³ and its
// furniture's area on top of the room's 174.4 m²) lies below the bare
// room's 4V/S = 3.08 m.
TEST(Office, MeanFreePathIsFourVolumesOverTheArea) {
    using test::addQuad;
    using test::kX;
    using test::kY;
    using test::kZ;
    Mesh box;
    box.name = "box";
    const Vec3 o(0.0), a = 4.0 * kX, b = 2.0 * kY, c = kZ;
    addQuad(box, 0, o, b, a);
    addQuad(box, 0, o + c, a, b);
    addQuad(box, 0, o, a, c);
    addQuad(box, 0, o + b, c, a);
    addQuad(box, 0, o, c, b);
    addQuad(box, 0, o + a, b, c);
    const Scene closed = test::sceneOf("box", {Material::diffuse("grey", Rgb(0.5))}, {box});
    EXPECT_NEAR(32.0 / 28.0, closed.meanFreePath(), 1e-12);
    const Scene flat = test::sceneOf("quad", {Material::diffuse("grey", Rgb(0.5))},
                                     {test::quadMesh("quad", 0, o, a, c)});
    EXPECT_EQ(0.0, flat.meanFreePath());
    const double office = makeOfficeScene().meanFreePath();
    EXPECT_GT(office, 1.0);
    EXPECT_LT(office, 4 * 134.4 / 174.4);
}
