// Lambert's cosine-weighted solid angle and the polygon solid angle against
// closed forms derived independently of the edge sum.
#include "core/reference/Lambert.h"

#include <gtest/gtest.h>

#include <random>

using namespace ml;

namespace {

// Axis-aligned rectangle [x0, x1] × [y0, y1] in the plane z = h, oriented
// counter-clockwise seen from +z.
std::vector<Vec3> rectangle(double x0, double x1, double y0, double y1, double h) {
    return {Vec3(x0, y0, h), Vec3(x1, y0, h), Vec3(x1, y1, h), Vec3(x0, y1, h)};
}

// Cosine-weighted solid angle of the rectangle [0, a] × [0, b] at height h
// seen from the origin with normal +z (a corner above the receiver): on the
// two edges that do not meet the axis, n·ĝ = a/√(a² + h²) and the edge
// subtends atan(b/√(a² + h²)) (the perpendicular from the receiver meets it
// at its end); the two edges meeting the axis lie in vertical planes (n·ĝ = 0).
double cornerRectangle(double a, double b, double h) {
    const double ra = std::sqrt(a * a + h * h), rb = std::sqrt(b * b + h * h);
    return 0.5 * (a / ra * std::atan(b / ra) + b / rb * std::atan(a / rb));
}

// Axis-centred 2a × 2b rectangle: four corner rectangles.
double centredRectangle(double a, double b, double h) { return 4 * cornerRectangle(a, b, h); }

void expectRelative(double expected, double actual, double tolerance) {
    EXPECT_NEAR(actual, expected, tolerance * std::abs(expected)) << "expected " << expected;
}

// A rotation of the whole configuration must not change any answer.
Mat3 someRotation() {
    const Vec3 axis = glm::normalize(Vec3(0.3, -0.8, 0.52));
    const double angle = 1.234;
    const double c = std::cos(angle), s = std::sin(angle);
    Mat3 k(0.0);
    k[1][0] = -axis.z; k[2][0] = axis.y;
    k[0][1] = axis.z;  k[2][1] = -axis.x;
    k[0][2] = -axis.y; k[1][2] = axis.x;
    return Mat3(1.0) + s * k + (1 - c) * k * k;
}

}  // namespace

TEST(Lambert, SmallSquareOnAxisIsAreaOverDistanceSquared) {
    // 4ε² X atan X with X = ε/√(1+ε²) expands to A/d² (1 − 4/3 ε² + 28/15 ε⁴ ...),
    // ε = a/h: the second-order term is checked too.
    const double a = 0.01, h = 1.0, eps = a / h;
    const double value = cosineSolidAngle(Vec3(0.0), Vec3(0, 0, 1), rectangle(-a, a, -a, a, h));
    const double areaOverD2 = 4 * a * a / (h * h);
    EXPECT_NEAR(value / areaOverD2, 1 - 4.0 / 3.0 * eps * eps, 2 * std::pow(eps, 4));
}

TEST(Lambert, TinyPolygonFarAwayKeepsItsDigits) {
    // A ~1e-3 square ~1e3 away, off axis: A cos θ cos θ' / r² is exact to
    // O((s/r)²) = 1e-12, while the edge terms are 1e6 times larger than their
    // sum. Powers of two keep the vertices exact.
    const double s = std::ldexp(1.0, -10);
    const Vec3 centre(3.0, 1024.0, -1.0), x(0.0), n = glm::normalize(Vec3(0.1, 1.0, 0.2));
    const std::vector<Vec3> square = {centre + Vec3(-s / 2, 0, -s / 2), centre + Vec3(s / 2, 0, -s / 2),
                                      centre + Vec3(s / 2, 0, s / 2), centre + Vec3(-s / 2, 0, s / 2)};
    const Vec3 d = centre - x;
    const double r = glm::length(d);
    expectRelative(s * s * glm::dot(n, d) * d.y / (r * r * r * r), cosineSolidAngle(x, n, square), 1e-10);
    expectRelative(s * s * d.y / (r * r * r), solidAngle(x, square), 1e-10);
}

TEST(Lambert, AxisCentredRectangleMatchesClosedForm) {
    const double cases[][3] = {{0.5, 0.5, 1.0}, {0.5, 2.0, 0.3}, {3.0, 0.01, 2.0}, {1.0, 1.0, 1e-4},
                               {1e-3, 2e-3, 5.0}};
    for (const auto& c : cases) {
        const double a = c[0], b = c[1], h = c[2];
        const double value = cosineSolidAngle(Vec3(0.0), Vec3(0, 0, 1), rectangle(-a, a, -b, b, h));
        expectRelative(centredRectangle(a, b, h), value, 1e-12);
    }
    // The bench light seen from under its centre: 4 s·atan(s), s = 0.5/√1.25.
    const double s = 0.5 / std::sqrt(1.25);
    expectRelative(4 * s * std::atan(s),
                   cosineSolidAngle(Vec3(0.0), Vec3(0, 1, 0),
                                    {Vec3(-0.5, 1, -0.5), Vec3(0.5, 1, -0.5), Vec3(0.5, 1, 0.5),
                                     Vec3(-0.5, 1, 0.5)}),
                   1e-14);
}

