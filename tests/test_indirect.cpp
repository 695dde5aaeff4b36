// Indirect light (issue 5): the fish-eye slice gather, the bounce solver and
// the bounce plan, checked against closed forms (the furnace) and against the
// reference path tracer (near field, jittered averages), and for leaks.
//
// Direct light comes from the exact reference (ExactDirect) on the cache
// meshes, so what is measured is the indirect part alone.
#include "cache/IndirectSolver.h"
#include "IndirectReference.h"
#include "RoomLeak.h"
#include "TestSamplers.h"
#include "cache/IrradianceCache.h"
#include "core/Random.h"
#include "core/raytrace/BounceCount.h"
#include "core/reference/ExactIrradiance.h"
#include "core/scenes/CornellBox.h"
#include "core/scenes/OfficeScene.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/indirect/RadianceProxy.h"
#include "gpu_sampling/indirect/SliceGather.h"
#include "viewer/compositor/Compositor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

namespace ml {
namespace {

// A quad as two triangles of `material`, counter-clockwise seen from `facing`.
void addQuad(Mesh& mesh, std::array<Vec3, 4> q, const Vec3& facing, uint32_t material) {
    if (glm::dot(glm::cross(q[1] - q[0], q[2] - q[0]), facing) < 0) std::swap(q[1], q[3]);
    const uint32_t base = uint32_t(mesh.positions.size());
    const Vec3 n = glm::normalize(glm::cross(q[1] - q[0], q[2] - q[0]));
    for (const Vec3& p : q) mesh.positions.push_back(p), mesh.normals.push_back(n);
    mesh.triangles.push_back({base, base + 1, base + 2});
    mesh.triangles.push_back({base, base + 2, base + 3});
    mesh.materials.push_back(material), mesh.materials.push_back(material);
    mesh.sourceLines.push_back(0), mesh.sourceLines.push_back(0);
}

// The walls of the box [lo, hi] as quads facing in, with the direction to
// the box's inside; `skip(axis, side)` leaves a wall out.
struct Wall {
    int axis, side;
    std::array<Vec3, 4> quad;
    Vec3 inward;
};
std::vector<Wall> boxWalls(const Vec3& lo, const Vec3& hi) {
    std::vector<Wall> walls;
    const Vec3 c = 0.5 * (lo + hi);
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            Wall w{axis, side, {}, Vec3(0.0)};
            for (int k = 0; k < 4; ++k) {
                Vec3 p;
                p[axis] = side ? hi[axis] : lo[axis];
                p[u] = (k == 1 || k == 2) ? hi[u] : lo[u];
                p[v] = (k >= 2) ? hi[v] : lo[v];
                w.quad[size_t(k)] = p;
            }
            w.inward[axis] = c[axis] - w.quad[0][axis];
            walls.push_back(w);
        }
    return walls;
}

// The six walls of the box [lo, hi], facing in, each a mesh and a material
// (so each is a planar light when it emits).
void addBox(Scene& scene, const Vec3& lo, const Vec3& hi, const Rgb& kd, const Rgb& ke) {
    for (const Wall& w : boxWalls(lo, hi)) {
        Mesh m;
        m.name = concat("wall", w.axis, w.side);
        Material mat;
        mat.name = m.name;
        mat.kd = kd;
        mat.ke = ke;
        scene.materials.push_back(mat);
        addQuad(m, w.quad, w.inward, uint32_t(scene.materials.size() - 1));
        scene.meshes.push_back(std::move(m));
    }
}

// White furnace: a closed box whose walls all emit Le and reflect a.
Scene furnace(double a, double le) {
    Scene scene;
    scene.name = "furnace";
    addBox(scene, Vec3(0.0), Vec3(1.0), Rgb(a), Rgb(le));
    scene.finalize();
    return scene;
}

// Direct caches sampled exactly, the indirect solver run to convergence on
// the slice gather: indirect light alone is what differs from the truth.
struct Pipeline {
    std::unique_ptr<GlContext> context = createHeadlessContext(GlBackend::OsMesa);
    const Scene& scene;
    ExactDirect exact;
    IrradianceCache direct;
    std::unique_ptr<SliceGather> gather;
    std::unique_ptr<IndirectSolver> solver;

