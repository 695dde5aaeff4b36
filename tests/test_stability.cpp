// Stability: geometry and magnitudes that real scenes contain and naive
// renderers break on, run through the whole pipeline (GPU sampler, cache,
// compositor): coincident and overlapping triangles, slivers of aspect 1e4,
// non-manifold edges and duplicate vertices, scenes 1e-3 and 1e5 units
// across, lights of radiance 1e-6 and 1e6. test_hard_cases.cpp holds the
// sampler's own hard configurations (receivers at the light, horizons,
// edge-on lights, touching occluders) with worst-case bounds; this file
// covers what it does not and checks, in every case, that every cached
// irradiance and every rendered pixel is finite and non-negative.
//
// The tolerances used throughout (each use says which):
//  [lambert]  Where nothing occludes a receiver, the control variate is
//             Lambert's closed form at the receiver, and so is the exact
//             reference: both double-precision sums of the same terms, equal
//             to 1e-9 relative (rounding is ~1e-15; test_render uses 1e-9 too).
//  [unbiased] The jittered estimators are unbiased: the mean of 32 passes with
//             fresh seeds lies within 4 standard errors of the exact value
//             (seeds are fixed, so this either always or never holds; by
//             chance, 4 standard errors are exceeded once in ~3,000 checks:
//             Student's t with 31 degrees of freedom).
//  [single]   One control-variate estimate (64×64 pixels, 8 tests each) errs
//             only in pixels crossed by an occluder's outline, each by at
//             most its own weight. The bench (README) measures at most 0.15 %
//             of the unoccluded irradiance over 10,000 receivers all in
//             penumbra; we allow 2 % of it, and 0.1 % on average over a
//             cache's vertices (bench: 0.013 %). Either is far below what a
//             systematic error costs (a missed or double-counted occluder,
//             a wrong weight: tens of percent where it matters).
//  [float]    The compositor works in 32-bit float (6e-8 relative rounding)
//             and interpolates a triangle's values as a plane (a0 + x·dadx +
//             y·dady on Mesa's llvmpipe), whose rounding is relative to the
//             largest value it interpolates: a pixel may err by 1e-4 of its
//             own value (1,600 roundings) plus 1e-7 of the image's largest.
#include "cache/IrradianceCache.h"
#include "TestSamplers.h"
#include "core/Error.h"
#include "core/image/ImageMetrics.h"
#include "core/loaders/ObjLoader.h"
#include "core/reference/ExactIrradiance.h"
#include "core/scenes/BenchScene.h"
#include "core/scenes/CornellBox.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/direct/Jitter.h"
#include "gpu_sampling/gl/GlContext.h"
#include "viewer/compositor/Compositor.h"

#include "GlTestContext.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

using namespace ml;
using test::addQuad, test::floorMesh, test::quadMesh, test::unitLight;
using test::kX, test::kY, test::kZ;

