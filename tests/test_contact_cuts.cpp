// Discontinuity meshing where a surface hangs close (cache/ContactCuts.h): a
// panel under a ceiling cuts it along its outline and penumbra lines (and
// itself along lines inside its outline, for its back), no
// face straddles a cut, the area is kept and the cut mesh stays conforming;
// touching contacts and hair-thin gaps are left uncut.
#include "TestScenes.h"

#include "cache/ContactCuts.h"
#include "cache/IrradianceCache.h"
#include "core/scenes/OfficeScene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <initializer_list>
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
// A square panel `size` wide, centred h under a 2 × 2 ceiling.
Scene panelScene(double h, double size = 0.6) {
    const double half = 0.5 * size;
    return test::sceneOf("panel", materials(),
                         {test::quadMesh("ceiling", 1, Vec3(-1, 1, -1), 2.0 * kX, 2.0 * kZ),
                          test::quadMesh("panel", 0, Vec3(-half, 1 - h, -half), size * kX, size * kZ),
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
    // The outline, lines 2h inside and outside it (the penumbra's bend) and
    // 4h and 8h inside (under the panel, as on its back), which cross at
    // their corners: no face straddles any of them.
    for (const double half : {0.3, 0.3 - 2 * h, 0.3 + 2 * h, 0.3 - 4 * h, 0.3 - 8 * h})
        for (int k = 0; k < 4; ++k) {
            const double sx = (k & 1) ? 1 : -1;
            // A line x = ±half (k & 2) or z = ±half from −half to +half.
            const Vec3 a = (k & 2) ? Vec3(sx * half, 1, -half) : Vec3(-half, 1, sx * half);
            const Vec3 b = (k & 2) ? Vec3(sx * half, 1, half) : Vec3(half, 1, sx * half);
            EXPECT_TRUE(hasVertex(ceiling, a)) << "corner of line " << half << " side " << k;
            EXPECT_FALSE(segmentCrossesAFace(ceiling, a, b)) << "line " << half << " side " << k;
        }
    expectConforming(ceiling, [](const Vec3& p) { return std::abs(std::abs(p.x) - 1) < 1e-12 ||
                                                          std::abs(std::abs(p.z) - 1) < 1e-12; });
    // The panel's back sees the same gap from below: lines 2h, 4h, 6h and
    // 8h inside its own outline, crossing at its corners (light reaches its
    // back only through the gap). The floor (far) is not cut.
    const Mesh& panel = cut[1];
    EXPECT_NEAR(totalArea(panel), 0.36, 1e-12);
    for (const double in : {0.3 - 2 * h, 0.3 - 4 * h, 0.3 - 6 * h, 0.3 - 8 * h}) {
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

TEST(ContactCuts, LinesUnderAHangingFaceStopAtHalfItsWidth) {
    // A panel 0.1 wide, 0.009 under the ceiling (within a tenth of its
    // edges' length: a contact): 4h (0.036) is under half its width, 8h
    // (0.072) is not (the opposite edge's lines are nearer there).
    const double h = 0.009;
    const Scene scene = panelScene(h, 0.1);
    ContactCutSettings s;
    s.spacing = 0.5;
    const std::vector<Mesh> cut = cutAlongContacts(scene, {}, s);
    // Where a line `depth` inside meets the panel's edge, and where one
    // under it on the ceiling ends (3h past the edge's end).
    const auto onPanel = [&](double depth) { return hasVertex(cut[1], Vec3(-0.05 + depth, 1 - h, -0.05)); };
    const auto onCeiling = [&](double depth) { return hasVertex(cut[0], Vec3(-0.05 + depth, 1, 0.05 + 3 * h)); };
    EXPECT_TRUE(onPanel(2 * h));
    EXPECT_TRUE(onPanel(4 * h));
    EXPECT_TRUE(onCeiling(4 * h));
    EXPECT_FALSE(onPanel(8 * h));
    EXPECT_FALSE(onCeiling(8 * h));
}

// Whether |c| is one of `values` (to rounding).
bool oneOf(double c, std::initializer_list<double> values) {
    for (double v : values)
        if (std::abs(std::abs(c) - v) < 1e-9) return true;
    return false;
}

TEST(ContactCuts, LinesFourGapsDeepOrMoreAreLate) {
    const double h = 0.02;
    const Scene scene = panelScene(h);
    ContactCutSettings s;
    s.spacing = 0.5;
    std::vector<std::vector<char>> late;
    const std::vector<Mesh> cut = cutAlongContacts(scene, {}, s, nullptr, &late);
    ASSERT_EQ(late.size(), cut.size());
    // A vertex is late when it lies on a line 4h or 8h in (on the ceiling
    // under the panel, or on the panel's back) and would be there without
    // them: not where two early cuts cross (on the ceiling the outline and
    // the lines 2h either side of it, on the panel the lines 2h and 6h in;
    // its outline is its own edge, not a cut).
    const std::initializer_list<double> lateLines = {0.3 - 4 * h, 0.3 - 8 * h};
    const std::initializer_list<double> earlyLines[2] = {{0.3, 0.3 - 2 * h, 0.3 + 2 * h}, {0.3 - 2 * h, 0.3 - 6 * h}};
    size_t count = 0;
    for (size_t mi = 0; mi < 2; ++mi) {
        const Mesh& m = cut[mi];
        ASSERT_EQ(late[mi].size(), m.positions.size());
        for (size_t v = 0; v < m.positions.size(); ++v) {
            const Vec3& p = m.positions[v];
            const bool onLate = oneOf(p.x, lateLines) || oneOf(p.z, lateLines);
            const int early = int(oneOf(p.x, earlyLines[mi])) + int(oneOf(p.z, earlyLines[mi]));
            const bool own = v < scene.meshes[mi].positions.size();
            EXPECT_EQ(bool(late[mi][v]), onLate && early < 2 && !own)
                << "mesh " << mi << " vertex (" << p.x << ", " << p.z << ")";
            count += late[mi][v];
        }
    }
    EXPECT_GT(count, 16u);
    // The floor (far below) has none.
    EXPECT_EQ(std::count(late[2].begin(), late[2].end(), 1), 0);
}

// Counts the samples taken; every one the same light.
struct CountingSampler final : VertexSampler {
    size_t taken = 0;
    VertexSample sample(size_t, const Vec3&, const Vec3&, uint32_t) override {
        ++taken;
        VertexSample out;
        out.irradiance = Rgb(1.0);
        return out;
    }
};

TEST(ContactCuts, ACachesFirstPassLeavesTheLateVerticesToRefinement) {
    const Scene scene = panelScene(0.02);
    CacheSettings settings;
    settings.contactCloseness = 0.1;
    settings.maxEdgeFraction = 0.1;  // base edges 0.3 (the scene is 3 across): lines 2h either side
    IrradianceCache cache(scene, settings);
    const size_t total = cache.totalVertices(), deferred = cache.deferredCount();
    ASSERT_GT(deferred, 16u);
    ASSERT_EQ(cache.unsampledCount() + deferred, total);
    // The first pass, in rounds, samples the others only.
    CountingSampler sampler;
    while (cache.unsampledCount() > 0) cache.refine(sampler, 64, 1);
    EXPECT_EQ(sampler.taken, total - deferred);
    EXPECT_EQ(cache.deferredCount(), deferred);
    EXPECT_EQ(cache.estimatedError(), 1.0) << "unknown while vertices wait";
    // The next round takes them, before any is scored or split.
    const RefineReport r = cache.refine(sampler, 1 << 20, 1);
    EXPECT_EQ(r.estimates, deferred);
    EXPECT_EQ(r.splits, 0u);
    EXPECT_EQ(cache.deferredCount(), 0u);
    EXPECT_EQ(sampler.taken, total);
    EXPECT_LT(cache.estimatedError(), 1.0);
    // Not deferred, the first pass takes every vertex.
    CacheLayout layout;
    layout.deferLate = false;
    IrradianceCache eager(scene, settings, layout);
    EXPECT_EQ(eager.totalVertices(), total);
    EXPECT_EQ(eager.deferredCount(), 0u);
    EXPECT_EQ(eager.unsampledCount(), total);
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

}  // namespace
}  // namespace ml