    Pipeline(const Scene& s, const GatherSettings& gs, int bounces, double albedo, double directEdge = 1.0 / 32)
        : scene(s), exact(s), direct(s, edgeSettings(directEdge)) {
        test::sampleEveryVertex(direct, [&](size_t l, const Vec3& x, const Vec3& n, uint32_t) {
            return exact.irradiance(l, x, n);
        }, 1, 1);
        gather = std::make_unique<SliceGather>(*context, scene, gs);
        IndirectSettings is;
        is.bounces = bounces;
        is.albedo = albedo;
        solver = std::make_unique<IndirectSolver>(scene, is);
    }
    static CacheSettings edgeSettings(double edge) {
        CacheSettings c;
        c.maxEdgeFraction = edge;
        return c;
    }
    std::vector<IrradianceMeshCopy> directMeshes() const {
        std::vector<IrradianceMeshCopy> v = direct.copyMeshes();
        return v;
    }
    void solve(int maxRounds = 4000) {
        for (int r = 0; r < maxRounds && !solver->allFinished(); ++r)
            solver->step(*gather, [&] { return directMeshes(); }, 256, 7, std::nullopt);
        ASSERT_TRUE(solver->allFinished()) << "the solver did not converge in " << maxRounds << " rounds";
    }
};

// ---------------------------------------------------------------------------
// Furnace: L = Le + a/π·E everywhere and E = π·L over the whole hemisphere,
// so L = Le/(1 − a) = Le·Σ a^k, k counting reflections. Direct light is one
// reflection, each indirect bounce one more: with N indirect bounces
// L = Le(1 − a^(N+2))/(1 − a). (The issue writes Le(1 − a^(N+1))/(1 − a)
// with N counting every reflection, direct light's included.)
// ---------------------------------------------------------------------------

// Radiance at the image's pixels, every one a wall seen from inside.
ImageRgb renderInside(Pipeline& p) {
    Compositor compositor(*p.context, p.scene);
    CompositorSettings cs;
    cs.width = cs.height = 24;
    cs.supersample = 2;
    Camera cam;
    cam.position = Vec3(0.5, 0.5, 0.1);
    cam.target = Vec3(0.5, 0.5, 1.0);
    cam.up = Vec3(0, 1, 0);
    cam.fovYDegrees = 100;
    return compositor.render(cam, p.directMeshes(), p.solver->copyMeshes(), cs);
}

void expectFurnace(double a, std::optional<int> forced, double tolerance) {
    const double le = 1.0;
    const Scene scene = furnace(a, le);
    BounceCountSettings bs;
    bs.forced = forced;
    const BounceCount plan = countBounces(scene, bs);
    EXPECT_NEAR(plan.meanAlbedo, a, 1e-9) << "uniform albedo: the weighting cannot change it";
    GatherSettings gs;
    gs.resolution = 32;
    Pipeline p(scene, gs, plan.bounces, plan.meanAlbedo);
    p.solve();
    const double expected = forced ? le * (1 - std::pow(a, *forced + 2)) / (1 - a) : le / (1 - a);
    const ImageRgb image = renderInside(p);
    double worst = 0, sum = 0;
    for (size_t i = 0; i < image.pixelCount(); ++i) {
        const double g = image.data[3 * i + 1];
        ASSERT_TRUE(std::isfinite(g));
        worst = std::max(worst, std::abs(g - expected) / expected);
        sum += g;
    }
    const double mean = sum / double(image.pixelCount());
    EXPECT_LT(std::abs(mean - expected) / expected, tolerance)
        << "a = " << a << ", " << plan.bounces << " bounces: mean radiance " << mean << ", expected " << expected;
    // Pixel by pixel a little more: each shows a few cache vertices, each
    // the mean of one or two jittered gathers.
    EXPECT_LT(worst, 1.5 * tolerance) << "a = " << a << ": worst pixel off by " << 100 * worst << "%";
    if (!forced) {
        EXPECT_LE(plan.missing, 0.01);  // of the reflected light
    }
}

// Tolerance 2% (the issue's): the plan leaves < 1% missing (a^(n+1) < 0.01),
// and a 40×40 slice gather of a uniform box errs by less than 0.5%: every
// texel is fully covered (face texels tile the walls exactly) and only the
// rays along the box's edges can slip between faces.
TEST(Furnace, HalfAlbedoAutomaticBounces) { expectFurnace(0.5, std::nullopt, 0.02); }
TEST(Furnace, AlbedoPointEightAutomaticBounces) { expectFurnace(0.8, std::nullopt, 0.02); }
// With a fixed count the sum is exactly the truncated series.
TEST(Furnace, FixedBouncesGiveTheTruncatedSeries) {
    expectFurnace(0.5, 2, 0.02);
    expectFurnace(0.8, 3, 0.02);
}

TEST(BounceCount, CountFromAlbedoAndCap) {
    const Scene scene = furnace(0.9, 1.0);
    BounceCountSettings s;
    s.maxBounces = 8;
    const BounceCount capped = countBounces(scene, s);
    EXPECT_EQ(capped.bounces, 8);
    EXPECT_TRUE(capped.capped);
    EXPECT_NEAR(capped.missing, std::pow(0.9, 9), 1e-12);
    s.maxBounces = 64;
    const BounceCount free = countBounces(scene, s);
    // 0.9^(n+1) ≤ 0.01 first at n + 1 = 44.
    EXPECT_EQ(free.bounces, 43);
    EXPECT_FALSE(free.capped);
    const Scene black = furnace(0.0, 1.0);
    EXPECT_EQ(countBounces(black).bounces, 0);
    // A uniform albedo is also the area-weighted one (the tail's ratio).
    EXPECT_NEAR(capped.areaAlbedo, 0.9, 1e-12);
}

TEST(BounceCount, AreaAlbedoWeighsEveryFaceByItsArea) {
    // The office: floor, walls, ceiling, furniture and the panels' housing;
    // the largest channel of their area-weighted mean, computed here from
    // the scene's own triangles.
    const Scene office = makeOfficeScene(OfficeSettings{});
    Rgb sum(0.0);
    double area = 0;
    for (const Mesh& m : office.meshes)
        for (size_t t = 0; t < m.triangles.size(); ++t) {
            sum += m.area(t) * office.materials[m.materials[t]].kd;
            area += m.area(t);
        }
    const Rgb mean = sum / area;
    const BounceCount b = countBounces(office);
    EXPECT_NEAR(b.areaAlbedo, std::max({mean.r, mean.g, mean.b}), 1e-12);
    // A light room with a dark floor, lit from above: later bounces meet
    // more of the light walls and ceiling than direct light does.
    EXPECT_GT(b.areaAlbedo, b.meanAlbedo);
}

TEST(BounceCount, ManyLightsAreDrawnByPowerAndAgreeWithEveryLight) {
    // 48 panels: past BounceCountSettings::everyLightUpTo (16) each point
    // draws 256 lights by power instead of 16 rays to each of the 48. The
    // draws' noise is in each point's weight only, averaged over 4,096
    // points: the irradiance-weighted albedo moves by the spread of the
    // albedos (0.1-0.8 here) times the weights' relative noise over
    // sqrt(4096), well under 0.005 (measured: 0.0010); the bounce ratio,
    // which weighs each point's one ray by it, as much (0.0006).
    OfficeSettings os;
    os.panelsX = 8;
    os.panelsZ = 6;
    const Scene office = makeOfficeScene(os);
    BounceCountSettings drawn, every;
    every.everyLightUpTo = 64;
    const BounceCount a = countBounces(office, drawn), b = countBounces(office, every);
    EXPECT_NEAR(a.meanAlbedo, b.meanAlbedo, 0.005);
    EXPECT_NEAR(a.bounceRatio, b.bounceRatio, 0.005);
    EXPECT_EQ(a.bounces, b.bounces);
    // The points are shared among threads and summed in their order: the
    // same plan, to the bit, on one thread or several.
    BounceCountSettings one = drawn;
    one.threads = 1;
    drawn.threads = 3;
    const BounceCount c = countBounces(office, one), d = countBounces(office, drawn);
    EXPECT_EQ(c.albedo.r, d.albedo.r);
    EXPECT_EQ(c.albedo.g, d.albedo.g);
    EXPECT_EQ(c.albedo.b, d.albedo.b);
    EXPECT_EQ(c.bounceRatio, d.bounceRatio);
    EXPECT_EQ(c.meanAlbedo, a.meanAlbedo);
}

// ---------------------------------------------------------------------------
// Near field and jitter, against the path tracer's one-bounce indirect light.
// ---------------------------------------------------------------------------

class CornellGather : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        scene_ = new Scene(makeCornellBox());
        GatherSettings gs;
        pipeline_ = new Pipeline(*scene_, gs, 1, 0.5, 1.0 / 128);
        pipeline_->gather->setSource(0, pipeline_->directMeshes());
        reference_ = new test::OneBounceReference(*scene_);
    }
    static void TearDownTestSuite() {
        delete reference_;
        delete pipeline_;
        delete scene_;
    }
    // The path tracer's first bounce at x, from `samples` paths.
    static test::OneBounce pathOneBounce(const Vec3& x, const Vec3& n, int samples) {
        return reference_->at(x, n, samples, 1);
    }
    static Rgb mean(const Vec3& x, const Vec3& n, int k, uint32_t seed0 = 0) {
        Rgb s(0.0);
        for (int i = 0; i < k; ++i) s += pipeline_->gather->estimate(0, x, n, seed0 + uint32_t(i));
        return s / double(k);
    }
    static Scene* scene_;
    static Pipeline* pipeline_;
    static test::OneBounceReference* reference_;
};
Scene* CornellGather::scene_ = nullptr;
Pipeline* CornellGather::pipeline_ = nullptr;
test::OneBounceReference* CornellGather::reference_ = nullptr;