namespace {

std::string dataFile(const std::string& name) { return std::string(MESHLIGHT_TEST_DATA) + "/" + name; }

std::string str(const Vec3& p) {
    return concat("(", p.x, ", ", p.y, ", ", p.z, ")");
}

// --- scenes built by hand ----------------------------------------------------

// Material 0 emits (Ke = 1: irradiance equals the cosine-weighted solid
// angle), material 1 is grey, material 2 is a second emitter.
std::vector<Material> materials() {
    Material light, grey, light2;
    light.name = "light";
    light.kd = Rgb(0.0);
    light.ke = Rgb(1.0);
    grey.name = "grey";
    grey.kd = Rgb(0.5);
    light2 = light;
    light2.name = "light2";
    return {light, grey, light2};
}
constexpr uint32_t kLight = 0, kGrey = 1, kLight2 = 2;

Scene makeScene(std::vector<Mesh> meshes) { return test::sceneOf("stability case", materials(), std::move(meshes)); }

// The bench's occluder (0.5 × 0.5 at y = 0.5, facing up here); its light
// and floor are test::unitLight() and test::floorMesh().
Mesh benchOccluder() { return quadMesh("occluder", kGrey, Vec3(-0.2, 0.5, -0.3), 0.5 * kZ, 0.5 * kX); }

// Longest edge over the height onto it: 1.15 for an equilateral triangle,
// 1e4 and more for the slivers below.
double aspectRatio(const Triangle3& t) {
    double longest = 0;
    for (int k = 0; k < 3; ++k) longest = std::max(longest, glm::length(t[(k + 1) % 3] - t[k]));
    const double area = 0.5 * glm::length(glm::cross(t[1] - t[0], t[2] - t[0]));
    return longest * longest / (2 * area);
}

// --- estimators --------------------------------------------------------------

// The sampler in its default configuration (jittered 64×64, 8 tests per
// pixel, control variate) or another estimator.
DirectSamplerSettings samplerSettings(DirectEstimator estimator = DirectEstimator::ControlVariate) {
    DirectSamplerSettings s;
    s.estimator = estimator;
    return s;
}

test::IrradianceFn samplerEstimate(DirectLightSampler& sampler) {
    return [&sampler](size_t l, const Vec3& x, const Vec3& n, uint32_t seed) {
        return sampler.sample(l, x, n, seed).irradiance;
    };
}

test::IrradianceFn exactEstimate(const ExactDirect& exact) {
    return [&exact](size_t l, const Vec3& x, const Vec3& n, uint32_t) { return exact.irradiance(l, x, n); };
}

// --- the pipeline and its universal checks -----------------------------------

void expectFiniteNonNegative(const IrradianceMeshCopy& view, const std::string& what) {
    size_t bad = 0;
    for (size_t v = 0; v < view.irradiance.size(); ++v) {
        const Rgb& e = view.irradiance[v];
        const bool ok = isFinite(e) && e.r >= 0 && e.g >= 0 && e.b >= 0;
        if (!ok && bad++ < 5)
            ADD_FAILURE() << what << ": cache vertex " << v << " at " << str(view.positions[v]) << " holds "
                          << str(e);
    }
    EXPECT_EQ(bad, 0u) << what << ": cache values not finite and non-negative";
    EXPECT_EQ(view.irradiance.size(), view.positions.size()) << what;
}

void expectFiniteNonNegative(const ImageRgb& image, const std::string& what) {
    ASSERT_EQ(image.data.size(), 3 * image.pixelCount()) << what;
    size_t bad = 0;
    for (size_t i = 0; i < image.data.size(); ++i) {
        const float v = image.data[i];
        if (!(std::isfinite(v) && v >= 0) && bad++ < 5)
            ADD_FAILURE() << what << ": pixel " << i / 3 % size_t(image.width) << "," << i / 3 / size_t(image.width)
                          << " channel " << i % 3 << " is " << v;
    }
    EXPECT_EQ(bad, 0u) << what << ": pixels not finite and non-negative";
}

// A view from above the floor at the scene's light, for the hand-built scenes.
Camera benchCamera() {
    Camera c;
    c.position = Vec3(0.3, 2.6, 3.2);
    c.target = Vec3(0.0, 0.3, 0.0);
    c.fovYDegrees = 50;
    return c;
}

struct Rendered {
    std::vector<IrradianceMeshCopy> caches;  // one per light
    ImageRgb image;
};

// Caches every light with `estimate` (one pass), checks every cached value,
// renders and checks every pixel.
Rendered renderScene(const Scene& scene, const test::IrradianceFn& estimate, const Camera& camera,
                     const std::string& what, double maxEdgeFraction = 1.0 / 24.0) {
    CacheSettings cs;
    cs.maxEdgeFraction = maxEdgeFraction;
    IrradianceCache cache(scene, cs);
    test::sampleEveryVertex(cache, estimate, 1, 1);
    Rendered out;
    for (size_t l = 0; l < cache.lightCount(); ++l) {
        out.caches.push_back(cache.copyMesh(l));
        expectFiniteNonNegative(out.caches.back(), what + ", light " + std::to_string(l));
    }
    Compositor compositor(test::glContext(), scene);
    CompositorSettings settings;
    settings.width = 32;  // 32 × 32 pixels of 2 × 2 sub-pixels: every pass runs
    settings.height = 32;
    settings.supersample = 2;
    out.image = compositor.render(camera, out.caches, settings);
    expectFiniteNonNegative(out.image, what + ", image");
    return out;
}

// Per-vertex error of cache `sampled` against `exact` (same mesh), in units
// of each vertex's unoccluded irradiance (Lambert), over every light.
struct CacheError {
    double mean = 0, max = 0;
    size_t vertices = 0, worst = 0;
};

CacheError cacheError(const Scene& scene, const std::vector<IrradianceMeshCopy>& sampled,
                      const std::vector<IrradianceMeshCopy>& exact) {
    const ExactDirect reference(scene);
    CacheError err;
    double sum = 0;
    for (size_t l = 0; l < sampled.size(); ++l) {
        const Rgb radiance = scene.lights[l].radiance;
        const double scale = std::max({radiance.r, radiance.g, radiance.b});
        for (size_t v = 0; v < sampled[l].positions.size(); ++v) {
            const double open =
                scale * reference.unoccludedCosineSolidAngle(l, sampled[l].positions[v], sampled[l].normals[v]);
            if (!(open > 0)) {
                EXPECT_EQ(sampled[l].irradiance[v], Rgb(0.0)) << "vertex " << v << " sees no light";
                continue;
            }
            const Rgb d = glm::abs(sampled[l].irradiance[v] - exact[l].irradiance[v]);
            const double e = std::max({d.r, d.g, d.b}) / open;
            sum += e;
            if (e > err.max) {
                err.max = e;
                err.worst = v;
            }
            ++err.vertices;
        }
    }
    err.mean = err.vertices ? sum / double(err.vertices) : 0.0;
    return err;
}

// [unbiased] for light `light` at (x, n): the mean of 32 jittered passes.
// The receiver must be unoccluded or clearly occluded: a sliver of shadow
// worth 1e-8 of the light is hit by no pass, and its mean is then off by
// that much with no variance to show for it.
void expectUnbiased(DirectLightSampler& sampler, const Scene& scene, size_t light, const Vec3& x, const Vec3& n,
                    uint32_t caseSeed, const std::string& what) {
    const ExactDirect reference(scene);
    const double exact = reference.cosineSolidAngle(light, x, n);
    const double open = reference.unoccludedCosineSolidAngle(light, x, n);
    ASSERT_GT(open, 0.0) << what << " at " << str(x);
    ASSERT_TRUE(exact == open || exact < (1 - 1e-3) * open)
        << what << " at " << str(x) << ": pick a receiver whose occluded part is 0 or > 1e-3, not "
        << 1 - exact / open;
    constexpr int kPasses = 32;
    double sum = 0, sumSq = 0;
    for (int k = 0; k < kPasses; ++k) {
        const DirectSample d = sampler.sample(light, x, n, jitter::seedFor(caseSeed, uint32_t(k)));
        ASSERT_TRUE(std::isfinite(d.cosineSolidAngle) && d.cosineSolidAngle >= 0) << what;
        sum += d.cosineSolidAngle;
        sumSq += d.cosineSolidAngle * d.cosineSolidAngle;
    }
    const double mean = sum / kPasses;
    const double var = std::max(0.0, (sumSq - kPasses * mean * mean) / (kPasses - 1));
    const double standardError = std::sqrt(var / kPasses);
    // The floor: an estimate without variance (nothing occluded) is Lambert,
    // equal to the exact value to [lambert].
    EXPECT_LE(std::abs(mean - exact), 4 * standardError + 1e-9 * exact + 1e-15)
        << what << ", light " << light << " at " << str(x) << ": mean " << mean << " ± " << standardError
        << ", exact " << exact;
}

// [float]: `image` is `expected` × `factor`.
void expectImageScaled(const ImageRgb& image, const ImageRgb& expected, double factor, const std::string& what) {
    ASSERT_EQ(image.data.size(), expected.data.size()) << what;
    double largest = 0;
    for (float v : expected.data) largest = std::max(largest, double(v));
    ASSERT_GT(largest, 0.0) << what;
    size_t bad = 0;
    for (size_t i = 0; i < image.data.size(); ++i) {
        const double want = expected.data[i], got = image.data[i] / factor;
        if (!(std::abs(got - want) <= 1e-4 * want + 1e-7 * largest) && bad++ < 5)
            ADD_FAILURE() << what << ": value " << i << " is " << got << " × " << factor << ", expected " << want;
    }
    EXPECT_EQ(bad, 0u) << what;
}

}  // namespace

