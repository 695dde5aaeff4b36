// TriangleLocator (core/raytrace): Embree's point query must find exactly
// the face a linear scan finds: the nearest within the tolerance among the
// faces facing the query's side, ties to the higher index.
#include "core/raytrace/TriangleLocator.h"

#include <gtest/gtest.h>

#include <optional>
#include <random>
#include <vector>

namespace ml {
namespace {

// The rule, face by face: what MeshIrradianceLookup did before the BVH.
std::optional<TriangleLocator::Location> scan(const std::vector<Vec3>& positions,
                                              const std::vector<glm::uvec3>& triangles, double tolerance,
                                              const Vec3& p, const Vec3& n) {
    std::optional<TriangleLocator::Location> best;
    double bestD2 = tolerance * tolerance;
    for (uint32_t t = 0; t < triangles.size(); ++t) {
        const glm::uvec3 i = triangles[t];
        const Vec3 &a = positions[i.x], &b = positions[i.y], &c = positions[i.z];
        const Vec3 cr = glm::cross(b - a, c - a);
        if (!(glm::length(cr) > 0)) continue;
        if (glm::dot(glm::vec3(cr / glm::length(cr)), glm::vec3(n)) < 0.5f) continue;
        const Vec3 w = closestBarycentric(p, a, b, c);
        const Vec3 x = w.x * a + w.y * b + w.z * c;
        const double d2 = glm::dot(x - p, x - p);
        if (d2 > bestD2) continue;
        bestD2 = d2;
        best = TriangleLocator::Location{t, w};
    }
    return best;
}

// A floor of n × n cells far from the origin (so float coordinates would
// lose digits without the locator's centring), each cell two triangles,
// with its reversed copy (the back of an open surface) and a wall standing
// on it: the shapes a cache mesh has.
struct TestMesh {
    std::vector<Vec3> positions;
    std::vector<glm::uvec3> triangles;
};

TestMesh floorAndWall(int n, const Vec3& offset) {
    TestMesh m;
    auto vertex = [&](double x, double y, double z) {
        m.positions.push_back(offset + Vec3(x, y, z));
        return uint32_t(m.positions.size() - 1);
    };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double x0 = double(i) / n, x1 = double(i + 1) / n, z0 = double(j) / n, z1 = double(j + 1) / n;
            const uint32_t a = vertex(x0, 0, z0), b = vertex(x1, 0, z0), c = vertex(x1, 0, z1), d = vertex(x0, 0, z1);
            m.triangles.push_back({a, d, c});  // facing +y
            m.triangles.push_back({a, c, b});
            m.triangles.push_back({a, c, d});  // its back, facing −y
            m.triangles.push_back({a, b, c});
        }
    const uint32_t a = vertex(0.5, 0, 0), b = vertex(0.5, 0, 1), c = vertex(0.5, 1, 1), d = vertex(0.5, 1, 0);
    m.triangles.push_back({a, b, c});  // facing +x
    m.triangles.push_back({a, c, d});
    m.triangles.push_back({a, a, b});  // without area: never found
    return m;
}

void expectSame(const std::optional<TriangleLocator::Location>& got,
                const std::optional<TriangleLocator::Location>& want) {
    ASSERT_EQ(got.has_value(), want.has_value());
    if (!want) return;
    EXPECT_EQ(got->triangle, want->triangle);
    EXPECT_EQ(got->barycentric, want->barycentric);
}

TEST(TriangleLocator, FindsWhatALinearScanFinds) {
    for (const Vec3 offset : {Vec3(0.0), Vec3(1e4, -3e3, 2e4)}) {
        const TestMesh m = floorAndWall(24, offset);
        const double tolerance = 1e-5;
        const TriangleLocator locator(m.positions, m.triangles, tolerance);
        std::mt19937 engine(17);
        std::uniform_real_distribution<double> unit(0.0, 1.0);
        auto uniform = [&] { return unit(engine); };
        const Vec3 normals[] = {{0, 1, 0}, {0, -1, 0}, {1, 0, 0}, {0.6, 0.8, 0}, {-1, 0, 0}};
        for (int k = 0; k < 20000; ++k) {
            // On the floor, on a cell's edge or corner, a hair off it, or
            // beyond the tolerance; on the wall; the normal of either side.
            Vec3 p(uniform(), 0, uniform());
            switch (k % 6) {
                case 1: p.x = double(int(p.x * 24)) / 24; break;   // on an edge
                case 2: p.x = double(int(p.x * 24)) / 24; p.z = double(int(p.z * 24)) / 24; break;
                case 3: p.y = 0.5 * tolerance * (uniform() - 0.5); break;
                case 4: p.y = 3 * tolerance; break;                // too far
                case 5: p = Vec3(0.5 + 0.4 * tolerance, uniform(), uniform()); break;
                default: break;
            }
            p += offset;
            const Vec3 n = glm::normalize(normals[k % 5]);
            expectSame(locator.locate(p, n), scan(m.positions, m.triangles, tolerance, p, n));
        }
    }
}

TEST(TriangleLocator, AnEmptyMeshFindsNothing) {
    const std::vector<Vec3> positions;
    const std::vector<glm::uvec3> triangles;
    const TriangleLocator locator(positions, triangles, 1e-3);
    EXPECT_FALSE(locator.locate(Vec3(0.0), Vec3(0, 1, 0)).has_value());
}

}  // namespace
}  // namespace ml