// Points in concave corners and next to walls, where the voxels are too
// coarse and the near field's triangles take over. Tolerance 8%: at 64
// voxels along the box (a voxel is 8.9 mm), slice faces stand up to a
// voxel off the surfaces they show and a slanted block face is drawn in
// steps; bench indirect measures 1–6% at such points. The path tracer's
// standard error (< 1%) is inside it.
TEST_F(CornellGather, NearFieldCornersMatchThePathTracer) {
    struct P {
        Vec3 x, n;
        const char* what;
    };
    const P points[] = {
        {{0.0, 5.0, 554.0}, {1, 0, 0}, "right wall, 5 mm from floor and back wall"},
        {{0.0, 20.0, 540.0}, {1, 0, 0}, "right wall, 20 mm from floor and back wall"},
        {{278.0, 3.0, 559.2}, {0, 0, -1}, "back wall, 3 mm above the floor"},
        {{100.0, 548.8, 100.0}, {0, -1, 0}, "ceiling near the front right corner"},
        {{278.0, 0.0, 400.0}, {0, 1, 0}, "floor, 19 mm from the tall block"},
    };
    for (const P& p : points) {
        const test::OneBounce ref = pathOneBounce(p.x, p.n, 40000);
        const Rgb got = mean(p.x, p.n, 16);
        const double rel = std::abs(luminance(got) - luminance(ref.value)) / luminance(ref.value);
        EXPECT_LT(rel, 0.08) << p.what << ": gather " << luminance(got) << ", path tracer " << luminance(ref.value)
                             << " ± " << luminance(ref.error);
        EXPECT_LT(luminance(ref.error) / luminance(ref.value), 0.02) << "reference too noisy at " << p.what;
    }
}