// === coincident and overlapping triangles ===================================

TEST(Stability, OccluderCoplanarWithTheReceiver) {
    // A grey plate lying on the floor (the same plane, facing up, part of it
    // beyond the floor's edge) and a second one back to back with the floor
    // (facing down): both lie in every floor receiver's tangent plane, so
    // neither hides any of the light, and floor and plates z-fight in the
    // compositor.
    Mesh plates;
    plates.name = "plates";
    addQuad(plates, kGrey, Vec3(-1.0, 0.0, -0.4), 0.8 * kZ, 3.0 * kX);  // facing up, past x = 1.5
    addQuad(plates, kGrey, Vec3(-0.6, 0.0, -1.0), 1.2 * kX, 0.9 * kZ);  // facing down
    const Scene scene = makeScene({unitLight(), floorMesh(), plates});
    const ExactDirect exact(scene);

    DirectLightSampler cv(test::glContext(), scene, samplerSettings());
    DirectLightSampler plain(test::glContext(), scene, samplerSettings(DirectEstimator::Plain));
    // On both plates, on the floor beside them, on a plate's corner.
    const std::vector<Vec3> receivers = {Vec3(0.0, 0.0, 0.0), Vec3(0.3, 0.0, -0.2), Vec3(-0.55, 0.0, -0.9),
                                         Vec3(1.2, 0.0, 0.9), Vec3(-0.6, 0.0, -1.0)};
    for (size_t i = 0; i < receivers.size(); ++i) {
        const Vec3& x = receivers[i];
        const double open = exact.unoccludedCosineSolidAngle(0, x, kY);
        // [lambert]: nothing in the receiver's own plane occludes it.
        EXPECT_NEAR(exact.cosineSolidAngle(0, x, kY), open, 1e-9 * open) << str(x);
        const DirectSample d = cv.sample(0, x, kY, uint32_t(i));
        EXPECT_NEAR(d.cosineSolidAngle, open, 1e-9 * open) << str(x);
        EXPECT_EQ(d.visibleSamples, d.lightSamples) << str(x);
        expectUnbiased(plain, scene, 0, x, kY, 10 + uint32_t(i), "plain, coplanar plates");
    }
    // Through the pipeline: nothing occludes any vertex that sees the
    // light, so the sampled cache is the exact one to [lambert].
    const Rendered sampled = renderScene(scene, samplerEstimate(cv), benchCamera(), "coplanar plates, sampled");
    const Rendered reference = renderScene(scene, exactEstimate(exact), benchCamera(), "coplanar plates, exact");
    const CacheError err = cacheError(scene, sampled.caches, reference.caches);
    EXPECT_LE(err.max, 1e-9) << "[lambert], vertex " << err.worst;
}

// Disabled: fails today because of viewer/Compositor.cpp (reported, not
// this suite's to fix). Its irradiance pass lays each cache mesh's nearest
// depth, then adds every fragment whose depth EQUALs it, so coinciding
// surfaces are summed: a floor with a copy of itself in another object
// renders with twice the floor's direct light. Run it with
// --gtest_also_run_disabled_tests once the compositor adds only one
// surface per pixel.
TEST(Stability, CoincidentSurfacesAreShadedOnce) {
    // The floor twice, as two objects: identical triangles, so the cache
    // meshes are bisected identically and their depths are equal bit for
    // bit. With equal reflectance and irradiance, the image must be the
    // single floor's to [float].
    Mesh copy = floorMesh();
    copy.name = "floor copy";
    const Scene doubled = makeScene({unitLight(), floorMesh(), copy});
    const Scene single = makeScene({unitLight(), floorMesh()});
    const ExactDirect exactDoubled(doubled), exactSingle(single);
    const Rendered two = renderScene(doubled, exactEstimate(exactDoubled), benchCamera(), "floor twice");
    const Rendered one = renderScene(single, exactEstimate(exactSingle), benchCamera(), "floor once");
    expectImageScaled(two.image, one.image, 1.0, "floor twice against once");
}

