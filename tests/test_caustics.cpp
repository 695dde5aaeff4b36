// Caustics (issue 16): photons through mirrors and glass into a cache mesh of
// their own (CausticCache), checked against irradiance known exactly, and
// the indirect ray gather through a mirror.
#include "IndirectReference.h"
#include "SessionRun.h"
#include "TestScenes.h"

#include "cache/CausticCache.h"
#include "cache/ProgressiveSession.h"
#include "core/SceneChange.h"
#include "core/SmoothSpecular.h"
#include "core/raytrace/BounceCount.h"
#include "gpu_sampling/SamplerFactory.h"
#include "gpu_sampling/gl/GlContext.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/reference/Lambert.h"
#include "gpu_sampling/indirect/RadianceProxy.h"
#include "gpu_sampling/indirect/RayGather.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ml {
namespace {

using test::addQuad;
using test::kX;
using test::kY;
using test::kZ;
using test::quadMesh;
using test::sceneOf;

constexpr double kRadiance = 10.0;  // the test light's Ke, W·sr⁻¹·m⁻²

Material emitter() { return Material::diffuse("light", Rgb(0.0), Rgb(kRadiance)); }
Material grey() { return Material::diffuse("grey", Rgb(0.5)); }

Material mirror(double reflectance) {
    Material m = Material::diffuse("mirror", Rgb(0.0));
    m.smooth.kind = SpecularKind::Mirror;
    m.smooth.reflectance = Rgb(reflectance);
    return m;
}

Material glass(double ior) {
    Material m = Material::diffuse("glass", Rgb(0.0));
    m.smooth.kind = SpecularKind::Glass;
    m.smooth.ior = ior;
    return m;
}

// A slab of glass between heights lo and hi over the square |x|, |z| ≤
// half: its top facing up and its bottom facing down, no sides (light inside
// a closed slab that meets its sides is reflected back by total internal
// reflection, towards the middle: the infinite slab of the reference has none).
Mesh slabMesh(uint32_t material, double lo, double hi, double half) {
    Mesh m;
    m.name = "slab";
    addQuad(m, material, Vec3(-half, hi, -half), 2 * half * kZ, 2 * half * kX);  // top, +y
    addQuad(m, material, Vec3(-half, lo, -half), 2 * half * kX, 2 * half * kZ);  // bottom, −y
    return m;
}

// The caustic mesh's floor vertices (y = 0, facing up) whose horizontal
// position passes `keep`, with their irradiance and standard error.
struct FloorPoint {
    Vec3 x;
    double e, se;
};
template <class Keep>
std::vector<FloorPoint> floorPoints(const IrradianceMeshCopy& m, Keep keep) {
    std::vector<FloorPoint> out;
    for (size_t v = 0; v < m.positions.size(); ++v)
        if (std::abs(m.positions[v].y) < 1e-9 && m.normals[v].y > 0.99 && keep(m.positions[v]))
            out.push_back({m.positions[v], m.irradiance[v].g, m.standardError[v].g});
    return out;
}

// A small light (0.2 × 0.2, Ke kRadiance) at y = 0.5 facing up, under a
// ceiling at y = 1 of the given material, over the grey floor 3 × 3.
Scene lampUnder(const Material& ceiling) {
    return sceneOf("mirror", {emitter(), grey(), ceiling},
                   {quadMesh("light", 0, Vec3(-0.1, 0.5, -0.1), 0.2 * kZ, 0.2 * kX), test::floorMesh(),
                    quadMesh("mirror", 2, Vec3(-1.5, 1.0, -1.5), 3.0 * kX, 3.0 * kZ)});
}

CausticSettings testSettings() {
    CausticSettings s;
    s.edgeFraction = 1.0 / 64;
    // A wide first kernel (1/32 of the diagonal, 0.14 here) gathers 4× the
    // photons of the default: 1-2% noise per vertex in a second of
    // photons. Its blur is second order: (R²/8)·|∇²E|/E ≤ 0.3% for the
    // smooth irradiance of a small light 1 to 1.5 units away.
    s.radiusFraction = 1.0 / 32;
    s.photonsPerRound = size_t(1) << 16;
    return s;
}

// Every vertex within 4 of its own standard errors plus `bias` of the
// reference, and the mean ratio within 1 ± (4 standard errors of the mean +
// bias). Vertices share photons (a kernel of radius R = 2 edges holds about
// π·2² = 12.6 vertices), so the mean's error is that of n / 12.6
// independent vertices, not n.
template <class Reference>
void expectAgrees(const std::vector<FloorPoint>& points, Reference reference, double bias) {
    ASSERT_GE(points.size(), 10u);
    const CausticSettings s = testSettings();
    const double shared = kPi * std::pow(s.radiusFraction / s.edgeFraction, 2);
    double sum = 0, sumRef = 0, relative2 = 0;
    for (const FloorPoint& p : points) {
        const double ref = reference(p.x);
        ASSERT_GT(ref, 0);
        EXPECT_NEAR(p.e, ref, 4 * p.se + bias * ref) << "at " << p.x.x << "," << p.x.z;
        sum += p.e, sumRef += ref, relative2 += (p.se / ref) * (p.se / ref);
    }
    const double meanError = std::sqrt(relative2 / double(points.size())) * std::sqrt(shared / double(points.size()));
    EXPECT_NEAR(sum / sumRef, 1.0, 4 * meanError + bias);
    std::printf("%zu floor vertices: mean ratio to the reference %.4f (its standard error %.2f%%)\n", points.size(),
                sum / sumRef, 100 * meanError);
}

// (a) A small light at y = 0.5 facing up, under a mirror ceiling at y = 1
// (reflectance 0.9) above a grey floor: the floor's caustic is the light's
// image (at y = 1.5, facing down) seen through the mirror, times 0.9.
TEST(Caustics, MirrorShowsTheLightsImageOnTheFloor) {
    const double r = 0.9;
    const Scene scene = sceneOf("mirror", {emitter(), grey(), mirror(r)},
                                {quadMesh("light", 0, Vec3(-0.1, 0.5, -0.1), 0.2 * kZ, 0.2 * kX),
                                 test::floorMesh(), quadMesh("mirror", 2, Vec3(-1.5, 1.0, -1.5), 3.0 * kX, 3.0 * kZ)});
    CausticCache cache(scene, testSettings());
    ASSERT_TRUE(cache.active()) << cache.describe();
    for (int k = 0; k < 12; ++k) cache.round(7);
    const IrradianceMeshCopy m = cache.copyMesh();
    const std::vector<Vec3> image = {Vec3(-0.1, 1.5, -0.1), Vec3(0.1, 1.5, -0.1), Vec3(0.1, 1.5, 0.1),
                                     Vec3(-0.1, 1.5, 0.1)};
    // Away from the light's own shadow (|x|, |z| < 0.2 sees the image
    // through the light's back) and 0.5 from the floor's edge, where the
    // kernel's disc would reach past it.
    const auto points = floorPoints(m, [](const Vec3& x) {
        const double d = std::max(std::abs(x.x), std::abs(x.z));
        return d >= 0.35 && d <= 1.0;
    });
    expectAgrees(points, [&](const Vec3& x) { return r * kRadiance * cosineSolidAngle(x, kY, image); }, 0.005);
    // Right under the light its back hides the image: the photons leave
    // that shadow dark (below 5% of the lit floor around it).
    for (const FloorPoint& p : floorPoints(m, [](const Vec3& x) { return std::max(std::abs(x.x), std::abs(x.z)) < 0.02; }))
        EXPECT_LT(p.e, 0.05 * r * kRadiance * cosineSolidAngle(Vec3(0.5, 0, 0), kY, image));
}

// Irradiance at floor point x under the light 0.2 × 0.2 at y = 1 (facing
// down) through a glass slab between y = 0.4 and 0.5 of index n: the
// directions from x whose refracted path meets the light, each weighted by
// the two interfaces' transmission (1 − F)², integrated exactly enough
// (Simpson in θ over the interval that meets the light, per φ).
double slabIrradiance(const Vec3& x, double n) {
    const double below = 0.4 + 0.5, inside = 0.1, half = 0.1;
    const auto rho = [&](double theta) {
        const double s = std::sin(theta) / n;
        return below * std::tan(theta) + inside * s / std::sqrt(1 - s * s);
    };
    const auto thetaAt = [&](double target) {  // ρ is increasing: bisection
        double lo = 0, hi = 1.5;
        for (int i = 0; i < 80; ++i) (rho(0.5 * (lo + hi)) < target ? lo : hi) = 0.5 * (lo + hi);
        return 0.5 * (lo + hi);
    };
    const auto f = [&](double theta) {
        const double t = 1 - fresnelDielectric(std::cos(theta), n);
        return t * t * std::cos(theta) * std::sin(theta);
    };
    const int phis = 4096, steps = 128;
    double sum = 0;
    for (int k = 0; k < phis; ++k) {
        const double phi = 2 * kPi * (k + 0.5) / phis;
        const double dx = std::cos(phi), dz = std::sin(phi);
        // The ray x + ρ(dx, dz) inside the square |·| ≤ half: ρ in [a, b].
        double a = 0, b = kInf;
        for (const auto& [p, d] : {std::pair{x.x, dx}, std::pair{x.z, dz}}) {
            if (std::abs(d) < 1e-15) {
                if (std::abs(p) > half) b = -1;
                continue;
            }
            const double t1 = (-half - p) / d, t2 = (half - p) / d;
            a = std::max(a, std::min(t1, t2));
            b = std::min(b, std::max(t1, t2));
        }
        if (!(b > a)) continue;
        const double t0 = thetaAt(a), t1 = thetaAt(b), h = (t1 - t0) / steps;
        double s = f(t0) + f(t1);
        for (int i = 1; i < steps; ++i) s += (i % 2 ? 4 : 2) * f(t0 + i * h);
        sum += s * h / 3;
    }
    return kRadiance * sum * 2 * kPi / phis;
}

// (b) The same light facing down over a glass slab (n = 1.5) over the
// floor: the caustic is the light's irradiance through the slab, times the
// Fresnel transmission of its two faces, and nearer than without it (the
// slab makes the light look closer by 0.1 (1 − 1/n)).
TEST(Caustics, GlassSlabTransmitsByFresnel) {
    const double n = 1.5;
    const Scene scene = sceneOf("slab", {emitter(), grey(), glass(n)},
                                {quadMesh("light", 0, Vec3(-0.1, 1.0, -0.1), 0.2 * kX, 0.2 * kZ), test::floorMesh(),
                                 slabMesh(2, 0.4, 0.5, 1.5)});
    CausticCache cache(scene, testSettings());
    ASSERT_TRUE(cache.active()) << cache.describe();
    for (int k = 0; k < 12; ++k) cache.round(11);
    const auto points =
        floorPoints(cache.copyMesh(), [](const Vec3& x) { return std::max(std::abs(x.x), std::abs(x.z)) <= 0.4; });
    // Near normal incidence (1 − F)² = 0.9216 of what arrives with no slab.
    const Vec3 centre(0.0);
    const std::vector<Vec3> light = {Vec3(-0.1, 1, -0.1), Vec3(0.1, 1, -0.1), Vec3(0.1, 1, 0.1), Vec3(-0.1, 1, 0.1)};
    const double t = 1 - fresnelDielectric(1.0, n);
    EXPECT_NEAR(slabIrradiance(centre, n) / (kRadiance * cosineSolidAngle(centre, kY, light)),
                t * t / std::pow(1 - 0.1 * (1 - 1 / n), 2), 0.01);
    // Light reflected twice inside the slab (F² = 0.16%) lands too, a little
    // aside: within the 0.5% allowed for bias.
    expectAgrees(points, [&](const Vec3& x) { return slabIrradiance(x, n); }, 0.005);
}

// (c) No specular material: no photons, no BVH, no caustic mesh, and a
// session has no caustic cache (its snapshots' meshes are unchanged).
TEST(Caustics, NoSpecularMaterialMakesNoCausticMesh) {
    const Scene scene = sceneOf("bench", {Material::diffuse("light", Rgb(0.0), Rgb(kRadiance)), grey()},
                                {test::unitLight(), test::floorMesh()});
    CausticCache cache(scene);
    EXPECT_FALSE(cache.active());
    EXPECT_EQ(cache.vertexCount(), 0u);
    EXPECT_EQ(cache.describe(), "no specular materials");
    cache.round(1);
    EXPECT_EQ(cache.photonsEmitted(), 0u);
    SessionSettings settings;
    settings.indirect = IndirectSettings{};
    ProgressiveSession session(scene, settings, [] { return WorkerSamplers{}; });
    EXPECT_EQ(session.caustics(), nullptr);
}

// A moved object moves its caustics: the session traces them again in the
// changed scene (none once the mirror is taken below the floor, where the
// light facing up cannot see it; photons anew once it is back).
TEST(Caustics, ASceneChangeTracesThemAgain) {
    Scene scene = sceneOf("mirror", {emitter(), grey(), mirror(0.9)},
                          {quadMesh("light", 0, Vec3(-0.1, 0.5, -0.1), 0.2 * kZ, 0.2 * kX), test::floorMesh(),
                           quadMesh("mirror", 2, Vec3(-1.5, 1.0, -1.5), 3.0 * kX, 3.0 * kZ)});
    SessionSettings settings;
    settings.indirect = IndirectSettings{};
    ProgressiveSession session(scene, settings, [] { return WorkerSamplers{}; });
    ASSERT_NE(session.caustics(), nullptr);
    session.applyChange(scene, SceneChange::moveObject("mirror", Vec3(0.0, -3.0, 0.0)));
    EXPECT_EQ(session.caustics(), nullptr);
    session.applyChange(scene, SceneChange::moveObject("mirror", Vec3(0.0, 3.0, 0.0)));
    ASSERT_NE(session.caustics(), nullptr);
    EXPECT_EQ(session.caustics()->photonsEmitted(), 0u);
}

// A lamp facing up lights only the mirror ceiling (Kd 0) above a grey
// floor: direct light meets no diffuse reflectance, but the mirror sends
// 0.9 of it on to the floor. The bounce plan counts what the mirror sends
// on, reflected where it lands as by the scene's area-weighted albedo (the
// albedo light meets is 0.9 times that, exactly: every lit point is on the
// mirror), so the session has indirect light and traces the caustic; with
// the mirror a black diffuse ceiling instead there is none.
TEST(Caustics, ALampLightingOnlyAMirrorStillPlansIndirectLight) {
    const BounceCount mirrored = countBounces(lampUnder(mirror(0.9)));
    EXPECT_GE(mirrored.bounces, 1);
    EXPECT_GT(mirrored.areaAlbedo, 0.2);  // the grey floor's half of the area, Kd 0.5
    EXPECT_NEAR(mirrored.meanAlbedo, 0.9 * mirrored.areaAlbedo, 1e-12);
    EXPECT_NE(mirrored.reason.find("100% of the direct light meets mirrors or glass"), std::string::npos)
        << mirrored.reason;
    const BounceCount black = countBounces(lampUnder(Material::diffuse("mirror", Rgb(0.0))));
    EXPECT_EQ(black.bounces, 0);
    EXPECT_EQ(black.reason, "the surfaces that receive direct light are black: they reflect nothing");
}

// The same lamp under the mirror ceiling (reflectance r = 0.9), in a
// session: the floor's only light is the caustic, the lamp's image at
// y = 1.5, and bounce 1 at the floor is that caustic reflected by the floor
// (Kd 0.5) and seen again in the mirror: r · 0.5/π ∫ E_c(y) cos cos / d² over
// the floor's image at y = 2, computed here on a 90 × 90 grid of it, E_c
// on 8 × 8 points of the lamp's image, each blocked where the lamp's back
// (|x|, |z| < 0.1 at y = 0.5, and its image at y = 1.5) lies on the straight
// line of the unfolded path. Bounce 1 must not be gathered before the
// caustics' first photons (it held none of their light, 12% of the floor's
// irradiance at (0.5, 0, 0), and kept too little of it: its first-pass
// samples stay in its means). Tolerance 6% on the mean over 0.4 ≤ |x|, |z|
// ≤ 1 (PPM's first kernel, 1/32 of the diagonal, blurs by ≤ 0.3%; the
// floor's caustic past 1.36 from the centre is cut by the kernel's disc at
// the edge, ≤ 2% of the integral; bounce 1's noise tolerance of 3% per
// vertex averages below 1% over the vertices; the first photon round's
// noise, which stays in the first-pass samples, averages out likewise; the
// 8 × 8 and 90² quadratures are within 0.5%).
TEST(Caustics, BounceOneReflectsTheCausticsOnceTheyAreTraced) {
    const double r = 0.9;
    const Scene scene = lampUnder(mirror(r));
    DirectChoice direct;
    direct.backend = GlBackend::OsMesa;
    IndirectChoice indirect;
    indirect.method = "raytrace";
    indirect.bounces.forced = 1;
    indirect.decide(scene);
    SessionSettings settings;
    settings.worker.threads = 1;
    settings.indirect = indirect.solver;
    settings.caustics = testSettings();
    StopRule stop;
    stop.samples = 40000;
    ProgressiveSession session(scene, settings, samplerFactory(scene, direct, indirect), stop);
    test::refineUntilStopped(session, stop);
    ASSERT_NE(session.caustics(), nullptr);
    ASSERT_GT(session.caustics()->photonsEmitted(), 0u);
    const std::vector<IrradianceMeshCopy> bounces = session.indirect()->copyMeshes();
    ASSERT_EQ(bounces.size(), 1u);

    const auto blocked = [](const Vec3& a, const Vec3& b, double height) {  // the line a→b at that height
        const Vec3 p = a + (b - a) * ((height - a.y) / (b.y - a.y));
        return std::abs(p.x) < 0.1 && std::abs(p.z) < 0.1;
    };
    const auto caustic = [&](const Vec3& y) {  // E_c on the floor, through the lamp's image at 1.5
        const int n = 8;
        double sum = 0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const Vec3 p(-0.1 + 0.2 * (i + 0.5) / n, 1.5, -0.1 + 0.2 * (j + 0.5) / n);
                if (blocked(y, p, 0.5)) continue;
                const Vec3 d = p - y;
                const double d2 = glm::dot(d, d);
                sum += d.y * d.y / (d2 * d2);  // cos at the floor × cos at the image / d²
            }
        return r * kRadiance * sum * (0.04 / (n * n));
    };
    const int g = 90;
    std::vector<double> floorE(g * g);
    for (int i = 0; i < g; ++i)
        for (int j = 0; j < g; ++j) floorE[i * g + j] = caustic(Vec3(-1.5 + 3.0 * (i + 0.5) / g, 0, -1.5 + 3.0 * (j + 0.5) / g));
    const auto bounceOne = [&](const Vec3& x) {
        double sum = 0;
        for (int i = 0; i < g; ++i)
            for (int j = 0; j < g; ++j) {
                const Vec3 y(-1.5 + 3.0 * (i + 0.5) / g, 2.0, -1.5 + 3.0 * (j + 0.5) / g);  // unfolded
                if (blocked(x, y, 0.5) || blocked(x, y, 1.5)) continue;
                const Vec3 d = y - x;
                const double d2 = glm::dot(d, d);
                sum += floorE[i * g + j] * d.y * d.y / (d2 * d2);
            }
        return r * 0.5 / kPi * sum * (9.0 / (g * g));
    };
    double sum = 0, sumRef = 0;
    int n = 0;
    const IrradianceMeshCopy& b1 = bounces[0];
    for (size_t v = 0; v < b1.positions.size(); ++v) {
        const Vec3& x = b1.positions[v];
        const double d = std::max(std::abs(x.x), std::abs(x.z));
        if (std::abs(x.y) > 1e-9 || b1.normals[v].y < 0.99 || d < 0.4 || d > 1.0) continue;
        sum += b1.irradiance[v].g;
        sumRef += bounceOne(x);
        ++n;
    }
    ASSERT_GE(n, 20);
    std::printf("bounce 1 at %d floor vertices: mean ratio to the reference %.4f (reference mean %.4g W/m2)\n", n,
                sum / sumRef, sumRef / n);
    EXPECT_NEAR(sum / sumRef, 1.0, 0.06);
}