// A point exactly in a corner gets the light of the corner's inside (its
// limit from the wall), not the quarter that an eye on the floor's plane
// would see.
TEST_F(CornellGather, CornerPointSeesTheRoomNotTheOutside) {
    const Rgb corner = mean(Vec3(0.0, 0.0, 559.2), Vec3(1, 0, 0), 8);
    const Rgb inside = mean(Vec3(0.0, 5.0, 554.0), Vec3(1, 0, 0), 8);
    EXPECT_GT(luminance(corner), 0.8 * luminance(inside));
}

// Averaging jittered gathers: the spread of a K-gather mean falls as 1/√K
// (independent jitter per seed), and the mean settles within the voxels'
// bias of the path tracer (the tolerance of the test above).
TEST_F(CornellGather, JitteredGathersConverge) {
    const Vec3 x(278.0, 274.0, 559.2), n(0, 0, -1);  // the back wall's centre
    auto spread = [&](int k) {
        double s1 = 0, s2 = 0;
        const int trials = 12;
        for (int t = 0; t < trials; ++t) {
            const double y = luminance(mean(x, n, k, uint32_t(1000 * (t + 1))));
            s1 += y, s2 += y * y;
        }
        const double m = s1 / trials;
        return std::sqrt(std::max(0.0, s2 / trials - m * m)) / m;
    };
    const double one = spread(1), sixteen = spread(16);
    EXPECT_GT(one, 0.0) << "jitter must change the estimate";
    // 1/√16 = 0.25, with room for the spread's own noise over 12 trials.
    EXPECT_LT(sixteen, 0.45 * one) << "spread of one gather " << one << ", of 16 " << sixteen;
    const test::OneBounce ref = pathOneBounce(x, n, 40000);
    const double rel = std::abs(luminance(mean(x, n, 64)) - luminance(ref.value)) / luminance(ref.value);
    EXPECT_LT(rel, 0.05) << "64 jittered gathers vs the path tracer at the back wall's centre";
}