TEST(Stability, CoincidentOccluders) {
    // Four coinciding copies of the bench's occluder: one in a mesh of its
    // own, two in one mesh (its triangles listed twice, on the same vertex
    // indices, as an OBJ face given twice loads) and one wound the other way
    // (facing down). Occlusion is a union: together they must hide exactly
    // what one hides (the control variate subtracts occluded samples:
    // counted per triangle, they would be subtracted four times).
    Mesh twice = benchOccluder();
    twice.name = "twice";
    Mesh doubled = benchOccluder();
    doubled.name = "doubled";
    for (size_t t = 0; t < 2; ++t) {
        doubled.triangles.push_back(doubled.triangles[t]);
        doubled.materials.push_back(kGrey);
        doubled.sourceLines.push_back(0);
    }
    Mesh flipped = benchOccluder();
    flipped.name = "flipped";
    for (glm::uvec3& t : flipped.triangles) std::swap(t.y, t.z);
    for (Vec3& n : flipped.normals) n = -n;
    const Scene single = makeScene({unitLight(), floorMesh(), benchOccluder()});
    const Scene stacked = makeScene({unitLight(), floorMesh(), twice, doubled, flipped});
    const ExactDirect exactSingle(single), exactStacked(stacked);

    std::vector<ReceiverPoint> points = makeBenchReceivers(5);
    points.push_back({Vec3(0.1, 0.0, -0.1), kY});   // the umbra point
    points.push_back({Vec3(0.05, 0.3, 0.0), kY});   // under the occluders
    for (auto method : {DirectMethod::Jittered, DirectMethod::Regular, DirectMethod::OcclusionQuery})
        for (auto estimator : {DirectEstimator::ControlVariate, DirectEstimator::Plain}) {
            DirectSamplerSettings s = samplerSettings(estimator);
            s.method = method;
            DirectLightSampler one(test::glContext(), single, s), four(test::glContext(), stacked, s);
            for (size_t i = 0; i < points.size(); ++i) {
                const Vec3& x = points[i].position;
                const uint32_t seed = jitter::seedFor(3, uint32_t(i));
                const DirectSample a = one.sample(0, x, kY, seed), b = four.sample(0, x, kY, seed);
                // Coverage bits are ANDed (or depth-tested): idempotent, so
                // the same jitter gives the same estimate, bit for bit.
                EXPECT_EQ(a.cosineSolidAngle, b.cosineSolidAngle)
                    << directMethodName(method) << "/" << directEstimatorName(estimator) << " at " << str(x);
                EXPECT_EQ(a.visibleSamples, b.visibleSamples) << str(x);
            }
        }
    for (const ReceiverPoint& p : points) {
        const double one = exactSingle.cosineSolidAngle(0, p.position, kY);
        // The exact reference unites the occluders' projections: the same
        // region, so the same value up to the union's rounding.
        // ExactDirect is accurate to 1e-12 relative (ExactIrradiance.h).
        EXPECT_NEAR(exactStacked.cosineSolidAngle(0, p.position, kY), one,
                    1e-12 * exactSingle.unoccludedCosineSolidAngle(0, p.position, kY))
            << str(p.position);
    }

    DirectLightSampler cv(test::glContext(), stacked, samplerSettings());
    const Rendered sampled = renderScene(stacked, samplerEstimate(cv), benchCamera(), "coincident occluders, sampled");
    const Rendered reference =
        renderScene(stacked, exactEstimate(exactStacked), benchCamera(), "coincident occluders, exact");
    const CacheError err = cacheError(stacked, sampled.caches, reference.caches);
    EXPECT_LE(err.max, 0.02) << "[single], vertex " << err.worst;
    EXPECT_LE(err.mean, 1e-3) << "[single]";
}

TEST(Stability, OccluderAndLightInOnePlane) {
    // Z-fighting with the light: a grey copy of the light facing the same
    // way, one facing the other way, a grey sheet around it in its plane and
    // a second light exactly on the first. Geometry in a light's plane does
    // not occlude it (DirectSamplerSettings::planeTolerance; ExactDirect
    // alike), so from below each light is seen whole: [lambert].
    Mesh copies;
    copies.name = "copies";
    addQuad(copies, kGrey, Vec3(-0.5, 1.0, -0.5), kX, kZ);          // the light's twin
    addQuad(copies, kGrey, Vec3(-0.5, 1.0, -0.5), kZ, kX);          // facing up
    addQuad(copies, kGrey, Vec3(-0.9, 1.0, -0.7), 1.3 * kX, 1.6 * kZ);  // a sheet around it
    Mesh second = quadMesh("second light", kLight2, Vec3(-0.5, 1.0, -0.5), kX, kZ);
    const Scene scene = makeScene({unitLight(), floorMesh(), copies, second});
    ASSERT_EQ(scene.lights.size(), 2u);
    const ExactDirect exact(scene);
    DirectLightSampler cv(test::glContext(), scene, samplerSettings());
    DirectLightSampler plain(test::glContext(), scene, samplerSettings(DirectEstimator::Plain));
    const std::vector<Vec3> receivers = {Vec3(0.0, 0.0, 0.0), Vec3(0.7, 0.0, -0.6), Vec3(0.2, 0.9, 0.1),
                                         Vec3(-1.2, 0.0, 1.1)};
    for (size_t i = 0; i < receivers.size(); ++i)
        for (size_t l = 0; l < 2; ++l) {
            const Vec3& x = receivers[i];
            const double open = exact.unoccludedCosineSolidAngle(l, x, kY);
            ASSERT_GT(open, 0.0);
            EXPECT_NEAR(exact.cosineSolidAngle(l, x, kY), open, 1e-9 * open) << "light " << l << " at " << str(x);
            const DirectSample d = cv.sample(l, x, kY, uint32_t(i));
            EXPECT_NEAR(d.cosineSolidAngle, open, 1e-9 * open) << "light " << l << " at " << str(x);
            EXPECT_EQ(d.visibleSamples, d.lightSamples) << "light " << l << " at " << str(x);
        }
    for (size_t i = 0; i < receivers.size(); ++i)
        for (size_t l = 0; l < 2; ++l)
            expectUnbiased(plain, scene, l, receivers[i], kY, 20 + uint32_t(i), "plain, light in a grey plane");

    const Rendered sampled = renderScene(scene, samplerEstimate(cv), benchCamera(), "light plane, sampled");
    const Rendered reference = renderScene(scene, exactEstimate(exact), benchCamera(), "light plane, exact");
    const CacheError err = cacheError(scene, sampled.caches, reference.caches);
    EXPECT_LE(err.max, 1e-9) << "[lambert], vertex " << err.worst;
}

// === slivers ================================================================

