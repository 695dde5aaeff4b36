// Grid caches over highly tessellated objects (cache/GridCache.h).
#include "cache/GridCache.h"
#include "core/Error.h"
#include "core/loaders/ObjLoader.h"

#include "TestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

using namespace ml;
using ml::test::uvSphere;

namespace {

Mesh withTriangleArrays(Mesh m) {
    m.materials.assign(m.triangles.size(), 0);
    m.sourceLines.assign(m.triangles.size(), 0);
    return m;
}

// An n×n lattice of vertices spanning [0, size]² at height z, normal ±z,
// then rotated by `rot` and moved by `offset`.
Mesh plate(int n, double size, double z, bool up, const Mat3& rot = Mat3(1.0), const Vec3& offset = Vec3(0.0)) {
    Mesh m;
    m.name = up ? "plate+z" : "plate-z";
    const double step = size / (n - 1);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            m.positions.push_back(offset + rot * Vec3(j * step, i * step, z));
            m.normals.push_back(rot * Vec3(0, 0, up ? 1 : -1));
        }
    for (int i = 0; i + 1 < n; ++i)
        for (int j = 0; j + 1 < n; ++j) {
            const unsigned a = unsigned(i * n + j), b = a + 1, c = a + unsigned(n), d = c + 1;
            if (up) {
                m.triangles.push_back({a, b, d});
                m.triangles.push_back({a, d, c});
            } else {
                m.triangles.push_back({a, d, b});
                m.triangles.push_back({a, c, d});
            }
        }
    return withTriangleArrays(std::move(m));
}

Mesh merged(const Mesh& a, const Mesh& b, const std::string& name) {
    Mesh m = a;
    m.name = name;
    const unsigned base = unsigned(a.positions.size());
    m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
    m.normals.insert(m.normals.end(), b.normals.begin(), b.normals.end());
    for (glm::uvec3 t : b.triangles) m.triangles.push_back(t + glm::uvec3(base));
    return withTriangleArrays(std::move(m));
}

// A unit cube, 24 vertices (flat faces), 12 triangles.
Mesh cube() {
    Mesh m;
    m.name = "cube";
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            Vec3 n(0.0);
            n[axis] = side ? 1 : -1;
            Vec3 t(0.0), b(0.0);
            t[(axis + 1) % 3] = 1;
            b[(axis + 2) % 3] = 1;
            if (!side) std::swap(t, b);  // keeps t × b = n
            const Vec3 c = Vec3(0.5) + 0.5 * n;
            const unsigned first = unsigned(m.positions.size());
            for (const Vec2 uv : {Vec2(-1, -1), Vec2(1, -1), Vec2(1, 1), Vec2(-1, 1)}) {
                m.positions.push_back(c + 0.5 * (uv.x * t + uv.y * b));
                m.normals.push_back(n);
            }
            m.triangles.push_back({first, first + 1, first + 2});
            m.triangles.push_back({first, first + 2, first + 3});
        }
    return withTriangleArrays(std::move(m));
}

Mat3 rotation(const Vec3& axis, double angle) {
    const Vec3 k = glm::normalize(axis);
    const Mat3 K(0, k.z, -k.y, -k.z, 0, k.x, k.y, -k.x, 0);  // column-major cross-product matrix
    return Mat3(1.0) + std::sin(angle) * K + (1 - std::cos(angle)) * K * K;
}

double boundsDiagonal(const Mesh& m) {
    Bounds3 b;
    for (const Vec3& p : m.positions) b.extend(p);
    return b.diagonal();
}