// On and next to the light and in corners, each estimate gets the light of
// the regular point beside it (test::HardPoint): R, the path tracer's first
// bounce there (2^18 samples: < 1% standard error).
// Finite and non-negative are not worth checking: the gather throws on a
// non-finite estimate and draws only radiance clamped at 0, with positive
// pixel weights. Each estimate must lie in
//   [minShare·R, 1.15·R + 1% of the room's light (mid-air, about 0.065)]:
// 1.15 is the near field's 8% at 64 voxels (NearFieldCornersMatchThe-
// PathTracer) plus one gather's jitter (16 were averaged there; one spreads
// by 3.5% here); an edge or corner hides part of the hemisphere, it adds
// nothing. 1% of the room is what counts as dark; minShare was measured
// over 8 seeds, with margin.
TEST_F(CornellGather, HardPointsGetTheLightOfARegularPointBeside) {
    const test::HardPoint points[] = {
        // Between the light and the ceiling, facing the light's back: dark
        // (path tracer: 1e-7; the gather 3e-5 at most), though the 0.1 and
        // 0.5 mm gaps are far below a voxel (8.9 mm).
        {"0.4 mm above the light", {278, 548.7, 279.5}, {0, -1, 0}, {278, 548.7, 279.5}, 0},
        {"0.01 mm below the ceiling, above the light", {278, 548.79, 279.5}, {0, -1, 0}, {278, 548.79, 279.5}, 0},
        // Corners: measured 1.01-1.03 of the regular point, and 0.71-0.82 in
        // the ceiling's corner, whose walls the eye (nudged off them) sees
        // edge-on.
        {"the right wall's corner with the floor, on the open side", {0, 0, 0}, {1, 0, 0}, {0, 5, 5}, 0.85},
        {"the ceiling's back-left corner", {556, 548.8, 559.2}, {0, -1, 0}, {551, 548.8, 554.2}, 0.6},
        // Measured 0.98-1.04.
        {"the tall block's top corner", {265, 330, 296}, {0, 1, 0}, {269.4, 330, 298.3}, 0.85},
    };
    const double room = luminance(pathOneBounce(Vec3(278, 274, 280), Vec3(0, 1, 0), 1 << 16).value);
    for (const test::HardPoint& p : points) {
        const test::OneBounce ref = pathOneBounce(p.regular, p.n, 1 << 18);
        const double r = luminance(ref.value);
        if (p.minShare > 0) {
            ASSERT_LT(luminance(ref.error), 0.01 * r) << "reference too noisy at " << p.what;
        }
        for (uint32_t seed : {3u, 4u}) {
            const double e = luminance(pipeline_->gather->estimate(0, p.x, p.n, seed));
            EXPECT_LE(e, 1.15 * r + 0.01 * room) << p.what << ", seed " << seed << ": path tracer " << r;
            EXPECT_GE(e, p.minShare * r) << p.what << ", seed " << seed << ": path tracer " << r;
        }
    }
    // Outside the box, a metre off the right wall, facing its back. The
    // slices keep one radiance per texel for both sides of a one-sided wall,
    // so the wall's back shows its lit inside: measured 8.2% of the room's
    // light (the path tracer, and the triangle gathers, which draw back
    // faces black: 0). 12% keeps that and fails an eye pulled into the
    // grid, which would see the whole room (100%).
    const double outside = luminance(pipeline_->gather->estimate(0, Vec3(-1e3, 0, 0), Vec3(1, 0, 0), 3));
    EXPECT_LE(outside, 0.12 * room) << "outside the box; the room's light is " << room;
}

// ---------------------------------------------------------------------------
// Leaks: a lit room and a dark room, a thin single-sided wall between them.
// ---------------------------------------------------------------------------