TEST(Lambert, OffAxisRectangleIsSumOfCornerRectangles) {
    // [0.2, 1.1] × [−0.4, 0.7] =
    //   [0,1.1]×[0,0.7] + [0,1.1]×[0,0.4] − [0,0.2]×[0,0.7] − [0,0.2]×[0,0.4].
    const double h = 0.6;
    const double expected = cornerRectangle(1.1, 0.7, h) + cornerRectangle(1.1, 0.4, h) -
                            cornerRectangle(0.2, 0.7, h) - cornerRectangle(0.2, 0.4, h);
    expectRelative(expected, cosineSolidAngle(Vec3(0.0), Vec3(0, 0, 1), rectangle(0.2, 1.1, -0.4, 0.7, h)),
                   1e-12);
}

TEST(Lambert, HugePolygonApproachesTheHemisphere) {
    const double a = 1e6, h = 1.0;
    const double value = cosineSolidAngle(Vec3(0.0), Vec3(0, 0, 1), rectangle(-a, a, -a, a, h));
    expectRelative(centredRectangle(a, a, h), value, 1e-12);
    EXPECT_NEAR(value, kPi, 1e-10);
    EXPECT_LE(value, kPi);
}

TEST(Lambert, HalfPlaneStraddlingTheHorizon) {
    // Receiver normal +x under the square [−L, L]² at height h: only x ≥ 0
    // is visible. Edge sum over that half: the horizon edge (in the plane
    // x = 0, n·ĝ = 1) gives 2 atan(L/h), the far edge (n·ĝ = −h/√(h² + L²))
    // −2 h/√(h² + L²) atan(L/√(h² + L²)), the other two n·ĝ = 0.
    for (double L : {0.5, 3.0, 1e7}) {
        const double h = 1.0, r = std::sqrt(h * h + L * L);
        const double expected = std::atan(L / h) - h / r * std::atan(L / r);
        const double value = cosineSolidAngle(Vec3(0.0), Vec3(1, 0, 0), rectangle(-L, L, -L, L, h));
        expectRelative(expected, value, 1e-12);
    }
    // A surface tilted by α under an (almost) infinite plane sees the sky
    // fraction (1 + cos α)/2 of π; the plane's finite size costs O(h/L).
    const double L = 1e8;
    for (double alpha : {0.3, 1.2, kPi / 2, 2.0, 3.0}) {
        const Vec3 n(std::sin(alpha), 0.0, std::cos(alpha));
        const double value = cosineSolidAngle(Vec3(0.0), n, rectangle(-L, L, -L, L, 1.0));
        EXPECT_NEAR(value, kPi * (1 + std::cos(alpha)) / 2, 1e-7) << "alpha " << alpha;
    }
}

TEST(Lambert, BelowTheHorizonIsZero) {
    EXPECT_EQ(cosineSolidAngle(Vec3(0.0), Vec3(0, 0, -1), rectangle(-1, 1, -1, 1, 1.0)), 0.0);
}

TEST(Lambert, EdgeOnIsZeroAndNearEdgeOnIsSmall) {
    const std::vector<Vec3> square = rectangle(-1, 1, -1, 1, 0.0);
    const Vec3 n = glm::normalize(Vec3(-0.8, 0.1, 0.6));  // towards the square from x = 3
    // In the plane: outside, inside, on an edge, at a vertex.
    for (const Vec3& x : {Vec3(3, 0.5, 0), Vec3(0.2, 0.1, 0), Vec3(1, 0.3, 0), Vec3(-1, -1, 0)}) {
        EXPECT_EQ(cosineSolidAngle(x, n, square), 0.0) << x.x << " " << x.y;
        EXPECT_EQ(solidAngle(x, square), 0.0);
    }
    // Just off the plane beside the square the polygon is a sliver: the value
    // is finite and shrinks linearly with the offset.
    const double small = cosineSolidAngle(Vec3(3, 0.5, -1e-9), n, square);
    const double smaller = cosineSolidAngle(Vec3(3, 0.5, -1e-10), n, square);
    EXPECT_GT(small, 0.0);
    EXPECT_LT(small, 1e-9);
    EXPECT_NEAR(smaller / small, 0.1, 1e-6);
    // Just below the interior the square fills the hemisphere in the limit.
    const double almost = cosineSolidAngle(Vec3(0.0, 0.0, -1e-9), Vec3(0, 0, 1), square);
    EXPECT_NEAR(almost, kPi, 1e-8);
}