// What every grid cache must satisfy, whatever the mesh: rows are
// partitions of unity (1e-12: a sum of at most a few dozen normalised
// doubles is off by a few ulp), only samples inside the vertex's normal cone
// and inside the 2×2×2 cells around it are used (per axis within 1.5 cells,
// + 1e-9 cell for the rounding of coordinates), samples sit on vertices.
void expectInvariants(const GridCache& g, const Mesh& m, const GridCacheSettings& s) {
    ASSERT_EQ(g.vertexCount(), m.positions.size());
    const auto& off = g.weightOffsets();
    const auto& ids = g.weightSamples();
    const auto& w = g.weights();
    ASSERT_EQ(off.size(), m.positions.size() + 1);
    ASSERT_EQ(off.back(), ids.size());
    ASSERT_EQ(ids.size(), w.size());
    for (size_t sI = 0; sI < g.sampleCount(); ++sI) {
        ASSERT_LT(g.sampleVertex(sI), m.positions.size());
        EXPECT_EQ(g.samplePosition(sI), m.positions[g.sampleVertex(sI)]) << "sample " << sI;
        EXPECT_NEAR(glm::length(g.sampleNormal(sI)), 1.0, 1e-12) << "sample " << sI;
    }
    size_t failures = 0;
    for (size_t v = 0; v < m.positions.size() && failures < 10; ++v) {
        ASSERT_LT(off[v], off[v + 1]) << "vertex " << v << " has no sample";
        double sum = 0;
        const Vec3 n = glm::normalize(m.normals[v]);
        for (uint32_t k = off[v]; k < off[v + 1]; ++k) {
            ASSERT_LT(ids[k], g.sampleCount());
            sum += w[k];
            const bool ok = std::isfinite(w[k]) && w[k] > 0 &&
                            glm::dot(n, g.sampleNormal(ids[k])) > s.normalConeCos &&
                            glm::all(glm::lessThanEqual(glm::abs(g.samplePosition(ids[k]) - m.positions[v]),
                                                        Vec3((1.5 + 1e-9) * s.cellSize)));
            if (!ok) ++failures;
            EXPECT_TRUE(ok) << "vertex " << v << " uses sample " << ids[k] << " weight " << w[k];
        }
        if (std::abs(sum - 1) > 1e-12) ++failures;
        EXPECT_NEAR(sum, 1.0, 1e-12) << "vertex " << v;
    }
}

// f(x) = A·x + b per channel.
struct LinearField {
    Mat3 A;  // column A[r] = gradient of channel r, so f = transpose(A)·x + b
    Rgb b;
    Rgb at(const Vec3& x) const { return glm::transpose(A) * x + b; }
    // Σ|∂f_r/∂x_i| for channel r: the bound's gradient norm (l1, per axis
    // distances are bounded separately).
    double l1(int r) const { return std::abs(A[r][0]) + std::abs(A[r][1]) + std::abs(A[r][2]); }
};

const LinearField kField{Mat3(0.3, -0.7, 0.5, 1.1, 0.2, -0.4, -0.6, 0.9, 0.8), Rgb(2.0, -1.0, 0.5)};

std::vector<Rgb> sampleField(const GridCache& g, const LinearField& f) {
    std::vector<Rgb> values(g.sampleCount());
    for (size_t s = 0; s < values.size(); ++s) values[s] = f.at(g.samplePosition(s));
    return values;
}

// The interpolated value is a convex combination of f at samples that lie,
// per axis, within 1.5 cells of the vertex (its 2×2×2 block of cells spans
// 2 cells and the vertex is in the middle cell's width), so the error of a
// linear field is at most 1.5·h·Σ|∂f/∂x_i| (+ rounding, 1e-12 of the scale).
// Returns the largest error relative to that bound.
double maxLinearErrorRatio(const GridCache& g, const Mesh& m, const LinearField& f, double scale) {
    std::vector<Rgb> out;
    g.interpolate(sampleField(g, f), out);
    double worst = 0;
    for (size_t v = 0; v < m.positions.size(); ++v) {
        const Rgb expected = f.at(m.positions[v]);
        for (int r = 0; r < 3; ++r) {
            const double bound = 1.5 * g.cellSize() * f.l1(r) + 1e-12 * scale;
            worst = std::max(worst, std::abs(out[v][r] - expected[r]) / bound);
        }
    }
    return worst;
}

}  // namespace

TEST(GridCacheSettings, RefusesBadValues) {
    GridCacheSettings s;
    s.cellSize = 0.1;
    EXPECT_NO_THROW(s.validate());
    for (double h : {0.0, -1.0, std::nan(""), kInf}) {
        GridCacheSettings b = s;
        b.cellSize = h;
        EXPECT_THROW(b.validate(), InputError) << h;
    }
    for (double c : {-0.1, 1.0, 1.5, std::nan("")}) {
        GridCacheSettings b = s;
        b.normalConeCos = c;
        EXPECT_THROW(b.validate(), InputError) << c;
    }
}

