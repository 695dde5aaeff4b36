// The exact occluded irradiance against Lambert's closed form, Monte Carlo
// ray casting and the cases that break naive implementations.
#include "core/Error.h"
#include "core/reference/ExactIrradiance.h"
#include "core/reference/Lambert.h"
#include "core/scenes/BenchScene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

using namespace ml;

namespace {

const Vec3 kUp(0, 1, 0);

std::vector<Vec3> asPolygon(const std::vector<Triangle3>& quad) {
    // Two triangles (a, b, c), (a, c, d) of a quad, as makeBenchScene builds them.
    return {quad[0][0], quad[0][1], quad[0][2], quad[1][2]};
}

// Axis-aligned horizontal quad [x0, x1] × [z0, z1] at height y as two
// triangles; facing down (emitting towards −y) when `down`.
std::vector<Triangle3> horizontalQuad(double x0, double x1, double z0, double z1, double y, bool down) {
    const Vec3 a(x0, y, z0), b(x1, y, z0), c(x1, y, z1), d(x0, y, z1);
    if (down) return {Triangle3{a, b, c}, Triangle3{a, c, d}};
    return {Triangle3{a, c, b}, Triangle3{a, d, c}};
}

// The visible part of the bench light when everything at X > edge is hidden.
std::vector<Vec3> lightLeftOf(double edge) {
    return {Vec3(-0.5, 1, -0.5), Vec3(edge, 1, -0.5), Vec3(edge, 1, 0.5), Vec3(-0.5, 1, 0.5)};
}

std::vector<Triangle3> occludersOf(const Scene& scene) {
    std::vector<Triangle3> all;
    for (const Mesh& mesh : scene.meshes) {
        if (mesh.name == "light") continue;
        for (size_t t = 0; t < mesh.triangles.size(); ++t) all.push_back(mesh.triangle(t));
    }
    return all;
}

std::vector<Triangle3> transformed(const std::vector<Triangle3>& triangles, double scale,
                                   const Vec3& offset) {
    std::vector<Triangle3> out;
    for (const Triangle3& t : triangles)
        out.push_back({scale * t[0] + offset, scale * t[1] + offset, scale * t[2] + offset});
    return out;
}

// Möller–Trumbore: does the open segment from o to o + d cross the triangle?
bool segmentHits(const Vec3& o, const Vec3& d, const Triangle3& t) {
    const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
    const Vec3 p = glm::cross(d, e2);
    const double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-300) return false;
    const Vec3 s = o - t[0];
    const double u = glm::dot(s, p) / det;
    if (u < 0 || u > 1) return false;
    const Vec3 q = glm::cross(s, e1);
    const double v = glm::dot(d, q) / det;
    if (v < 0 || u + v > 1) return false;
    const double along = glm::dot(e2, q) / det;
    return along > 1e-9 && along < 1 - 1e-9;
}

struct Estimate {
    double mean = 0;
    double sigma = 0;  // standard deviation of the mean
};

// Uniform area sampling of the light with ray-cast visibility:
// ∫ V cos θ cos θ' / r² dA.
Estimate monteCarlo(const Vec3& x, const Vec3& n, const std::vector<Triangle3>& light,
                    const std::vector<Triangle3>& occluders, int samples, uint64_t seed) {
    std::vector<double> cdf;
    double total = 0;
    for (const Triangle3& t : light)
        cdf.push_back(total += 0.5 * glm::length(glm::cross(t[1] - t[0], t[2] - t[0])));
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    double sum = 0, sumSquares = 0;
    for (int i = 0; i < samples; ++i) {
        const auto picked = std::lower_bound(cdf.begin(), cdf.end(), uniform(rng) * total);
        const size_t k = std::min<size_t>(picked - cdf.begin(), light.size() - 1);
        const Triangle3& t = light[k];
        double u = uniform(rng), v = uniform(rng);
        if (u + v > 1) u = 1 - u, v = 1 - v;
        const Vec3 y = t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]);
        const Vec3 d = y - x;
        const double r2 = glm::dot(d, d);
        const Vec3 lightNormal = glm::normalize(glm::cross(t[1] - t[0], t[2] - t[0]));
        const double cosReceiver = glm::dot(n, d), cosLight = -glm::dot(lightNormal, d);
        double f = 0;
        if (cosReceiver > 0 && cosLight > 0) {
            const bool blocked = std::any_of(occluders.begin(), occluders.end(),
                                             [&](const Triangle3& o) { return segmentHits(x, d, o); });
            if (!blocked) f = total * cosReceiver * cosLight / (r2 * r2);
        }
        sum += f;
        sumSquares += f * f;
    }
    const double mean = sum / samples;
    const double variance = std::max(0.0, sumSquares / samples - mean * mean);
    return {mean, std::sqrt(variance / (samples - 1))};
}