TEST(Lambert, IndependentOfOrientationStartVertexRotationAndScale) {
    // An L-shaped (non-convex) polygon at a slant, straddling the horizon.
    const std::vector<Vec3> shape = {Vec3(-1, 0, 1.0), Vec3(1, 0, 1.5), Vec3(1, 1, 1.5),
                                     Vec3(0, 1, 1.25), Vec3(0, 2, 1.25), Vec3(-1, 2, 1.0)};
    const Vec3 x(0.1, 0.4, -0.2);
    const Vec3 n = glm::normalize(Vec3(0.7, 0.1, 0.4));
    const double reference = cosineSolidAngle(x, n, shape);
    ASSERT_GT(reference, 0.0);

    std::vector<Vec3> reversed(shape.rbegin(), shape.rend());
    expectRelative(reference, cosineSolidAngle(x, n, reversed), 1e-14);
    for (size_t shift = 1; shift < shape.size(); ++shift) {
        std::vector<Vec3> rotated(shape.begin() + shift, shape.end());
        rotated.insert(rotated.end(), shape.begin(), shape.begin() + shift);
        expectRelative(reference, cosineSolidAngle(x, n, rotated), 1e-14);
    }
    const Mat3 r = someRotation();
    const Vec3 offset(12.5, -3.0, 7.0);
    for (double scale : {1e-3, 1.0, 1e4}) {
        std::vector<Vec3> moved;
        for (const Vec3& p : shape) moved.push_back(scale * (r * p + offset));
        expectRelative(reference, cosineSolidAngle(scale * (r * x + offset), r * n, moved), 1e-12);
    }
    // Non-convex and clipped: equal to the sum of its two rectangles' parts.
    const std::vector<Vec3> lower = {Vec3(-1, 0, 1.0), Vec3(1, 0, 1.5), Vec3(1, 1, 1.5), Vec3(-1, 1, 1.0)};
    const std::vector<Vec3> upper = {Vec3(-1, 1, 1.0), Vec3(0, 1, 1.25), Vec3(0, 2, 1.25), Vec3(-1, 2, 1.0)};
    expectRelative(reference, cosineSolidAngle(x, n, lower) + cosineSolidAngle(x, n, upper), 1e-13);
}

TEST(Lambert, ClippingKeepsSharedEdgesIdentical) {
    // The same edge walked both ways must cross the plane at the same point.
    const Vec3 a(0.1, -2.0, 0.3), b(-0.7, 3.0, 1.9), m = glm::normalize(Vec3(0.2, 1.0, -0.4));
    const std::vector<Vec3> one = clipToHalfSpace({a, b, Vec3(5, 5, 5)}, m, 0.1);
    const std::vector<Vec3> two = clipToHalfSpace({b, a, Vec3(-5, 5, 5)}, m, 0.1);
    auto crossing = [&](const std::vector<Vec3>& poly) {
        for (const Vec3& p : poly)
            if (p != a && p != b && std::abs(glm::dot(m, p) - 0.1) < 1e-12 &&
                std::abs(glm::length(glm::cross(p - a, b - a))) < 1e-9)
                return p;
        return Vec3(kInf);
    };
    const Vec3 p1 = crossing(one), p2 = crossing(two);
    ASSERT_TRUE(isFinite(p1));
    EXPECT_EQ(p1, p2);
}

TEST(SolidAngle, CubeFaceFromTheCentreIsOneSixthOfTheSphere) {
    // The six faces of the cube [−1, 1]³, each counter-clockwise from outside.
    const std::vector<std::vector<Vec3>> faces = {
        {Vec3(1, -1, -1), Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(1, -1, 1)},
        {Vec3(-1, -1, -1), Vec3(-1, -1, 1), Vec3(-1, 1, 1), Vec3(-1, 1, -1)},
        {Vec3(-1, 1, -1), Vec3(-1, 1, 1), Vec3(1, 1, 1), Vec3(1, 1, -1)},
        {Vec3(-1, -1, -1), Vec3(1, -1, -1), Vec3(1, -1, 1), Vec3(-1, -1, 1)},
        {Vec3(-1, -1, 1), Vec3(1, -1, 1), Vec3(1, 1, 1), Vec3(-1, 1, 1)},
        {Vec3(-1, -1, -1), Vec3(-1, 1, -1), Vec3(1, 1, -1), Vec3(1, -1, -1)}};
    double total = 0;
    for (const auto& face : faces) {
        const double omega = solidAngle(Vec3(0.0), face);
        expectRelative(4 * kPi / 6, omega, 1e-14);
        total += omega;
    }
    expectRelative(4 * kPi, total, 1e-14);
}

TEST(SolidAngle, AxisCentredRectangleMatchesClosedForm) {
    // Ω = 4 atan(ab / (h √(a² + b² + h²))) for a 2a × 2b rectangle at
    // distance h (the asin form loses digits near 2π).
    const double cases[][3] = {{0.5, 0.5, 1.0}, {0.5, 2.0, 0.3}, {1e-3, 1e-3, 10.0}, {1e5, 1e5, 1.0}};
    for (const auto& c : cases) {
        const double a = c[0], b = c[1], h = c[2];
        const double expected = 4 * std::atan(a * b / (h * std::sqrt(a * a + b * b + h * h)));
        expectRelative(expected, solidAngle(Vec3(0.0), rectangle(-a, a, -b, b, h)), 1e-12);
        expectRelative(expected, solidAngle(Vec3(0.0), rectangle(-a, a, -b, b, -h)), 1e-12);
    }
}