TEST(Stability, SliversAsLightOccluderAndReceiver) {
    // Triangles of aspect ratio 1e4 and more: a second light 1 × 1e-5 seen
    // obliquely, a needle 1.2 × 1e-4 crossing under the unit light
    // diagonally (in the bench occluder's plane, across it), and a receiver
    // strip 3 × 3e-4 running through their shadows. The needle is much
    // thinner than a sampling pixel (~8e-3 across where it is).
    //
    // Two sampler defects this test caught, both fixed: the sampling
    // window's rows followed the sliver light's width (its edge most across
    // the line of sight), so its length ran diagonally through the window
    // and ~1/64 of the pixels held it (single estimates off by 30 % of the
    // unoccluded value, [single] failed); and its corners went to the GPU
    // relative to the eye in world axes, so float rounding of the distance
    // (6e-8 of it) moved its edges by up to 1 % of its width (the plain
    // estimator's mean 0.2 % off, 20 standard errors: [unbiased] failed).
    Mesh sliverLight = quadMesh("sliver light", kLight2, Vec3(0.6, 1.0, 0.1), kX, 1e-5 * kZ);
    Mesh needle;
    needle.name = "needle";
    const Vec3 along = glm::normalize(Vec3(1.0, 0.0, 0.8)), across = glm::normalize(Vec3(-0.8, 0.0, 1.0));
    addQuad(needle, kGrey, Vec3(-0.6, 0.5, -0.45), 1e-4 * across, 1.2 * along);  // facing down
    Mesh strip = quadMesh("strip", kGrey, Vec3(-1.5, 0.0, -0.1), 3e-4 * kZ, 3.0 * kX);
    const Scene scene = makeScene({unitLight(), strip, needle, benchOccluder(), sliverLight});
    ASSERT_EQ(scene.lights.size(), 2u);
    for (const Mesh* m : {&sliverLight, &needle, &strip})
        for (size_t t = 0; t < m->triangles.size(); ++t)
            EXPECT_GE(aspectRatio(m->triangle(t)), 1e4) << m->name << " triangle " << t;
    EXPECT_TRUE(scene.lights[1].planar);

    // On the strip, in both lights' penumbrae (the occluder's, the
    // needle's), in one light's only, in neither.
    const double z = -0.1 + 1.5e-4;
    const std::vector<Vec3> receivers = {Vec3(-1.35, 0.0, z), Vec3(-0.55, 0.0, z), Vec3(-0.25, 0.0, z),
                                         Vec3(0.45, 0.0, z), Vec3(1.35, 0.0, z)};
    DirectLightSampler cv(test::glContext(), scene, samplerSettings());
    DirectLightSampler plain(test::glContext(), scene, samplerSettings(DirectEstimator::Plain));
    const ExactDirect exact(scene);
    for (size_t i = 0; i < receivers.size(); ++i)
        for (size_t l = 0; l < 2; ++l) {
            expectUnbiased(cv, scene, l, receivers[i], kY, 30 + uint32_t(i), "slivers, cv");
            expectUnbiased(plain, scene, l, receivers[i], kY, 40 + uint32_t(i), "slivers, plain");
        }

    const Rendered sampled = renderScene(scene, samplerEstimate(cv), benchCamera(), "slivers, sampled");
    const Rendered reference = renderScene(scene, exactEstimate(exact), benchCamera(), "slivers, exact");
    const CacheError err = cacheError(scene, sampled.caches, reference.caches);
    EXPECT_LE(err.max, 0.02) << "[single], vertex " << err.worst;
    EXPECT_LE(err.mean, 1e-3) << "[single]";
}

// === non-manifold edges and duplicate vertices ===============================

namespace {

// Whether p lies inside triangle t (in its plane, within 1e-9 of its size)
// and t faces along n.
bool coversFacing(const Triangle3& t, const Vec3& p, const Vec3& n) {
    const Vec3 an = glm::cross(t[1] - t[0], t[2] - t[0]);
    const double len = glm::length(an);
    if (!(len > 0) || glm::dot(an / len, n) < 1 - 1e-9) return false;
    const double size = std::sqrt(len);
    if (std::abs(glm::dot(p - t[0], an / len)) > 1e-9 * size) return false;
    for (int k = 0; k < 3; ++k)
        if (glm::dot(glm::cross(t[(k + 1) % 3] - t[k], p - t[k]), an) < 0) return false;
    return true;
}

// What a cache mesh must keep of the scene, however the scene's meshes are
// connected: every object triangle's front side, covered as many times as
// the scene covers it (faces OpenMesh refuses as non-manifold are detached,
// not lost, and none is doubled; the cache may add reversed copies for
// backs, which face the other way), with no edge longer than the
// bisection's limit and unit normals on each triangle's front side.
void expectCacheCoversTheScene(const Scene& scene, const IrradianceMeshCopy& view, double maxEdgeFraction,
                               const std::string& what) {
    std::vector<Triangle3> cacheTriangles;
    const double maxEdge = maxEdgeFraction * scene.bounds.diagonal();
    size_t longEdges = 0, flipped = 0;
    for (const glm::uvec3& t : view.triangles) {
        const Triangle3 p = {view.positions[t.x], view.positions[t.y], view.positions[t.z]};
        cacheTriangles.push_back(p);
        const Vec3 an = glm::cross(p[1] - p[0], p[2] - p[0]);
        for (int k = 0; k < 3; ++k) longEdges += glm::length(p[(k + 1) % 3] - p[k]) > maxEdge * (1 + 1e-12);
        // Vertex normals are the scene's (interpolated along split edges):
        // on the side the triangle's winding says.
        flipped += glm::dot(an, view.normals[t.x] + view.normals[t.y] + view.normals[t.z]) <= 0;
    }
    EXPECT_EQ(longEdges, 0u) << what << ": edges longer than " << maxEdge;
    EXPECT_EQ(flipped, 0u) << what << ": triangles facing away from their normals";
    for (size_t v = 0; v < view.normals.size(); ++v)
        ASSERT_NEAR(glm::length(view.normals[v]), 1.0, 1e-12) << what << ", vertex " << v;

    std::vector<Triangle3> sceneTriangles;
    for (const Mesh& m : scene.meshes)
        for (size_t t = 0; t < m.triangles.size(); ++t) sceneTriangles.push_back(m.triangle(t));
    for (const Mesh& m : scene.meshes) {
        bool isLight = false;
        for (const Light& l : scene.lights) isLight = isLight || &scene.meshes[l.mesh] == &m;
        if (isLight) continue;  // what the cache keeps of a light is its own affair
        for (size_t t = 0; t < m.triangles.size(); ++t) {
            const Triangle3 p = m.triangle(t);
            const Vec3 n = glm::normalize(m.areaNormal(t));
            // A point inside the triangle, at barycentrics no bisection
            // lands on (its centroid or a dyadic point could lie on a cache
            // edge, inside two cache triangles).
            const Vec3 x = 0.4711 * p[0] + 0.3137 * p[1] + 0.2152 * p[2];
            size_t inScene = 0, inCache = 0;
            for (const Triangle3& q : sceneTriangles) inScene += coversFacing(q, x, n);
            for (const Triangle3& q : cacheTriangles) inCache += coversFacing(q, x, n);
            EXPECT_EQ(inCache, inScene) << what << ": mesh '" << m.name << "' triangle " << t << " at " << str(x);
        }
    }
}

// How many triangles use each edge, by vertex index or by position.
template <typename Key, typename KeyOf>
std::map<std::pair<Key, Key>, int> edgeUse(const Mesh& m, KeyOf keyOf) {
    std::map<std::pair<Key, Key>, int> use;
    for (const glm::uvec3& t : m.triangles)
        for (int k = 0; k < 3; ++k) {
            Key a = keyOf(t[k]), b = keyOf(t[(k + 1) % 3]);
            if (b < a) std::swap(a, b);
            ++use[{a, b}];
        }
    return use;
}

using PositionKey = std::array<double, 3>;

}  // namespace