TEST(GridCache, ConstantFieldIsExact) {
    const Mesh m = uvSphere(Vec3(0.123, -0.456, 0.789), 1.0, 60, 80);
    GridCacheSettings s;
    s.cellSize = 0.173;
    const GridCache g(m, s);
    expectInvariants(g, m, s);
    std::vector<Rgb> out;
    g.interpolate(std::vector<Rgb>(g.sampleCount(), Rgb(3.5, 0.25, 7.0)), out);
    ASSERT_EQ(out.size(), m.positions.size());
    for (size_t v = 0; v < out.size(); ++v) {
        // Partition of unity: off by a few ulp of the value at most.
        EXPECT_NEAR(out[v].r, 3.5, 1e-12 * 3.5) << v;
        EXPECT_NEAR(out[v].g, 0.25, 1e-12 * 0.25) << v;
        EXPECT_NEAR(out[v].b, 7.0, 1e-12 * 7.0) << v;
    }
}

// A grid-aligned plane: 5×5 vertices per cell (spacing 1/8, cells 5/8; both
// exact in binary, so every vertex's cell is exact). Each cell's sample is
// its middle vertex, 1/16 below the cell centre on x and y, so bilinear
// weights at a vertex whose four surrounding cells exist give exactly
// f(p − (1/16, 1/16, 0)). Vertices within half a cell of the rim have only
// one column or row of cells and obey the general bound.
TEST(GridCache, LinearFieldOnAlignedPlaneIsBilinear) {
    const int cells = 8, perCell = 5;
    const double step = 1.0 / 8.0, h = perCell * step;
    const Mesh m = plate(cells * perCell, (cells * perCell - 1) * step, 0.3, true);
    GridCacheSettings s;
    s.cellSize = h;
    const GridCache g(m, s);
    expectInvariants(g, m, s);
    EXPECT_EQ(g.sampleCount(), size_t(cells * cells));
    std::vector<Rgb> out;
    g.interpolate(sampleField(g, kField), out);
    size_t interior = 0;
    for (size_t v = 0; v < m.positions.size(); ++v) {
        const Vec3 p = m.positions[v];
        const Vec3 t = p / h;
        if (t.x < 0.5 || t.y < 0.5 || t.x > cells - 0.5 || t.y > cells - 0.5) continue;
        ++interior;
        const Rgb expected = kField.at(p - Vec3(step / 2, step / 2, 0));
        for (int r = 0; r < 3; ++r) EXPECT_NEAR(out[v][r], expected[r], 1e-12) << "vertex " << v << " channel " << r;
    }
    EXPECT_EQ(interior, size_t((cells * perCell - perCell) * (cells * perCell - perCell)));
    EXPECT_LE(maxLinearErrorRatio(g, m, kField, 4.0), 1.0);
}

TEST(GridCache, LinearFieldOnDenseSphereWithinCellBound) {
    const Mesh m = uvSphere(Vec3(0.123, -0.456, 0.789), 1.0, 120, 160);
    GridCacheSettings s;
    s.cellSize = boundsDiagonal(m) / 64;
    const GridCache g(m, s);
    expectInvariants(g, m, s);
    const double ratio = maxLinearErrorRatio(g, m, kField, 4.0);
    std::printf("dense sphere (%zu vertices, h = %.4f): %zu samples, worst linear error %.3f of the 1.5·h·|∇f|₁ bound\n",
                m.positions.size(), s.cellSize, g.sampleCount(), ratio);
    EXPECT_LE(ratio, 1.0);
}