TEST(Leaks, DarkRoomStaysDark) {
    Scene scene;
    scene.name = "two rooms";
    Material white;
    white.name = "white";
    white.kd = Rgb(0.7);
    Material lamp;
    lamp.name = "lamp";
    lamp.kd = Rgb(0.7);
    lamp.ke = Rgb(10.0);
    scene.materials = {white, lamp};
    // Two rooms, [-2, 0] and [0, 2] x [0, 2] x [0, 2], each with its own
    // floor, ceiling and walls facing in (as rooms are modelled: a cache mesh
    // never interpolates across the wall), open where they meet.
    Mesh shell;
    shell.name = "shell";
    for (int room = 0; room < 2; ++room)
        for (const Wall& w : boxWalls(Vec3(room ? 0.0 : -2.0, 0, 0), Vec3(room ? 2.0 : 0.0, 2, 2)))
            if (!(w.axis == 0 && w.side == 1 - room)) addQuad(shell, w.quad, w.inward, 0);  // not the partition's place
    // The partition at x = 0: one quad, lit side towards the lamp (x < 0).
    Mesh wall;
    wall.name = "partition";
    addQuad(wall, {Vec3(0, 0, 0), Vec3(0, 2, 0), Vec3(0, 2, 2), Vec3(0, 0, 2)}, Vec3(-1, 0, 0), 0);
    Mesh light;
    light.name = "lamp";
    addQuad(light, {Vec3(-1.3, 1.99, 0.7), Vec3(-0.7, 1.99, 0.7), Vec3(-0.7, 1.99, 1.3), Vec3(-1.3, 1.99, 1.3)},
            Vec3(0, -1, 0), 1);
    scene.meshes = {shell, wall, light};
    scene.finalize();

    GatherSettings gs;
    gs.resolution = 64;
    const BounceCount plan = countBounces(scene);
    Pipeline p(scene, gs, plan.bounces, plan.meanAlbedo);
    p.solve();
    const test::RoomLeak leak = test::roomLeak(p.solver->copyMeshes());
    ASSERT_GT(leak.lit, 0.1);
    // The dark room: no light path reaches it, so all light there is leak:
    // through floor, ceiling and side-wall texels that straddle the
    // partition (a texel a voxel wide, 6 cm here, averages both rooms'
    // surfaces) and from there on by further bounces. Bounds, measured
    // 3.3%, 0.59% and 0.51% (of the lit room's floor, mean): 4% within
    // 0.4 m of the partition, 1.5% beyond, 1% on average over the dark room.
    const double nearMax = leak.nearMax, farMax = leak.farMax;
    std::printf("leak, relative to the lit floor: %.4f near the partition, %.4f beyond, %.4f mean\n", nearMax, farMax,
                leak.mean);
    EXPECT_LT(nearMax, 0.04);
    EXPECT_LT(farMax, 0.015);
    EXPECT_LT(leak.mean, 0.01);
}

}  // namespace
}  // namespace ml
namespace ml {
namespace {

// In a box whose walls all reflect the same radiance Lo, one gather gives
// E = π·Lo wherever the point is: face centres, a hair off a wall, on an
// edge, in a corner (where a cache vertex sits, sampled a hair inside its
// faces). Tolerance 0.5%: face texels tile the walls exactly, so only rays
// along the box's edges can slip between faces, a few pixels of 1,256.
TEST(UniformBox, OneGatherIsPiTimesTheRadiance) {
    const Scene scene = furnace(0.5, 1.0);
    GatherSettings gs;
    gs.resolution = 32;
    Pipeline p(scene, gs, 1, 0.5);
    p.gather->setSource(0, p.directMeshes());  // Lo = a/π · π·Le = 0.5 everywhere
    const Vec3 pts[] = {{0.5, 0, 0.5}, {0.5, 0.001, 0.5}, {0.02, 0, 0.5}, {0.0, 0, 0.5}, {0, 0, 0},
                        {0.3, 0, 0.7}, {0.5, 0.5, 0}, {0.97, 0.5, 0.5}, {0.999, 0.5, 0.5}};
    const Vec3 ns[] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {-1, 0, 0}};
    for (size_t i = 0; i < std::size(pts); ++i) {
        Rgb s(0.0);
        for (int k = 0; k < 4; ++k) s += p.gather->estimate(0, pts[i], ns[i], uint32_t(k));
        EXPECT_NEAR(s.g / 4 / (kPi * 0.5), 1.0, 0.005) << "point " << i;
    }
}

// --- The first pass's effort ------------------------------------------------------

// Records what each setSource was asked to spend; every estimate is 1.
struct EffortRecorder : IndirectEstimator {
    std::vector<std::pair<size_t, double>> built;  // (slot, importance) per setSource
    std::string name() const override { return "recorder"; }
    void setSource(size_t slot, const std::vector<IrradianceMeshCopy>&, double importance) override {
        built.push_back({slot, importance});
    }
    void releaseSource(size_t) override {}
    Rgb estimate(size_t, const Vec3&, const Vec3&, uint32_t) override { return Rgb(1.0); }
    IndirectStats stats() const override { return {}; }
};

// Two bounces, each half the one before: the furnace tests' solver settings.
IndirectSettings twoHalfBounces() {
    IndirectSettings is;
    is.bounces = 2;
    is.albedo = 0.5;
    return is;
}

// Each source built while the first passes run, and only those, spends
// firstPassGathers over the base's vertices (times ā^(n−1) for bounce n);
// a base no larger than firstPassGathers is gathered at full effort.
void expectFirstPassEffort(double firstPassGathers) {
    const Scene scene = test::furnaceBox(0.5, 0.0);
    IndirectSettings is = twoHalfBounces();
    is.firstPassGathers = firstPassGathers;
    IndirectSolver solver(scene, is);
    EffortRecorder recorder;
    const std::vector<IrradianceMeshCopy> direct = test::uniformSource(scene, 1.0);
    size_t firstPassBuilds = 0, laterBuilds = 0;
    for (int r = 0; r < 400 && !solver.allFinished(); ++r) {
        const bool first = !solver.firstPassDone();
        const size_t before = recorder.built.size();
        solver.step(recorder, [&] { return direct; }, 64, 7, std::nullopt);
        const double base = double(solver.cache(1).level() == 0 ? solver.cache(1).totalVertices() : 0);
        for (size_t k = before; k < recorder.built.size(); ++k) {
            const auto [slot, importance] = recorder.built[k];
            const double share = std::pow(0.5, double(slot));
            if (first) {
                ASSERT_GT(base, 0.0) << "the base is refined during the first pass";
                const double effort = std::min(1.0, firstPassGathers / base);
                EXPECT_DOUBLE_EQ(importance, effort * share) << "first pass, slot " << slot;
                ++firstPassBuilds;
            } else {
                EXPECT_DOUBLE_EQ(importance, share) << "pass 2, slot " << slot;
                ++laterBuilds;
            }
        }
    }
    ASSERT_TRUE(solver.allFinished());
    EXPECT_EQ(firstPassBuilds, 2u);  // one source per bounce
    EXPECT_GE(laterBuilds, 1u);      // bounce 1's source is rebuilt for pass 2
}

// The solver's interrupt reaches every bounce's cache, those made after it
// was set too: asked at once, a round gathers nothing; cleared, rounds go on.
TEST(IndirectInterrupt, EveryBouncesCacheEndsItsRoundWhenAsked) {
    const Scene scene = test::furnaceBox(0.5, 0.0);
    IndirectSolver solver(scene, twoHalfBounces());
    EffortRecorder recorder;
    const std::vector<IrradianceMeshCopy> direct = test::uniformSource(scene, 1.0);
    const auto round = [&] { return solver.step(recorder, [&] { return direct; }, 64, 7, std::nullopt); };
    bool stop = true;
    solver.setInterrupt([&] { return stop; });
    RefineReport r = round();
    ASSERT_EQ(solver.started(), 1);
    EXPECT_EQ(r.estimates, 0u);
    EXPECT_EQ(solver.cache(1).totalSamples(), 0u);
    stop = false;
    for (int k = 0; k < 400 && solver.started() < 2; ++k) round();
    ASSERT_EQ(solver.started(), 2);  // bounce 2's cache made while the interrupt was set
    const uint64_t second = solver.cache(2).totalSamples();
    stop = true;
    r = round();
    EXPECT_EQ(r.estimates, 0u);
    EXPECT_EQ(solver.cache(2).totalSamples(), second);
    solver.setInterrupt({});
    EXPECT_GT(round().estimates, 0u);
}

TEST(FirstPassEffort, ALargeBaseIsGatheredFirstAtItsShare) { expectFirstPassEffort(10); }
TEST(FirstPassEffort, ASmallBaseIsGatheredAtFullEffort) { expectFirstPassEffort(1e9); }

// --- Pass 2: which bounce next -----------------------------------------------------

// Every estimate is 1 plus noise drawn from the seed: ±`noise[slot]`
// (uniform) for the bounce gathering from that slot.
struct NoisyEstimator : EffortRecorder {
    std::array<double, 2> noise{0.1, 0.8};
    Rgb estimate(size_t slot, const Vec3&, const Vec3&, uint32_t seed) override {
        const double u = double(hash32(seed) & 0xffff) / 65535.0 - 0.5;
        return Rgb(1 + 2 * noise.at(slot) * u);
    }
};

// Bounce 2's gathers are eight times noisier than bounce 1's, so its share
// of the image's error (its error × ā) is the larger: pass 2 refines it
// before bounce 1 has converged, rather than waiting for bounce 1 to
// converge first; and bounce 2's source, built from bounce 1, is built
// again as bounce 1's samples double. Both converge.
TEST(PassTwo, TheBounceWithTheLargestShareOfTheErrorGoesFirst) {
    const Scene scene = test::furnaceBox(0.5, 0.0);
    IndirectSolver solver(scene, twoHalfBounces());
    NoisyEstimator estimator;
    const std::vector<IrradianceMeshCopy> direct = test::uniformSource(scene, 1.0);
    int r = 0;
    for (; r < 400 && !solver.firstPassDone(); ++r) solver.step(estimator, [&] { return direct; }, 64, 7, std::nullopt);
    ASSERT_TRUE(solver.firstPassDone());
    const uint64_t secondBase = solver.cache(2).totalSamples();
    bool secondRefinedEarly = false;
    for (; r < 4000 && !solver.allFinished(); ++r) {
        solver.step(estimator, [&] { return direct; }, 64, 7, std::nullopt);
        if (solver.cache(2).totalSamples() > secondBase && solver.finished() == 0) secondRefinedEarly = true;
    }
    ASSERT_TRUE(solver.allFinished());
    EXPECT_TRUE(secondRefinedEarly);
    size_t secondSources = 0;
    for (const auto& [slot, importance] : estimator.built) secondSources += slot == 1;
    EXPECT_GE(secondSources, 3u);  // the first pass's, pass 2's, and at least one rebuilt as bounce 1 grew
}

// Two triangles of areas 1 and 3 sharing an edge, lit 0, 6, 6 and
// (12, 0, 12) at their vertices.
IrradianceMeshCopy twoTriangles() {
    IrradianceMeshCopy m;
    m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 2, 0), Vec3(3, 2, 0)};
    m.normals.assign(4, Vec3(0, 0, 1));
    m.triangles = {glm::uvec3(0, 1, 2), glm::uvec3(1, 3, 2)};
    m.irradiance = {Rgb(0.0), Rgb(6.0), Rgb(6.0), Rgb(12.0, 0.0, 12.0)};
    return m;
}