TEST(Stability, BookOfPagesThroughLoaderAndCache) {
    // tests/data/stability_book.obj: an open book of four pages hinged on
    // one spine, three of them on the same two vertices (a non-manifold
    // edge), one on duplicates of them; a floor whose second quad repeats
    // two corners of the first; two degenerate faces. The pages look up
    // within 40° of the vertical, the spine's normal is vertical and the
    // lamp is above: no shading normal makes a receiver see the light
    // through its own page (where the sampler, lifting its eye off the
    // surface, and the exact reference, which ignores the receiver's own
    // surface, would rightly disagree).
    const std::string path = dataFile("stability_book.obj");
    const Scene scene = loadObj(path);
    EXPECT_EQ(scene.warnings, (std::vector<std::string>{path + ": dropped 2 degenerate triangles (first at line 48)"}));
    ASSERT_EQ(scene.meshes.size(), 3u);
    ASSERT_EQ(scene.lights.size(), 1u);
    const Mesh& floor = scene.meshes[0];
    const Mesh& book = scene.meshes[1];
    ASSERT_EQ(book.name, "book");
    // The floor's repeated corners are welded (same position, same normal).
    EXPECT_EQ(floor.positions.size(), 6u);
    // The book keeps what the file says: the spine edge is used by the
    // three pages sharing it, and by four triangles counting positions.
    auto byIndex = edgeUse<uint32_t>(book, [](uint32_t v) { return v; });
    auto byPosition = edgeUse<PositionKey>(book, [&](uint32_t v) {
        const Vec3& p = book.positions[v];
        return PositionKey{p.x, p.y, p.z};
    });
    int maxByIndex = 0, maxByPosition = 0;
    for (const auto& [e, n] : byIndex) maxByIndex = std::max(maxByIndex, n);
    for (const auto& [e, n] : byPosition) maxByPosition = std::max(maxByPosition, n);
    EXPECT_EQ(maxByIndex, 3);
    EXPECT_EQ(maxByPosition, 4);
    EXPECT_EQ(book.triangles.size(), 8u);
    for (size_t v = 0; v < book.normals.size(); ++v) EXPECT_NEAR(glm::length(book.normals[v]), 1.0, 1e-15);

    const double maxEdgeFraction = 1.0 / 16;
    {
        CacheSettings cs;
        cs.maxEdgeFraction = maxEdgeFraction;
        IrradianceCache cache(scene, cs);
        const IrradianceMeshCopy view = cache.copyMesh(0);
        expectCacheCoversTheScene(scene, view, maxEdgeFraction, "book");
        // Each page is bisected on its own along the shared spine, at
        // midpoints: every page must end with the same spine vertices, or
        // the pages' shading would not meet there.
        std::map<int, std::set<double>> spineCuts;  // page side (by normal) -> x of spine vertices
        for (const glm::uvec3& t : view.triangles) {
            const Triangle3 p = {view.positions[t.x], view.positions[t.y], view.positions[t.z]};
            const Vec3 n = glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
            if (std::abs(n.x) > 1e-9 || p[0].y < 0.1 || p[0].y > 1.0) continue;  // the floor or the lamp
            const int page = int(std::lround(std::atan2(n.y, n.z) * 180 / kPi));
            for (const Vec3& q : p)
                if (std::abs(q.y - 0.3) < 1e-12 && std::abs(q.z) < 1e-12) spineCuts[page].insert(q.x);
        }
        ASSERT_GE(spineCuts.size(), 4u);
        for (const auto& [page, cuts] : spineCuts)
            EXPECT_EQ(cuts, spineCuts.begin()->second) << "page at " << page << " degrees";
        EXPECT_GT(spineCuts.begin()->second.size(), 2u);  // the spine was split
    }

    const ExactDirect exact(scene);
    DirectLightSampler cv(test::glContext(), scene, samplerSettings());
    Camera camera;
    camera.position = Vec3(1.6, 1.4, 2.2);
    camera.target = Vec3(0.0, 0.3, 0.0);
    camera.fovYDegrees = 45;
    const Rendered sampled = renderScene(scene, samplerEstimate(cv), camera, "book, sampled", maxEdgeFraction);
    const Rendered reference = renderScene(scene, exactEstimate(exact), camera, "book, exact", maxEdgeFraction);
    const CacheError err = cacheError(scene, sampled.caches, reference.caches);
    EXPECT_LE(err.max, 0.02) << "[single], vertex " << err.worst;
    EXPECT_LE(err.mean, 1e-3) << "[single]";
}