// Two parallel plates 1e-3 apart with opposite normals, tilted so that the
// grid cuts them anywhere: cells are 1/8 of the slab, so nearly every cell
// holds both sides.
TEST(GridCache, ThinSlabSidesNeverMix) {
    const Mat3 rot = rotation(Vec3(0.3, -0.5, 0.8), 0.7);
    const Vec3 offset(-0.21, 0.37, 0.05);
    const Mesh top = plate(61, 1.0, 1e-3, true, rot, offset);
    const Mesh bottom = plate(61, 1.0, 0.0, false, rot, offset);
    const Mesh slab = merged(top, bottom, "slab");
    const Vec3 up = rot * Vec3(0, 0, 1);
    GridCacheSettings s;
    s.cellSize = 1.0 / 8;
    const GridCache g(slab, s);
    expectInvariants(g, slab, s);

    size_t topSamples = 0, shared = 0;
    for (size_t i = 0; i < g.sampleCount(); ++i) {
        const double c = glm::dot(g.sampleNormal(i), up);
        ASSERT_NEAR(std::abs(c), 1.0, 1e-12) << "sample " << i << " mixes the sides";
        topSamples += c > 0;
        shared += g.sampleVertex(i) < top.positions.size() ? c > 0 : c < 0;
    }
    EXPECT_EQ(shared, g.sampleCount()) << "a sample sits on the other side's vertex";
    EXPECT_GT(topSamples, 0u);
    EXPECT_LT(topSamples, g.sampleCount());

    for (int side = 0; side < 2; ++side) {
        std::vector<Rgb> values(g.sampleCount());
        for (size_t i = 0; i < values.size(); ++i)
            values[i] = Rgb((glm::dot(g.sampleNormal(i), up) > 0) == (side == 0) ? 1.0 : 0.0);
        std::vector<Rgb> out;
        g.interpolate(values, out);
        for (size_t v = 0; v < slab.positions.size(); ++v) {
            const bool onTop = v < top.positions.size();
            if (onTop == (side == 0)) {
                // Σ normalised weights: 1 to a few ulp.
                EXPECT_NEAR(out[v].r, 1.0, 1e-14) << "vertex " << v;
            } else {
                EXPECT_EQ(out[v].r, 0.0) << "vertex " << v;  // no weight at all on the other side
            }
        }
    }
}

// The same sphere at 1e-4 and 1e4 of its size, far from the origin: the
// grid is relative to the object, so the samples and weights are the same.
TEST(GridCache, ScaleAndPositionDoNotMatter) {
    const Mesh unit = uvSphere(Vec3(0.3, -0.2, 0.1), 1.0, 40, 50);
    GridCacheSettings s;
    s.cellSize = 0.0731;
    const GridCache ref(unit, s);
    for (const auto& [scale, offset] : {std::pair{1e-4, Vec3(1e-3, 0, 0)}, std::pair{1e4, Vec3(1e5, -1e5, 3e5)}}) {
        Mesh m = unit;
        for (Vec3& p : m.positions) p = scale * p + offset;
        GridCacheSettings ss = s;
        ss.cellSize = scale * s.cellSize;
        const GridCache g(m, ss);
        expectInvariants(g, m, ss);
        ASSERT_EQ(g.sampleCount(), ref.sampleCount()) << scale;
        for (size_t i = 0; i < g.sampleCount(); ++i) EXPECT_EQ(g.sampleVertex(i), ref.sampleVertex(i)) << scale;
        ASSERT_EQ(g.weightSamples(), ref.weightSamples()) << scale;
        for (size_t k = 0; k < g.weights().size(); ++k) EXPECT_NEAR(g.weights()[k], ref.weights()[k], 1e-9) << scale;
        EXPECT_LE(maxLinearErrorRatio(g, m, kField, 4e5), 1.0) << scale;
    }
}

// A cell larger than the object: every vertex in one cell, the samples are
// the normal clusters. Each vertex normal is within θ = acos(0.5)/3 = 20°
// of its cluster's seed, and every direction is within 7.5° of a vertex
// normal of this 24×32 sphere, so caps of 27.5° around the seeds cover the
// sphere: at least 2/(1 − cos 27.5°) > 17 of them.
TEST(GridCache, WholeObjectInOneCell) {
    const Mesh m = uvSphere(Vec3(5, 5, 5), 0.01, 24, 32);
    GridCacheSettings s;
    s.cellSize = 1.0;
    const GridCache g(m, s);
    expectInvariants(g, m, s);
    EXPECT_GE(g.sampleCount(), 18u);
    EXPECT_LT(g.sampleCount(), m.positions.size());
    // Normal field n·e: every vertex sees samples within 60° of its normal only.
    std::vector<Rgb> values(g.sampleCount());
    for (size_t i = 0; i < values.size(); ++i) values[i] = g.sampleNormal(i);
    std::vector<Rgb> out;
    g.interpolate(values, out);
    for (size_t v = 0; v < out.size(); ++v) EXPECT_GT(glm::dot(out[v], m.normals[v]), 0.5) << v;
}