void expectRelative(double expected, double actual, double tolerance) {
    EXPECT_NEAR(actual, expected, tolerance * std::abs(expected)) << "expected " << expected;
}

}  // namespace

TEST(ExactIrradiance, WithoutOccludersEqualsLambert) {
    const Scene bench = makeBenchScene();
    const std::vector<Triangle3>& light = bench.lights[0].geometry;
    const std::vector<Vec3> polygon = asPolygon(light);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> coordinate(-2.0, 2.0);
    for (int i = 0; i < 200; ++i) {
        const Vec3 x(coordinate(rng), coordinate(rng) * 0.5, coordinate(rng));
        const Vec3 n = glm::normalize(Vec3(coordinate(rng), coordinate(rng), coordinate(rng)));
        const double lambert = cosineSolidAngle(x, n, polygon);
        EXPECT_NEAR(exactVisibleCosineSolidAngle(x, n, light, {}), lambert, 1e-13 * (1 + lambert));
    }
}

TEST(ExactIrradiance, MatchesMonteCarloOnTheBench) {
    const Scene bench = makeBenchScene();
    const ExactDirect exact(bench);
    const std::vector<Triangle3> occluders = occludersOf(bench);
    const ReceiverPoint receivers[] = {
        {Vec3(0, 0, 0), kUp},                                        // centre: L-shaped visible part
        {Vec3(0.5, 0, 0.3), kUp},                                    // penumbra of two edges
        {Vec3(-0.6, 0, -0.5), kUp},                                  // penumbra near its outer edge
        {Vec3(0.1, 0, -0.1), kUp},                                   // full shadow, all edges aligned
        {Vec3(0.3, 0.2, -0.6), glm::normalize(Vec3(1.0, 1.0, 0.5))},  // tilted, above the floor
        {Vec3(-0.3, 0.1, -0.7), glm::normalize(Vec3(0.3, 1.0, -1.0))},  // light straddles the horizon
    };
    uint64_t seed = 1;
    for (const ReceiverPoint& r : receivers) {
        const double value = exact.cosineSolidAngle(0, r.position, r.normal);
        const Estimate mc =
            monteCarlo(r.position, r.normal, bench.lights[0].geometry, occluders, 2'000'000, seed++);
        EXPECT_NEAR(value, mc.mean, 5 * mc.sigma + 1e-12)
            << "receiver " << r.position.x << " " << r.position.y << " " << r.position.z;
        EXPECT_LT(value, exact.unoccludedCosineSolidAngle(0, r.position, r.normal) + 1e-15);
    }
}

TEST(ExactIrradiance, SubdividedOccluderCastsTheSameShadow) {
    // The cost bench's 7,200-triangle occluder: its pieces are merged back
    // into one polygon before the Boolean operations.
    const ExactDirect whole(makeBenchScene(1));
    const ExactDirect split(makeBenchScene(60));
    for (const ReceiverPoint& r : makeBenchReceivers(6)) {
        const double expected = whole.cosineSolidAngle(0, r.position, r.normal);
        EXPECT_NEAR(split.cosineSolidAngle(0, r.position, r.normal), expected, 1e-12 * expected + 1e-15);
    }
}