// The tail's shape (shapeAsLaterBounces): after bounce 1, half of each
// vertex's light and half the area-weighted mean; after a later bounce,
// unchanged. Two triangles of areas 1 and 3 sharing an edge: vertex areas
// (a third of each face) 1/3, 4/3, 4/3, 1; the mean of 0, 6, 6, 12 so
// weighted is (0 + 8 + 8 + 12) / 4 = 7. Exact arithmetic up to rounding.
TEST(TailShape, AfterBounceOneHalfTheLightIsTheAreaMean) {
    IrradianceMeshCopy m = twoTriangles();
    IrradianceMeshCopy later = m;
    shapeAsLaterBounces(later, 2);
    for (size_t v = 0; v < 4; ++v) EXPECT_EQ(later.irradiance[v], m.irradiance[v]);
    shapeAsLaterBounces(m, 1);
    const Rgb mean = (Rgb(0.0) * (1.0 / 3) + Rgb(6.0) * (8.0 / 3) + Rgb(12.0, 0.0, 12.0)) / 4.0;
    const std::vector<Rgb> before = {Rgb(0.0), Rgb(6.0), Rgb(6.0), Rgb(12.0, 0.0, 12.0)};
    for (size_t v = 0; v < 4; ++v)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(m.irradiance[v][c], 0.5 * (before[v][c] + mean[c]), 1e-12);
    EXPECT_NEAR(mean.x, 7.0, 1e-12);
}