TEST(Stability, CacheKeepsNonManifoldFacesWhole) {
    // Built by hand, so the cache meets what a loader might not produce:
    // five fins hinged on one edge (shared vertex indices), a fin listed
    // twice, two triangles touching at one vertex only (a bow tie), and a
    // triangle on duplicates of another's vertices. Every face looks up
    // within 35° of the vertical and the light is above (seen at least 50°
    // above the horizontal), so no shading normal makes a receiver see the
    // light through its own surface.
    Mesh fins;
    fins.name = "fins";
    const Vec3 a(-0.4, 0.3, 0.0), b(0.4, 0.3, 0.0);
    fins.positions = {a, b};
    fins.normals = {kY, kY};
    // (side, elevation): the far corner of fin k, 0.4 from the hinge.
    const std::pair<double, double> finAt[] = {{1, 5}, {1, 20}, {1, 35}, {-1, 10}, {-1, 30}};
    for (int k = 0; k < 5; ++k) {
        const auto [side, degrees] = finAt[k];
        const double t = glm::radians(degrees);
        fins.positions.push_back(Vec3(0.1 * k - 0.2, 0.3 + 0.4 * std::sin(t), side * 0.4 * std::cos(t)));
        fins.normals.push_back(Vec3(0.0, std::cos(t), -side * std::sin(t)));
        fins.triangles.push_back(side > 0 ? glm::uvec3(0, uint32_t(2 + k), 1) : glm::uvec3(0, 1, uint32_t(2 + k)));
    }
    fins.triangles.push_back(fins.triangles[2]);  // listed twice
    // The bow tie: two triangles meeting at (0.8, 0.3, 0).
    const uint32_t c = uint32_t(fins.positions.size());
    for (const Vec3& p : {Vec3(0.8, 0.3, 0.0), Vec3(1.1, 0.25, 0.1), Vec3(1.1, 0.35, -0.1), Vec3(0.5, 0.25, -0.1),
                          Vec3(0.5, 0.35, 0.1)}) {
        fins.positions.push_back(p);
        fins.normals.push_back(kY);
    }
    fins.triangles.push_back({c, c + 1, c + 2});
    fins.triangles.push_back({c, c + 3, c + 4});
    // Duplicates of the bow tie's far corners, carrying a third triangle.
    const uint32_t d = uint32_t(fins.positions.size());
    for (const uint32_t v : {c + 1, c + 2}) {
        fins.positions.push_back(fins.positions[v]);
        fins.normals.push_back(kY);
    }
    fins.positions.push_back(Vec3(1.4, 0.3, 0.0));
    fins.normals.push_back(kY);
    fins.triangles.push_back({d + 1, d, d + 2});
    fins.materials.assign(fins.triangles.size(), kGrey);
    fins.sourceLines.assign(fins.triangles.size(), 0);
    const Scene scene = makeScene({unitLight(), floorMesh(), fins});

    for (double fraction : {1.0 / 8, 1.0 / 40}) {
        CacheSettings cs;
        cs.maxEdgeFraction = fraction;
        IrradianceCache cache(scene, cs);
        expectCacheCoversTheScene(scene, cache.copyMesh(0), fraction, concat("fins, edges below ", fraction));
    }
    const ExactDirect exact(scene);
    DirectLightSampler cv(test::glContext(), scene, samplerSettings());
    const Rendered sampled = renderScene(scene, samplerEstimate(cv), benchCamera(), "fins, sampled", 1.0 / 40);
    const Rendered reference = renderScene(scene, exactEstimate(exact), benchCamera(), "fins, exact", 1.0 / 40);
    const CacheError err = cacheError(scene, sampled.caches, reference.caches);
    EXPECT_LE(err.max, 0.02) << "[single], vertex " << err.worst;
    EXPECT_LE(err.mean, 1e-3) << "[single]";
}

// === scale ==================================================================

namespace {

// The Cornell box scaled about the origin so that its diagonal is `size`.
Scene scaledCornell(double size) {
    Scene scene = makeCornellBox();
    const double s = size / scene.bounds.diagonal();
    for (Mesh& m : scene.meshes)
        for (Vec3& p : m.positions) p *= s;
    scene.camera->position *= s;
    scene.camera->target *= s;
    scene.finalize();
    return scene;
}

}  // namespace