TEST(ExactIrradiance, NonConvexAndOverlappingOccluders) {
    // An L of three 0.2 × 0.2 cells at y = 0.5 and a strip at y = 0.7 whose
    // shadows overlap: the tiles of the L cannot merge into one convex
    // polygon, so the Boolean union gets them one by one.
    const std::vector<Triangle3> light = horizontalQuad(-0.5, 0.5, -0.5, 0.5, 1.0, true);
    const auto lShape = [](int subdivisions) {
        std::vector<Triangle3> triangles;
        const double cells[3][2] = {{-0.2, -0.2}, {0.0, -0.2}, {-0.2, 0.0}};
        const double step = 0.2 / subdivisions;
        for (const auto& cell : cells)
            for (int i = 0; i < subdivisions; ++i)
                for (int j = 0; j < subdivisions; ++j) {
                    const double x0 = cell[0] + i * step, z0 = cell[1] + j * step;
                    for (const Triangle3& t : horizontalQuad(x0, x0 + step, z0, z0 + step, 0.5, true))
                        triangles.push_back(t);
                }
        return triangles;
    };
    std::vector<Triangle3> coarse = lShape(1), fine = lShape(5);
    for (const Triangle3& t : horizontalQuad(-0.05, 0.3, -0.1, 0.05, 0.7, true)) {
        coarse.push_back(t);
        fine.push_back(t);
    }
    const ReceiverPoint receivers[] = {{Vec3(0.0, 0.0, 0.0), kUp}, {Vec3(0.15, 0.1, -0.1), kUp},
                                       {Vec3(-0.2, 0.2, 0.25), glm::normalize(Vec3(0.2, 1.0, -0.3))}};
    uint64_t seed = 100;
    for (const ReceiverPoint& r : receivers) {
        const double value = exactVisibleCosineSolidAngle(r.position, r.normal, light, coarse);
        EXPECT_LT(value, exactVisibleCosineSolidAngle(r.position, r.normal, light, {}) - 0.05);
        EXPECT_NEAR(exactVisibleCosineSolidAngle(r.position, r.normal, light, fine), value, 1e-12 * value);
        const Estimate mc = monteCarlo(r.position, r.normal, light, coarse, 2'000'000, seed++);
        EXPECT_NEAR(value, mc.mean, 5 * mc.sigma + 1e-12);
    }
}

TEST(ExactIrradiance, IrradianceIsRadianceTimesVisibleCosineSolidAngle) {
    Scene bench = makeBenchScene();
    bench.materials[0].ke = Rgb(2.0, 1.0, 0.5);
    bench.finalize();
    const ExactDirect exact(bench);
    const Vec3 x(0.2, 0, 0.1);
    const double value = exact.cosineSolidAngle(0, x, kUp);
    ASSERT_GT(value, 0.0);
    const Rgb e = exact.irradiance(0, x, kUp);
    EXPECT_EQ(e, Rgb(2.0, 1.0, 0.5) * value);
}

TEST(ExactIrradiance, FullyHiddenIsZero) {
    const ExactDirect exact(makeBenchScene(3));
    // Under the occluder's centre, a quarter of the way up: the pyramid to
    // the light is 1/3 of the light's size at the occluder, inside it.
    EXPECT_EQ(exact.cosineSolidAngle(0, Vec3(0.05, 0.25, -0.05), kUp), 0.0);
    EXPECT_GT(exact.unoccludedCosineSolidAngle(0, Vec3(0.05, 0.25, -0.05), kUp), 1.0);
}

TEST(ExactIrradiance, OtherLightsOcclude) {
    // The bench with the occluder made emissive: it still casts its shadow.
    const Scene bench = makeBenchScene();
    Scene twoLights = bench;
    twoLights.materials[1].ke = Rgb(0.5);
    twoLights.finalize();
    ASSERT_EQ(twoLights.lights.size(), 2u);
    const ExactDirect one(bench), two(twoLights);
    const Vec3 x(0.0, 0.0, 0.0);
    const double expected = one.cosineSolidAngle(0, x, kUp);
    EXPECT_LT(expected, 0.5 * one.unoccludedCosineSolidAngle(0, x, kUp));
    EXPECT_NEAR(two.cosineSolidAngle(0, x, kUp), expected, 1e-14);
}