// With the albedo each vertex sees, the tail after bounce 1 is the
// area-weighted mean (7, 0, 7 on the triangles above) times that albedo
// over its own area-weighted mean, channel by channel. Seen albedos 0.2,
// 0.4, 0.4, 0.8 (blue half of them) have area-weighted mean
// (0.2/3 + 0.4 · 8/3 + 0.8) / 4 = 0.4833..., so vertex 3 gets 7 · 0.8 /
// 0.4833 and the mean stays 7; a channel no vertex sees (green) is its
// mean everywhere, (6 · 8/3) / 4 = 4. Exact arithmetic up to rounding.
TEST(TailShape, AfterBounceOneTheAreaMeanGoesWhereTheAlbedoSeenIs) {
    IrradianceMeshCopy m = twoTriangles();
    const std::vector<Rgb> seen = {Rgb(0.2, 0, 0.1), Rgb(0.4, 0, 0.2), Rgb(0.4, 0, 0.2), Rgb(0.8, 0, 0.4)};
    const std::vector<double> area = {1.0 / 3, 4.0 / 3, 4.0 / 3, 1.0};
    shapeAsLaterBounces(m, 1, seen);
    const double seenMean = (0.2 / 3 + 0.4 * 8 / 3 + 0.8) / 4;
    Rgb mean(0.0);
    for (size_t v = 0; v < 4; ++v) {
        EXPECT_NEAR(m.irradiance[v].x, 7.0 * seen[v].x / seenMean, 1e-12) << v;
        EXPECT_NEAR(m.irradiance[v].z, 7.0 * seen[v].z / (0.5 * seenMean), 1e-12) << v;
        EXPECT_NEAR(m.irradiance[v].y, 4.0, 1e-12) << v;
        mean += area[v] * m.irradiance[v] / 4.0;
    }
    EXPECT_NEAR(mean.x, 7.0, 1e-12);
    EXPECT_NEAR(mean.y, 4.0, 1e-12);
    EXPECT_NEAR(mean.z, 7.0, 1e-12);
    // A seen albedo of another size (not this mesh's) is not used.
    IrradianceMeshCopy other = twoTriangles();
    shapeAsLaterBounces(other, 1, {Rgb(1.0)});
    EXPECT_NEAR(other.irradiance[0].x, 3.5, 1e-12);
    // After bounce 2 the same, with the albedo seen; without it (or of
    // another size), and after bounce 3, the light's own shape.
    IrradianceMeshCopy second = twoTriangles();
    shapeAsLaterBounces(second, 2, seen);
    for (size_t v = 0; v < 4; ++v) EXPECT_EQ(second.irradiance[v], m.irradiance[v]) << v;
    const IrradianceMeshCopy own = twoTriangles();
    for (const std::vector<Rgb>& albedo : {std::vector<Rgb>{}, std::vector<Rgb>{Rgb(1.0)}}) {
        IrradianceMeshCopy kept = twoTriangles();
        shapeAsLaterBounces(kept, 2, albedo);
        for (size_t v = 0; v < 4; ++v) EXPECT_EQ(kept.irradiance[v], own.irradiance[v]) << v;
    }
    IrradianceMeshCopy third = twoTriangles();
    shapeAsLaterBounces(third, 3, seen);
    for (size_t v = 0; v < 4; ++v) EXPECT_EQ(third.irradiance[v], own.irradiance[v]) << v;
}

}  // namespace
}  // namespace ml