TEST(Stability, CornellBoxFromAMillimetreToAHundredKilometres) {
    // The Cornell box scaled to a diagonal of 1e-3 and 1e5 units, against
    // 1 (as built, in millimetres, it is ~960 across). The cosine-weighted
    // solid angle is dimensionless, and the sampler, the exact reference,
    // the cache and the compositor all work relative to the scene's size:
    // every result must be the same at every scale.
    const Scene unit = scaledCornell(1.0);
    const ExactDirect exactUnit(unit);
    DirectLightSampler cvUnit(test::glContext(), unit, samplerSettings());
    const double edges = 1.0 / 16;  // 1,343 cache vertices
    const Rendered unitRender = renderScene(unit, samplerEstimate(cvUnit), *unit.camera, "Cornell box 1 across", edges);
    // Every other cache vertex of the unit box, scaled, are the receivers at
    // every scale.
    const IrradianceMeshCopy& points = unitRender.caches[0];
    for (double size : {1e-3, 1e5}) {
        const Scene scene = scaledCornell(size);
        const double s = size / unit.bounds.diagonal();
        DirectLightSampler cv(test::glContext(), scene, samplerSettings());
        const ExactDirect exact(scene);
        const std::string what = concat("Cornell box ", size, " across");
        const Rendered rendered = renderScene(scene, samplerEstimate(cv), *scene.camera, what, edges);

        double sumError = 0;
        size_t lit = 0, differ = 0;
        for (size_t v = 0; v < points.positions.size(); v += 2) {
            const Vec3 x = points.positions[v], n = points.normals[v];
            const std::string at = what + ", point " + str(x);
            const double open = exactUnit.unoccludedCosineSolidAngle(0, x, n);
            EXPECT_NEAR(exact.unoccludedCosineSolidAngle(0, s * x, n), open, 1e-10 * open) << at;
            if (!(open > 0)) continue;
            ++lit;
            // ExactDirect promises 1e-12 relative at any scale: the two
            // evaluations differ by at most twice that; 1e-10 of the
            // unoccluded value leaves room for grazing receivers.
            const double e1 = exactUnit.cosineSolidAngle(0, x, n), es = exact.cosineSolidAngle(0, s * x, n);
            EXPECT_NEAR(es, e1, 1e-10 * open) << at;
            // The same seed tests the same points of the same windows, so
            // the estimates agree except where rounding of a scaled vertex
            // (6e-8 of the scene in float) flips a test lying within
            // ~1e-6 pixel of an edge: rare (measured: 0 or 1 point in 1,300),
            // at most 1 % of the points here, each within [single] anyway.
            const double d1 = cvUnit.sample(0, x, n, uint32_t(v)).cosineSolidAngle;
            const double ds = cv.sample(0, s * x, n, uint32_t(v)).cosineSolidAngle;
            differ += !(std::abs(d1 - ds) <= 1e-9 * open);
            EXPECT_NEAR(ds, es, 0.02 * open) << "[single], " << at;
            sumError += std::abs(ds - es) / open;
        }
        EXPECT_GT(lit, 500u) << what;
        EXPECT_LE(differ, lit / 100) << what << ": estimates that changed with the scale";
        EXPECT_LE(sumError / double(lit), 1e-3) << "[single], " << what;

        // The images: caches bisected alike (up to ties between equal edge
        // lengths, which rounding may break differently) and sampled alike
        // (up to the flips above), drawn through the same camera. Their
        // relative RMSE (test_render's metric) within 1e-3, a tenth of what
        // test_render allows between sampled and exact caches (measured:
        // 5e-5 and 2e-4).
        EXPECT_LE(relativeRmse(rendered.image, unitRender.image), 1e-3) << what;
    }
}

// === radiance ===============================================================

TEST(Stability, LightRadianceFromMicroToMega) {
    // The Cornell box with its light's radiance times 1e-6 and 1e6, and with
    // its light split into two (a triangle each) of 1e6 and 1e-6. Irradiance
    // is linear in radiance: with the same seeds every cached value scales
    // exactly (the sampler's estimate does not depend on radiance; one
    // product rounds: 1e-12 relative is 4,500 roundings) and so does every
    // pixel, to [float]. No threshold, clamp or epsilon may break that.
    // Linearity carries the accuracy of the unit radiance, checked against
    // the exact reference here at every 8th vertex.
    const double edges = 1.0 / 16;
    auto render = [&](const Scene& scene, const std::string& what) {
        DirectLightSampler cv(test::glContext(), scene, samplerSettings());
        return renderScene(scene, samplerEstimate(cv), *scene.camera, what, edges);
    };
    const Scene unitScene = makeCornellBox();
    const Rendered unitRender = render(unitScene, "radiance x1");
    {
        const ExactDirect exact(unitScene);
        const IrradianceMeshCopy& view = unitRender.caches[0];
        const double l = unitScene.lights[0].radiance.r;  // the largest channel
        for (size_t v = 0; v < view.positions.size(); v += 8) {
            const double open = l * exact.unoccludedCosineSolidAngle(0, view.positions[v], view.normals[v]);
            const Rgb e = exact.irradiance(0, view.positions[v], view.normals[v]);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(view.irradiance[v][c], e[c], 0.02 * open) << "[single], vertex " << v;
        }
    }
    auto expectCacheScaled = [](const IrradianceMeshCopy& view, const IrradianceMeshCopy& unit, double factor,
                                const std::string& what) {
        ASSERT_EQ(view.irradiance.size(), unit.irradiance.size()) << what;
        for (size_t v = 0; v < view.irradiance.size(); ++v)
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(view.irradiance[v][c] / factor, unit.irradiance[v][c], 1e-12 * unit.irradiance[v][c])
                    << what << ", vertex " << v << " channel " << c;
    };
    for (double factor : {1e-6, 1e6}) {
        Scene scene = makeCornellBox();
        for (Material& m : scene.materials) m.ke *= factor;
        scene.finalize();
        const std::string what = concat("radiance x", factor);
        const Rendered rendered = render(scene, what);
        expectCacheScaled(rendered.caches[0], unitRender.caches[0], factor, what);
        expectImageScaled(rendered.image, unitRender.image, factor, what);
    }

    // Two lights of 1e6 and 1e-6 side by side, against the same two at 1:
    // each light's cache scales by its own factor; in the image the dim one
    // vanishes below float rounding, as it should.
    auto split = [](double first, double second) {
        Scene scene = makeCornellBox();
        Mesh& light = scene.meshes.back();
        const uint32_t lamp = light.materials.at(0);
        Material dim = scene.materials[lamp];
        dim.name = "lamp 2";
        dim.ke *= second;
        scene.materials[lamp].ke *= first;
        scene.materials.push_back(dim);
        light.materials.at(1) = uint32_t(scene.materials.size() - 1);
        scene.finalize();
        return scene;
    };
    const Scene both = split(1.0, 1.0), mixed = split(1e6, 1e-6);
    ASSERT_EQ(mixed.lights.size(), 2u);
    const Rendered bothRender = render(both, "two lights of 1"), mixedRender = render(mixed, "lights of 1e6 and 1e-6");
    expectCacheScaled(mixedRender.caches[0], bothRender.caches[0], 1e6, "the 1e6 light");
    expectCacheScaled(mixedRender.caches[1], bothRender.caches[1], 1e-6, "the 1e-6 light");
}