// Two flat plates folded along a shared edge, both inside one cell, so
// each vertex weighs the two samples by normal agreement alone:
// (cos − c)/(1 − c) is 1 for its own plate and (cos α − 0.5)/0.5 for the
// other, which is left out when α is beyond the 60° cone.
TEST(GridCache, FoldWeightsByNormalAgreement) {
    for (double degrees : {50.0, 70.0}) {
        const double alpha = degrees * kPi / 180;
        const Mesh a = plate(11, 1.0, 0.0, true);
        const Mesh b = plate(11, 1.0, 0.0, true, rotation(Vec3(1, 0, 0), alpha));
        const Mesh fold = merged(a, b, "fold");
        GridCacheSettings s;
        s.cellSize = 10;
        const GridCache g(fold, s);
        expectInvariants(g, fold, s);
        ASSERT_EQ(g.sampleCount(), 2u) << degrees;
        std::vector<Rgb> values(2);
        for (size_t i = 0; i < 2; ++i) values[i] = Rgb(g.sampleNormal(i).z > 0.99 ? 1.0 : 0.0);
        std::vector<Rgb> out;
        g.interpolate(values, out);
        const double other = std::max(0.0, (std::cos(alpha) - 0.5) / 0.5);
        for (size_t v = 0; v < fold.positions.size(); ++v) {
            const double expected = v < a.positions.size() ? 1 / (1 + other) : other / (1 + other);
            EXPECT_NEAR(out[v].r, expected, 1e-12) << degrees << "°, vertex " << v;
        }
    }
}

TEST(GridCache, BadInputNamesTheObject) {
    Mesh m = uvSphere(Vec3(0.0), 1.0, 8, 8);
    m.name = "bunny";
    GridCacheSettings s;
    s.cellSize = 0.1;
    auto expectError = [&](const Mesh& bad, const GridCacheSettings& set, const std::string& part) {
        try {
            GridCache g(bad, set);
            ADD_FAILURE() << "no error for " << part;
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("'bunny'"), std::string::npos) << what;
            EXPECT_NE(what.find(part), std::string::npos) << what;
        }
    };
    Mesh zero = m;
    zero.normals[7] = Vec3(0.0);
    expectError(zero, s, "vertex 7 has a degenerate normal");
    Mesh nanNormal = m;
    nanNormal.normals[3].y = std::nan("");
    expectError(nanNormal, s, "vertex 3 has a degenerate normal");
    Mesh nanPos = m;
    nanPos.positions[5].x = kInf;
    expectError(nanPos, s, "vertex 5 has a non-finite position");
    Mesh missing = m;
    missing.normals.pop_back();
    expectError(missing, s, "normals for");
    Mesh empty;
    empty.name = "bunny";
    expectError(empty, s, "none");
    GridCacheSettings tiny = s;
    tiny.cellSize = 1e-7;
    expectError(m, tiny, "cells along its longest side");

    const GridCache g(m, s);
    std::vector<Rgb> out;
    EXPECT_THROW(g.interpolate(std::vector<Rgb>(g.sampleCount() + 1), out), std::invalid_argument);
    std::vector<Rgb> nanValues(g.sampleCount(), Rgb(1.0));
    nanValues[0].g = std::nan("");
    EXPECT_THROW(g.interpolate(nanValues, out), std::invalid_argument);
}

// The paper's case: a ~70k-triangle object (a bunny's worth) in a scene of
// its own size, cache edges 1/64 of the scene's diagonal.
TEST(GridCacheDecision, DenseSphereGetsAGridCubeDoesNot) {
    const Mesh sphere = uvSphere(Vec3(0.0), 1.0, 187, 188);
    ASSERT_EQ(sphere.triangles.size(), 69936u);
    const double L = boundsDiagonal(sphere) / 64;
    const GridCacheDecision d = decideGridCache(sphere, L);
    // needed = ⌈area / (√3/2·L²)⌉ with area just under 4π.
    const double area = 4 * kPi;
    EXPECT_NEAR(double(d.neededVertices), area / (std::sqrt(3.0) / 2 * L * L), 0.001 * area / (L * L));
    EXPECT_EQ(d.vertices, sphere.positions.size());
    EXPECT_TRUE(d.useGrid) << d.reason;
    EXPECT_NE(d.reason.find(std::to_string(d.vertices)), std::string::npos) << d.reason;
    EXPECT_NE(d.reason.find(std::to_string(d.neededVertices)), std::string::npos) << d.reason;
    EXPECT_NE(d.reason.find("'sphere'"), std::string::npos) << d.reason;

    const Mesh box = cube();
    const GridCacheDecision c = decideGridCache(box, boundsDiagonal(box) / 64);
    EXPECT_FALSE(c.useGrid) << c.reason;
    EXPECT_EQ(c.vertices, 24u);
    EXPECT_NE(c.reason.find("24 vertices"), std::string::npos) << c.reason;
    EXPECT_NE(c.reason.find(std::to_string(c.neededVertices)), std::string::npos) << c.reason;

    // Each condition alone refuses: the same sphere with 16× finer cache
    // edges needs more vertices than it has...
    const GridCacheDecision fine = decideGridCache(sphere, L / 16);
    EXPECT_FALSE(fine.useGrid) << fine.reason;
    EXPECT_NE(fine.reason.find("not more than 4 x needed"), std::string::npos) << fine.reason;
    // ...and an object of 1,800 vertices is never worth a grid.
    const Mesh small = uvSphere(Vec3(0.0), 1.0, 31, 60);
    ASSERT_LE(small.positions.size(), kGridMinVertices);
    const GridCacheDecision sm = decideGridCache(small, 1.0);
    EXPECT_FALSE(sm.useGrid) << sm.reason;
    EXPECT_NE(sm.reason.find("not more than 2000 vertices"), std::string::npos) << sm.reason;

    EXPECT_THROW(decideGridCache(box, 0.0), InputError);
    EXPECT_THROW(decideGridCache(box, std::nan("")), InputError);
}