TEST(ExactIrradiance, NonPlanarLightIsAnInputError) {
    Scene scene;
    Material emitter;
    emitter.name = "bent";
    emitter.ke = Rgb(1.0);
    scene.materials = {emitter};
    Mesh mesh;
    mesh.name = "fold";
    mesh.positions = {Vec3(0, 1, 0), Vec3(1, 1, 0), Vec3(1, 1, 1), Vec3(0, 1.5, 1)};
    mesh.normals.assign(4, Vec3(0, -1, 0));
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    mesh.materials = {0, 0};
    mesh.sourceLines = {0, 0};
    scene.meshes = {mesh};
    scene.finalize();
    const ExactDirect exact(scene);
    try {
        exact.irradiance(0, Vec3(0.5, 0, 0.5), kUp);
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "light 'bent' is not planar: the exact method needs planar lights");
    }
    EXPECT_THROW(exact.cosineSolidAngle(3, Vec3(0.0), kUp), std::out_of_range);
}

// Hard cases

TEST(ExactIrradianceHardCases, ScaleAndPositionInvariant) {
    const Scene bench = makeBenchScene(4);
    const std::vector<Triangle3>& light = bench.lights[0].geometry;
    const std::vector<Triangle3> occluders = occludersOf(bench);
    const ReceiverPoint receivers[] = {{Vec3(0, 0, 0), kUp},
                                       {Vec3(0.5, 0, 0.3), kUp},
                                       {Vec3(1.1, 0.7, 0.2), glm::normalize(Vec3(-0.2, 1.0, -1.0))}};
    for (const ReceiverPoint& r : receivers) {
        const double reference = exactVisibleCosineSolidAngle(r.position, r.normal, light, occluders);
        ASSERT_GT(reference, 0.0);
        for (double scale : {1e-3, 1e4}) {
            const Vec3 offset = scale * Vec3(3.0, -7.0, 11.0);
            const double value = exactVisibleCosineSolidAngle(scale * r.position + offset, r.normal,
                                                              transformed(light, scale, offset),
                                                              transformed(occluders, scale, offset));
            expectRelative(reference, value, 1e-9);
        }
    }
}

TEST(ExactIrradianceHardCases, ReceiverVeryCloseToTheLightPlane) {
    const std::vector<Triangle3> light = horizontalQuad(-0.5, 0.5, -0.5, 0.5, 1.0, true);
    const double h = 1e-4;
    const Vec3 x(0.1, 1.0 - h, -0.2);
    const std::vector<Vec3> whole = asPolygon(light);
    // Unoccluded: the centred-rectangle closed form, nearly π.
    const double unoccluded = exactVisibleCosineSolidAngle(x, kUp, light, {});
    expectRelative(cosineSolidAngle(x, kUp, whole), unoccluded, 1e-13);
    EXPECT_GT(unoccluded, kPi - 1e-3);
    // A half-plane X > e halfway between x and the light hides about X > 2e − x.
    const double e = 0.15, y = 1.0 - h / 2;
    const std::vector<Triangle3> halfway = horizontalQuad(e, 5.0, -5.0, 5.0, y, true);
    const double edge = x.x + (e - x.x) * (1.0 - x.y) / (y - x.y);
    expectRelative(cosineSolidAngle(x, kUp, lightLeftOf(edge)),
                   exactVisibleCosineSolidAngle(x, kUp, light, halfway), 1e-12);
    // Beside the light, just below its plane: small and finite. Lambert's
    // edge terms are O(1) and cancel down to ~1e-7 here, so both sides are
    // good to ~1e-16 absolute only.
    const Vec3 beside(0.7, 1.0 - h, 0.0);
    const double grazing = exactVisibleCosineSolidAngle(beside, kUp, light, {});
    EXPECT_GT(grazing, 1e-8);
    EXPECT_NEAR(cosineSolidAngle(beside, kUp, whole), grazing, 1e-15);
}

