// Discontinuity meshing where a surface hangs close (cache/ContactCuts.h): a
// panel under a ceiling cuts it along its outline and penumbra lines (and
// itself along lines inside its outline, for its back), no
// face straddles a cut, the area is kept and the cut mesh stays conforming;
// touching contacts and hair-thin gaps are left uncut.
#include "TestScenes.h"

#include "cache/ContactCuts.h"
#include "core/MeshUtil.h"
#include "core/scenes/OfficeScene.h"

#include <gtest/gtest.h>

#include <map>

namespace ml {
namespace {

using test::addQuad;
using test::kX;
using test::kY;
using test::kZ;

// A box [lo, hi] without its bottom face, faces outwards (the Cornell box's blocks).
Mesh blockMesh(const Vec3& lo, const Vec3& hi) {
    Mesh m;
    m.name = "block";
    const Vec3 s = hi - lo;
    addQuad(m, 1, Vec3(lo.x, hi.y, lo.z), s.z * kZ, s.x * kX);                 // top, +y
    addQuad(m, 1, lo, s.z * kZ, s.y * kY);                                    // −x
    addQuad(m, 1, Vec3(hi.x, lo.y, lo.z), s.y * kY, s.z * kZ);                // +x
    addQuad(m, 1, lo, s.y * kY, s.x * kX);                                    // −z
    addQuad(m, 1, Vec3(lo.x, lo.y, hi.z), s.x * kX, s.y * kY);                // +z
    return m;
}

std::vector<Material> materials() {
    return {Material::diffuse("light", Rgb(0.5), Rgb(1.0)), Material::diffuse("grey", Rgb(0.5))};
}

double totalArea(const Mesh& m) {
    double a = 0;
    for (size_t t = 0; t < m.triangles.size(); ++t) a += m.area(t);
    return a;
}

// Whether some point of segment (a, b) lies strictly inside a triangle of
// `m` (in the plane y = const the mesh lies in): then that face straddles
// the cut. 400 points along the segment.
bool segmentCrossesAFace(const Mesh& m, const Vec3& a, const Vec3& b) {
    for (size_t t = 0; t < m.triangles.size(); ++t) {
        const Triangle3 p = m.triangle(t);
        for (int k = 1; k < 400; ++k) {
            const Vec3 q = a + (b - a) * (k / 400.0);
            // Barycentrics in the xz-plane.
            const double x0 = p[0].x, z0 = p[0].z;
            const double d = (p[1].x - x0) * (p[2].z - z0) - (p[2].x - x0) * (p[1].z - z0);
            const double u = ((q.x - x0) * (p[2].z - z0) - (p[2].x - x0) * (q.z - z0)) / d;
            const double v = ((p[1].x - x0) * (q.z - z0) - (q.x - x0) * (p[1].z - z0)) / d;
            const double tol = 1e-9;
            if (u > tol && v > tol && 1 - u - v > tol) return true;
        }
    }
    return false;
}

bool hasVertex(const Mesh& m, const Vec3& p) {
    for (const Vec3& q : m.positions)
        if (glm::length(q - p) < 1e-9) return true;
    return false;
}

// The square of lines x = ±half, z = ±half at height y, each from −half to
// +half: cut along, with vertices at its corners and no face straddling it.
void expectSquareOfLines(const Mesh& m, double y, double half) {
    for (int k = 0; k < 4; ++k) {
        const double sx = (k & 1) ? 1 : -1;
        const Vec3 a = (k & 2) ? Vec3(sx * half, y, -half) : Vec3(-half, y, sx * half);
        const Vec3 b = (k & 2) ? Vec3(sx * half, y, half) : Vec3(half, y, sx * half);
        EXPECT_TRUE(hasVertex(m, a)) << "corner of line " << half << " side " << k;
        EXPECT_FALSE(segmentCrossesAFace(m, a, b)) << "line " << half << " side " << k;
    }
}

// Every edge is used by two faces, or lies on the mesh's border `onBorder`:
// no T-vertex, no hole (by vertex index, as the cache's mesh joins faces).
template <class Border>
void expectConforming(const Mesh& m, Border onBorder) {
    std::map<std::pair<uint32_t, uint32_t>, int> uses;
    for (const glm::uvec3& t : m.triangles)
        for (int k = 0; k < 3; ++k) ++uses[std::minmax(t[k], t[(k + 1) % 3])];
    for (const auto& [e, n] : uses) {
        const Vec3 a = m.positions[e.first], b = m.positions[e.second];
        if (onBorder(a) && onBorder(b)) EXPECT_EQ(n, 1);
        else EXPECT_EQ(n, 2) << "edge (" << a.x << ", " << a.z << ") - (" << b.x << ", " << b.z << ")";
    }
}

TEST(ContactCuts, ATouchingBlockIsLeftUncut) {
    // A block standing on the floor (h = 0): the cache's hidden-vertex rule
    // handles what is under it, and a vertex on the contact would have the
    // block's side through its sampling point (ContactCuts.h).
    const Scene scene = test::sceneOf("block", materials(), {test::unitLight(), test::floorMesh(),
                                                             blockMesh(Vec3(-0.3, 0.0, -0.2), Vec3(0.3, 0.5, 0.2))});
    ContactCutSettings s;
    s.spacing = scene.bounds.diagonal() / 32;
    ContactCutReport report;
    const std::vector<Mesh> cut = cutAlongContacts(scene, {}, s, &report);
    for (size_t i = 0; i < cut.size(); ++i) EXPECT_EQ(cut[i].triangles, scene.meshes[i].triangles) << i;
    EXPECT_EQ(report.receivers, 0u);
}

// A 2 x 2 ceiling at y = 1 facing down and a 0.6 m panel `h` under it, facing down; a floor.
Scene panelScene(double h) {
    return test::sceneOf("panel", materials(),
                         {test::quadMesh("ceiling", 1, Vec3(-1, 1, -1), 2.0 * kX, 2.0 * kZ),
                          test::quadMesh("panel", 0, Vec3(-0.3, 1 - h, -0.3), 0.6 * kX, 0.6 * kZ),
                          test::quadMesh("floor", 1, Vec3(-1, 0, -1), 2.0 * kZ, 2.0 * kX)});
}

TEST(ContactCuts, APanelUnderACeilingCutsItsOutlineAndPenumbraLines) {
    const double h = 0.02;
    const Scene scene = panelScene(h);
    ContactCutSettings s;
    s.spacing = 0.5;  // 2h = 0.04 is under half of it: penumbra lines
    const std::vector<Mesh> cut = cutAlongContacts(scene, {}, s);
    const Mesh& ceiling = cut[0];
    EXPECT_NEAR(totalArea(ceiling), 4.0, 1e-12);
    // The outline, and lines 2h inside and outside it (the penumbra's
    // bend), which cross at their corners: no face straddles any of them.
    for (const double half : {0.3, 0.3 - 2 * h, 0.3 + 2 * h}) expectSquareOfLines(ceiling, 1, half);
    // Under the panel, where the light through the gap is convex in the
    // depth, lines at h and 3h too (kUnder), crossing at their corners; they
    // stay under the panel: none reaches the line 2h outside.
    for (const double d : {h, 3 * h}) {
        expectSquareOfLines(ceiling, 1, 0.3 - d);
        EXPECT_FALSE(hasVertex(ceiling, Vec3(-0.3 - 2 * h, 1, -(0.3 - d)))) << d;
    }
    expectConforming(ceiling, [](const Vec3& p) { return std::abs(std::abs(p.x) - 1) < 1e-12 ||
                                                          std::abs(std::abs(p.z) - 1) < 1e-12; });
    // The panel's back sees the same gap from below: lines 2h and 6h inside
    // its own outline, crossing at its corners (light reaches its back only
    // through the gap). The floor (far) is not cut.
    const Mesh& panel = cut[1];
    EXPECT_NEAR(totalArea(panel), 0.36, 1e-12);
    for (const double in : {0.3 - 2 * h, 0.3 - 6 * h}) {
        for (int k = 0; k < 4; ++k) {
            const double sx = (k & 1) ? 1 : -1;
            const Vec3 a = (k & 2) ? Vec3(sx * in, 1 - h, -0.3) : Vec3(-0.3, 1 - h, sx * in);
            const Vec3 b = (k & 2) ? Vec3(sx * in, 1 - h, 0.3) : Vec3(0.3, 1 - h, sx * in);
            EXPECT_TRUE(hasVertex(panel, (k & 2) ? Vec3(sx * in, 1 - h, -in) : Vec3(-in, 1 - h, sx * in))) << k;
            EXPECT_FALSE(segmentCrossesAFace(panel, a, b)) << "panel line " << in << ", side " << k;
        }
    }
    expectConforming(panel, [](const Vec3& p) { return std::abs(std::abs(p.x) - 0.3) < 1e-12 ||
                                                        std::abs(std::abs(p.z) - 0.3) < 1e-12; });
    EXPECT_EQ(cut[2].triangles.size(), 2u);
    // With a spacing that already resolves 2h, the outline alone.
    s.spacing = 0.06;
    const Mesh coarse = cutAlongContacts(scene, {}, s)[0];
    EXPECT_FALSE(hasVertex(coarse, Vec3(-0.3 - 2 * h, 1, -0.3 - 2 * h)));
    EXPECT_TRUE(hasVertex(coarse, Vec3(-0.3, 1, -0.3)));
    // The same scene gives the same meshes, to the bit.
    s.spacing = 0.5;
    const Mesh again = cutAlongContacts(scene, {}, s)[0];
    EXPECT_EQ(again.positions, ceiling.positions);
    EXPECT_EQ(again.triangles, ceiling.triangles);
}

TEST(ContactCuts, AGapUnderAThousandthOfTheSceneIsLeftUncut) {
    // The scene is 2.2 across: a panel 1 mm under the ceiling (the Cornell
    // box's light hangs 0.5 mm under its ceiling) cuts nothing.
    const Scene scene = panelScene(1e-3);
    ContactCutSettings s;
    s.spacing = 0.5;
    ContactCutReport report;
    const std::vector<Mesh> cut = cutAlongContacts(scene, {}, s, &report);
    EXPECT_EQ(cut[0].triangles, scene.meshes[0].triangles);
    EXPECT_EQ(report.receivers, 0u);
}

TEST(ContactCuts, NoFaceIsThinnerThanTheGpuCanDraw) {
    // The office with 192 panels 10 cm apart: the outlines and penumbra
    // lines of the panels in a row lie on the same lines, each computed from
    // its own panel's corners, and leave faces between them a rounding wide
    // (2,642 of them), whose attributes overflow when rasterised in floats:
    // a NaN pixel in the office's walkthrough. They are left out.
    OfficeSettings o;
    o.panelsX = 16;
    o.panelsZ = 12;
    o.panelSize = 0.4;
    const Scene scene = makeOfficeScene(o);
    ContactCutSettings s;
    s.spacing = scene.bounds.diagonal() / 32;
    ContactCutReport report;
    const std::vector<Mesh> cut = cutAlongContacts(scene, {}, s, &report);
    EXPECT_GT(report.dropped, 0u);
    const double least = 1e-6 * scene.bounds.diagonal();
    size_t thin = 0;
    double lost = 0;
    for (size_t i = 0; i < cut.size(); ++i) {
        const Mesh& m = cut[i];
        for (size_t t = 0; t < m.triangles.size(); ++t) {
            const Triangle3 p = m.triangle(t);
            const double longest =
                std::max({glm::length(p[1] - p[0]), glm::length(p[2] - p[1]), glm::length(p[0] - p[2])});
            thin += 2 * m.area(t) / longest < least;
        }
        lost += totalArea(scene.meshes[i]) - totalArea(m);
    }
    EXPECT_EQ(thin, 0u);
    EXPECT_NEAR(lost, 0.0, 1e-6);  // what was left out is that thin
}

TEST(ContactCuts, SkippedMeshesStayButStillCut) {
    const Scene scene = panelScene(0.02);
    ContactCutSettings s;
    s.spacing = 0.5;
    EXPECT_EQ(cutAlongContacts(scene, {true, false, false}, s)[0].triangles, scene.meshes[0].triangles);
    // A skipped panel still cuts the ceiling.
    EXPECT_GT(cutAlongContacts(scene, {false, true, false}, s)[0].triangles.size(), 2u);
}

// The panel scene with a wall at x = 1 facing the room, from the floor to
// the ceiling, `length` long along z (centred).
Scene panelSceneWithWall(double h, double length) {
    Scene scene = panelScene(h);
    scene.meshes.push_back(test::quadMesh("wall", 1, Vec3(1, 0, -0.5 * length), length * kZ, 1.0 * kY));
    scene.finalize();
    return scene;
}

// Whether some triangle of `m` has corners more than 1e-12 above and below
// the height y: then it straddles the line y = const.
bool straddles(const Mesh& m, double y) {
    for (size_t t = 0; t < m.triangles.size(); ++t) {
        const Triangle3 p = m.triangle(t);
        bool above = false, below = false;
        for (const Vec3& q : p) above = above || q.y > y + 1e-12, below = below || q.y < y - 1e-12;
        if (above && below) return true;
    }
    return false;
}

TEST(ContactCuts, AWallCrossingALightsPlaneIsCutAlongIt) {
    // Behind the panel's plane (y = 1 − h) its light is 0 and in front of
    // it it grows from 0: a wall from the floor to the ceiling gets a line
    // there, across the region near the light, and nothing else is cut.
    const double h = 0.02;
    const Scene scene = panelSceneWithWall(h, 2.0);
    const std::vector<CutPlane> planes = lightCutPlanes(scene);
    ASSERT_EQ(planes.size(), 1u);
    EXPECT_NEAR(std::abs(glm::dot(planes[0].normal, kY)), 1.0, 1e-12);
    EXPECT_NEAR(planes[0].point.y, 1 - h, 1e-12);
    ContactCutSettings s;
    s.closeness = 0;  // no contact cuts: the planes alone
    s.planes = planes;
    ContactCutReport report;
    const std::vector<Mesh> cut = cutAlongContacts(scene, {}, s, &report);
    const Mesh& wall = cut[3];
    EXPECT_TRUE(hasVertex(wall, Vec3(1, 1 - h, -1)));
    EXPECT_TRUE(hasVertex(wall, Vec3(1, 1 - h, 1)));
    EXPECT_TRUE(straddles(scene.meshes[3], 1 - h));
    EXPECT_FALSE(straddles(wall, 1 - h));
    EXPECT_NEAR(totalArea(wall), 2.0, 1e-12);
    expectConforming(wall, [](const Vec3& p) { return std::abs(p.y) < 1e-12 || std::abs(p.y - 1) < 1e-12 ||
                                                      std::abs(std::abs(p.z) - 1) < 1e-12; });
    EXPECT_EQ(report.planeSegments, 2u);  // the wall's two triangles
    for (size_t i = 0; i < 3; ++i) EXPECT_EQ(cut[i].triangles, scene.meshes[i].triangles) << i;
}

TEST(ContactCuts, ALightsPlaneCutsOnlyNearTheLight) {
    // The region is the panel's bounds grown by twice their diagonal (0.6√2):
    // a 10-m wall is cut from z = −0.3 − 1.2√2 to 0.3 + 1.2√2 only.
    const double h = 0.02, reach = 0.3 + 1.2 * std::sqrt(2.0);
    const Scene scene = panelSceneWithWall(h, 10.0);
    ContactCutSettings s;
    s.closeness = 0;
    s.planes = lightCutPlanes(scene);
    const Mesh wall = cutAlongContacts(scene, {}, s)[3];
    EXPECT_TRUE(hasVertex(wall, Vec3(1, 1 - h, -reach)));
    EXPECT_TRUE(hasVertex(wall, Vec3(1, 1 - h, reach)));
    for (const Vec3& p : wall.positions) EXPECT_LE(std::abs(p.z), 5.0 + 1e-12);
    size_t onLine = 0;
    for (const Vec3& p : wall.positions) onLine += std::abs(p.y - (1 - h)) < 1e-12;
    EXPECT_EQ(onLine, 2u);
}

TEST(ContactCuts, ALightsPlaneUnderAThousandthOfTheSceneFromAnEdgeCutsNothing) {
    // The Cornell box's light hangs 0.5 mm under its ceiling: the walls
    // cross its plane by a hair at their tops, which no pixel shows.
    const Scene scene = panelSceneWithWall(1e-3, 2.0);
    ContactCutSettings s;
    s.closeness = 0;
    s.planes = lightCutPlanes(scene);
    ContactCutReport report;
    const std::vector<Mesh> cut = cutAlongContacts(scene, {}, s, &report);
    EXPECT_EQ(cut[3].triangles, scene.meshes[3].triangles);
    EXPECT_EQ(report.planeSegments, 0u);
}

TEST(ContactCuts, ALightCloseToTheWallAddsALineWhereItsLightBends) {
    // A wall as wide as the panel, 5 cm from its edge: in front of the plane
    // its light grows from 0 and bends about 5 cm under it, under half the
    // base mesh's spacing (0.5 here): a second line goes there (δ is the
    // distance from each receiver triangle's crossing to the nearest light).
    // A spacing that resolves 5 cm (0.08) gets the plane's line alone.
    const double h = 0.02, gap = 0.05;
    Scene scene = panelScene(h);
    scene.meshes.push_back(test::quadMesh("wall", 1, Vec3(0.3 + gap, 0, -0.3), 0.6 * kZ, 1.0 * kY));
    scene.finalize();
    ContactCutSettings s;
    s.closeness = 0;
    s.planes = lightCutPlanes(scene);
    ASSERT_EQ(s.planes.size(), 1u);
    ASSERT_EQ(s.planes[0].lights.size(), 1u);
    s.spacing = 0.5;
    const Mesh wall = cutAlongContacts(scene, {}, s)[3];
    for (const double y : {1 - h, 1 - h - gap}) {
        EXPECT_TRUE(hasVertex(wall, Vec3(0.3 + gap, y, -0.3))) << y;
        EXPECT_TRUE(hasVertex(wall, Vec3(0.3 + gap, y, 0.3))) << y;
        EXPECT_FALSE(straddles(wall, y)) << y;
    }
    EXPECT_NEAR(totalArea(wall), 0.6, 1e-12);
    s.spacing = 0.08;
    const Mesh fine = cutAlongContacts(scene, {}, s)[3];
    EXPECT_TRUE(hasVertex(fine, Vec3(0.3 + gap, 1 - h, -0.3)));
    EXPECT_FALSE(hasVertex(fine, Vec3(0.3 + gap, 1 - h - gap, -0.3)));
}

TEST(ContactCuts, ALightsPlaneAddsItsLinesVerticesAlone) {
    // The receivers near a plane are bisected to the base's spacing before
    // they are cut, so the cut adds the line's points and the bisection
    // after it nothing: a 2-m wall under a panel 2 cm below the ceiling,
    // spacing 0.1, bisected the same way cut or not, differs by the points
    // on the line: at most four per 0.1 of its 2 m (the bisected faces are
    // 0.1/√2 wide, and the line crosses a side and one or two diagonals of
    // each), and its ends. Cut first (its two triangles: a strip 2 cm high
    // and the pieces beside it) and bisected after, the wall had 283
    // vertices more than uncut, for a line of two points.
    const Scene scene = panelSceneWithWall(0.02, 2.0);
    ContactCutSettings s;
    s.closeness = 0;
    s.planes = lightCutPlanes(scene);
    s.spacing = 0.1;
    ContactCutReport report;
    Mesh cut = cutAlongContacts(scene, {}, s, &report)[3];
    EXPECT_FALSE(straddles(cut, 0.98));
    EXPECT_NEAR(totalArea(cut), 2.0, 1e-12);
    EXPECT_EQ(bisectLongEdges(cut, 0.1), 0u);
    Mesh uncut = scene.meshes[3];
    bisectLongEdges(uncut, 0.1);
    size_t onLine = 0;
    for (const Vec3& p : cut.positions) onLine += std::abs(p.y - 0.98) < 1e-12;
    EXPECT_GE(onLine, 21u);  // a point every 0.1 at least
    EXPECT_LE(cut.positions.size(), uncut.positions.size() + 4 * 20 + 2);
    EXPECT_EQ(cut.positions.size() - uncut.positions.size(), onLine);
}

TEST(ContactCuts, CoplanarLightsShareOnePlane) {
    // The office's panels all hang in one plane: one cut plane, whose region
    // spans them all; its walls are cut along it.
    OfficeSettings o;
    o.panelsX = 8, o.panelsZ = 6;
    const Scene scene = makeOfficeScene(o);
    ASSERT_EQ(scene.lights.size(), 48u);
    const std::vector<CutPlane> planes = lightCutPlanes(scene);
    ASSERT_EQ(planes.size(), 1u);
    for (const Light& l : scene.lights) {
        EXPECT_LE(planes[0].region.lo.x, l.bounds.lo.x);
        EXPECT_GE(planes[0].region.hi.z, l.bounds.hi.z);
    }
    ContactCutSettings s;
    s.closeness = 0;
    s.planes = planes;
    ContactCutReport report;
    cutAlongContacts(scene, {}, s, &report);
    EXPECT_GE(report.planeSegments, 8u);  // four walls, two triangles each at least
}

}  // namespace
}  // namespace ml