// A mirror no light sees (facing away from the only light) has no caustics.
TEST(Caustics, AMirrorNoLightSeesHasNone) {
    const Scene scene = sceneOf("unseen", {emitter(), grey(), mirror(0.9)},
                                {test::unitLight(), test::floorMesh(),
                                 quadMesh("mirror", 2, Vec3(-0.5, 2.0, -0.5), kZ, kX)});  // above the light, facing up
    CausticCache cache(scene);
    EXPECT_FALSE(cache.active());
    EXPECT_EQ(cache.describe(), "no light sees a specular object");
}

// The indirect ray gather reads the cache where a ray ends after a mirror:
// under a mirror ceiling (y = 1, reflectance 0.9) over a floor of uniform
// irradiance E0 and Kd 0.5, a floor point gathers 0.9 × 0.5 × E0 × the
// cosine solid angle of the floor's image (y = 2) over π.
TEST(Caustics, RayGatherFollowsAMirror) {
    const double r = 0.9, e0 = 3.0;
    const Scene scene = sceneOf("gather", {emitter(), grey(), mirror(r)},  // the emitter unused: no light
                                {test::floorMesh(), quadMesh("mirror", 2, Vec3(-1.5, 1.0, -1.5), 3.0 * kX, 3.0 * kZ)});
    const IrradianceMeshCopy source = test::uniformIrradiance(scene.meshes[0], Rgb(e0));
    const MeshIrradianceLookup lookup(source, 0.1, 1e-6);
    const EmbreeScene rays(scene);
    const std::vector<char> closed = closedMeshesOf(scene);
    const std::vector<Vec3> image = {Vec3(-1.5, 2, -1.5), Vec3(1.5, 2, -1.5), Vec3(1.5, 2, 1.5), Vec3(-1.5, 2, 1.5)};
    for (const Vec3& x : {Vec3(0.0), Vec3(0.7, 0, -0.3)}) {
        const double expected = r * 0.5 * e0 * cosineSolidAngle(x, kY, image) / kPi;
        // 64 × 64 stratified rays: the mean's error is ~1e-3 of it, the
        // strata's edges against the image's (12 seeds' mean: /√12).
        double sum = 0;
        for (uint32_t seed = 0; seed < 12; ++seed)
            sum += gatherCachedRadiance(scene, rays, closed, {&lookup}, x, kY, 64, seed).g;
        EXPECT_NEAR(sum / 12, expected, 2e-3 * expected) << "at " << x.x << "," << x.z;
    }
}

}  // namespace
}  // namespace ml