TEST(ExactIrradianceHardCases, LightStraddlingTheHorizon) {
    const Scene bench = makeBenchScene();
    const std::vector<Triangle3>& light = bench.lights[0].geometry;
    // The receiver's horizon cuts the light in two.
    const Vec3 x(0.2, 0.6, 0.0), n(1.0, 0.0, 0.0);
    const double unoccluded = exactVisibleCosineSolidAngle(x, n, light, {});
    expectRelative(cosineSolidAngle(x, n, asPolygon(light)), unoccluded, 1e-13);
    // Its visible half is the part X ≥ 0.2: a rectangle in front of x.
    expectRelative(cosineSolidAngle(x, n, {Vec3(0.2, 1, -0.5), Vec3(0.5, 1, -0.5), Vec3(0.5, 1, 0.5),
                                           Vec3(0.2, 1, 0.5)}),
                   unoccluded, 1e-12);
    // Hiding the part below the horizon changes nothing.
    const std::vector<Triangle3> belowHorizon = horizontalQuad(-0.5, 0.1, -0.5, 0.5, 0.9, true);
    EXPECT_EQ(exactVisibleCosineSolidAngle(x, n, light, belowHorizon), unoccluded);
}

TEST(ExactIrradianceHardCases, LightSeenEdgeOnOrFromBehind) {
    const std::vector<Triangle3> light = horizontalQuad(-0.5, 0.5, -0.5, 0.5, 1.0, true);
    const Vec3 n = glm::normalize(Vec3(-1.0, 0.5, 0.0));
    EXPECT_EQ(exactVisibleCosineSolidAngle(Vec3(1.0, 1.0, 0.1), n, light, {}), 0.0);      // in its plane
    EXPECT_EQ(exactVisibleCosineSolidAngle(Vec3(0.0, 1.0, 0.0), kUp, light, {}), 0.0);    // on it
    EXPECT_EQ(exactVisibleCosineSolidAngle(Vec3(0.0, 1.5, 0.0), -kUp, light, {}), 0.0);   // behind it
    // Just below the plane (offsets exact in binary): tiny, positive, linear
    // in the offset.
    const double a = exactVisibleCosineSolidAngle(Vec3(1.0, 1.0 - std::ldexp(1.0, -30), 0.1), n, light, {});
    const double b = exactVisibleCosineSolidAngle(Vec3(1.0, 1.0 - std::ldexp(1.0, -33), 0.1), n, light, {});
    EXPECT_GT(a, 0.0);
    EXPECT_LT(a, 1e-8);
    EXPECT_NEAR(b / a, 0.125, 1e-6);
}

TEST(ExactIrradianceHardCases, OccluderTouchingTheReceiver) {
    const std::vector<Triangle3> light = horizontalQuad(-0.5, 0.5, -0.5, 0.5, 1.0, true);
    const Vec3 x(0.0);
    const double unoccluded = exactVisibleCosineSolidAngle(x, kUp, light, {});
    // A box [0, 0.2] × [0, 0.2] × [−0.1, 0.1] standing on the floor, x on its
    // bottom edge: the faces through x are seen edge-on, its top hides
    // exactly the half X > 0 of the light (by symmetry, half the value).
    const Vec3 lo(0.0, 0.0, -0.1), hi(0.2, 0.2, 0.1);
    std::vector<Triangle3> box = horizontalQuad(lo.x, hi.x, lo.z, hi.z, hi.y, true);
    for (const Triangle3& t : horizontalQuad(lo.x, hi.x, lo.z, hi.z, lo.y, false)) box.push_back(t);
    const Vec3 c[8] = {Vec3(lo.x, lo.y, lo.z), Vec3(hi.x, lo.y, lo.z), Vec3(hi.x, hi.y, lo.z),
                       Vec3(lo.x, hi.y, lo.z), Vec3(lo.x, lo.y, hi.z), Vec3(hi.x, lo.y, hi.z),
                       Vec3(hi.x, hi.y, hi.z), Vec3(lo.x, hi.y, hi.z)};
    const int sides[4][4] = {{0, 1, 2, 3}, {4, 7, 6, 5}, {0, 3, 7, 4}, {1, 5, 6, 2}};
    for (const auto& s : sides) {
        box.push_back({c[s[0]], c[s[1]], c[s[2]]});
        box.push_back({c[s[0]], c[s[2]], c[s[3]]});
    }
    expectRelative(0.5 * unoccluded, exactVisibleCosineSolidAngle(x, kUp, light, box), 1e-12);
    // A lid 1e-4 above x, its edge right over x: hides the half X > 0.
    const std::vector<Triangle3> lid = horizontalQuad(0.0, 0.01, -0.01, 0.01, 1e-4, true);
    expectRelative(0.5 * unoccluded, exactVisibleCosineSolidAngle(x, kUp, light, lid), 1e-12);
    // A lid 1e-4 above x covering it hides everything.
    const std::vector<Triangle3> cap = horizontalQuad(-0.01, 0.01, -0.01, 0.01, 1e-4, true);
    EXPECT_EQ(exactVisibleCosineSolidAngle(x, kUp, light, cap), 0.0);
    // A slanted triangle with a corner at x is seen edge-on: it hides nothing.
    const std::vector<Triangle3> slanted = {{x, Vec3(0.3, 0.4, -0.2), Vec3(-0.2, 0.5, 0.3)}};
    EXPECT_EQ(exactVisibleCosineSolidAngle(x, kUp, light, slanted), unoccluded);
}