// With cells of the cache's edge length h the sphere crosses about
// (|nx|+|ny|+|nz|)·area/h² = 1.5·4πR²/h² cells (≈ 6,400 here), and a cell
// grazed without holding a vertex has no sample: the count must be near,
// and not above, that, and far below the 35k vertices.
TEST(GridCache, DenseSphereSampleCount) {
    const Mesh sphere = uvSphere(Vec3(0.0), 1.0, 187, 188);
    GridCacheSettings s;
    s.cellSize = boundsDiagonal(sphere) / 64;
    const GridCache g(sphere, s);
    expectInvariants(g, sphere, s);
    const double crossed = 1.5 * 4 * kPi / (s.cellSize * s.cellSize);
    std::printf("dense sphere: %zu vertices, %zu samples (%.0f cells crossed expected), %zu weights, %zu bytes\n",
                sphere.positions.size(), g.sampleCount(), crossed, g.weights().size(), g.memoryBytes());
    EXPECT_GT(double(g.sampleCount()), 0.7 * crossed);
    EXPECT_LT(double(g.sampleCount()), 1.1 * crossed);
    EXPECT_LT(g.sampleCount() * 4, sphere.positions.size());
    const double ratio = maxLinearErrorRatio(g, sphere, kField, 4.0);
    EXPECT_LE(ratio, 1.0);
}

// The densest public model at hand (../shared/scenes, optional): McGuire's
// CornellBox-Water, 7,088 triangles; its objects are decided at the
// renderer's default cache edge (1/64 of the scene's diagonal) and the
// densest one gets a grid cache (forced) whose interpolation must be finite
// and within the linear bound.
TEST(GridCache, SharedCornellBoxWater) {
    const std::string path = std::string(MESHLIGHT_SHARED_SCENES) + "/mcguire-cornellbox/CornellBox-Water.obj";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent";
    const Scene scene = loadObj(path);
    const double L = scene.bounds.diagonal() / 64;
    const Mesh* densest = nullptr;
    for (const Mesh& m : scene.meshes) {
        const GridCacheDecision d = decideGridCache(m, L);
        std::printf("%s\n", d.reason.c_str());
        EXPECT_EQ(d.vertices, m.positions.size());
        EXPECT_EQ(d.useGrid, double(d.vertices) > kGridVertexRatio * double(d.neededVertices) &&
                                 d.vertices > kGridMinVertices);
        if (!densest || m.positions.size() > densest->positions.size()) densest = &m;
    }
    ASSERT_TRUE(densest);
    GridCacheSettings s;
    s.cellSize = L;
    const GridCache g(*densest, s);
    expectInvariants(g, *densest, s);
    const double ratio = maxLinearErrorRatio(g, *densest, kField, scene.bounds.diagonal());
    std::printf("'%s': %zu vertices, %zu samples, %zu bytes, worst linear error %.3f of bound\n",
                densest->name.c_str(), densest->positions.size(), g.sampleCount(), g.memoryBytes(), ratio);
    EXPECT_LE(ratio, 1.0);
}