TEST(ExactIrradianceHardCases, OccluderJustBelowTheLight) {
    const std::vector<Triangle3> light = horizontalQuad(-0.5, 0.5, -0.5, 0.5, 1.0, true);
    const Vec3 x(-0.3, 0.0, 0.2);
    // A half-plane X > e at 1e-4 below the light hides X > x + (e − x)/(1 − 1e-4).
    const double e = 0.1, gap = 1e-4;
    const std::vector<Triangle3> nearLight = horizontalQuad(e, 5.0, -5.0, 5.0, 1.0 - gap, true);
    const double edge = x.x + (e - x.x) / (1.0 - gap);
    expectRelative(cosineSolidAngle(x, kUp, lightLeftOf(edge)),
                   exactVisibleCosineSolidAngle(x, kUp, light, nearLight), 1e-12);
    // In the light's own plane (a backing panel, say) it hides nothing.
    const std::vector<Triangle3> coplanar = horizontalQuad(-2.0, 2.0, -2.0, 2.0, 1.0, true);
    const double open = exactVisibleCosineSolidAngle(x, kUp, light, {});
    EXPECT_EQ(exactVisibleCosineSolidAngle(x, kUp, light, coplanar), open);
    // Behind the light it hides nothing either.
    const std::vector<Triangle3> behind = horizontalQuad(-2.0, 2.0, -2.0, 2.0, 1.2, true);
    EXPECT_EQ(exactVisibleCosineSolidAngle(x, kUp, light, behind), open);
}

TEST(ExactIrradianceHardCases, TinyLightFarAway) {
    // A 1e-3 square 1e3 away, half hidden by a half-plane halfway, X > 0.
    const double s = 1e-3, d = 1e3;
    const std::vector<Triangle3> light = horizontalQuad(-s / 2, s / 2, -s / 2, s / 2, d, true);
    const std::vector<Triangle3> halfPlane = horizontalQuad(0.0, 1.0, -1.0, 1.0, d / 2, true);
    const Vec3 x(0.0);
    const double unoccluded = exactVisibleCosineSolidAngle(x, kUp, light, {});
    expectRelative(s * s / (d * d), unoccluded, 1e-6);  // A/d² to O((s/d)²)
    expectRelative(0.5 * unoccluded, exactVisibleCosineSolidAngle(x, kUp, light, halfPlane), 1e-12);
    // Off axis and tilted: against Lambert on the visible rectangle.
    const Vec3 y(3.0, 0.0, -1.0), n = glm::normalize(Vec3(0.1, 1.0, 0.2));
    const std::vector<Triangle3> edgeAbove = horizontalQuad(1.5, 4.0, -4.0, 4.0, d / 2, true);
    // Seen from y, the edge X = 1.5 at height d/2 lands at X = 2·1.5 − 3 = 0.
    const std::vector<Vec3> visible = {Vec3(-s / 2, d, -s / 2), Vec3(0, d, -s / 2), Vec3(0, d, s / 2),
                                       Vec3(-s / 2, d, s / 2)};
    expectRelative(cosineSolidAngle(y, n, visible), exactVisibleCosineSolidAngle(y, n, light, edgeAbove),
                   1e-9);
}
