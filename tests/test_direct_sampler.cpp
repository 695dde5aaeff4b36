// The GPU direct-light sampler (§4 of Fournier & Péroche) against the exact
// occluded irradiance on the paper's bench (§6.1): every scheme, both
// estimators, with each tolerance derived from what the scheme is.
//
// Reference point. The estimates are compared with the exact value at the
// receiver x. The sampler renders from an eye lifted to
// x + n·eyeOffset·diagonal (DirectSamplerSettings::eyeOffset: 4.4e-6 on the
// bench) so that a receiver never shadows itself; depending on the
// estimator, the lift moves its expectation by up to
// |E(eye) − E(x)| + |Lambert(eye) − Lambert(x)| (plain: by the first term;
// the control variate, which subtracts occluded samples seen from the eye
// from Lambert's value at x: by at most the sum). That "lift allowance" is
// computed exactly and added to statistical tolerances; on the bench it is
// below 1e-4 of the answer (EyeLiftCostsLessThanATenThousandth).
#include "core/Error.h"
#include "core/reference/ExactIrradiance.h"
#include "core/reference/Lambert.h"
#include "core/scenes/BenchScene.h"
#include "core/scenes/CornellBox.h"
#include "core/scenes/OfficeScene.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/direct/Jitter.h"
#include "gpu_sampling/direct/LightFrustum.h"
#include "gpu_sampling/direct/OccluderBvh.h"
#include "gpu_sampling/direct/OccluderPolygons.h"
#include "gpu_sampling/gl/GlContext.h"

#include "BenchReference.h"
#include "GlTestContext.h"
#include "MeanAndError.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <tuple>

using namespace ml;
using test::benchExact, test::benchScene, test::exactAt, test::lambertAt;
using test::clearOfPenumbra, test::eyePoint, test::liftAllowance, test::penumbraReceivers;
using test::MeanAndError, test::meanOf;

namespace {

// --- shared state: one GL context, one sampler per setting -----------------

using SamplerKey = std::tuple<DirectMethod, DirectEstimator, int, int>;

class GlEnvironment {
public:
    // Samplers compile a program per variant: keep one per setting.
    static DirectLightSampler& sampler(DirectMethod method, DirectEstimator estimator, int imageSize, int bits) {
        const SamplerKey key{method, estimator, imageSize, bits};
        auto it = samplers_.find(key);
        if (it == samplers_.end()) {
            DirectSamplerSettings s;
            s.method = method;
            s.estimator = estimator;
            s.imageSize = imageSize;
            s.bits = bits;
            if (samplers_.empty()) test::GlTestEnvironment::beforeTearDown([] { samplers_.clear(); });
            it = samplers_.emplace(key, std::make_unique<DirectLightSampler>(test::glContext(), benchScene(), s)).first;
        }
        return *it->second;
    }
private:
    static inline std::map<SamplerKey, std::unique_ptr<DirectLightSampler>> samplers_;
};

constexpr auto kQuery = DirectMethod::OcclusionQuery;
constexpr auto kRegular = DirectMethod::Regular;
constexpr auto kJittered = DirectMethod::Jittered;
constexpr auto kPlain = DirectEstimator::Plain;
constexpr auto kCv = DirectEstimator::ControlVariate;

const Vec3 kUp(0, 1, 0);

double sampleValue(DirectLightSampler& s, const Vec3& x, const Vec3& n, uint32_t seed) {
    const double e = s.sample(0, x, n, seed).cosineSolidAngle;
    EXPECT_TRUE(std::isfinite(e)) << "at (" << x.x << ", " << x.y << ", " << x.z << ")";
    return e;
}

// The bench light as one convex polygon (its two triangles (a,b,c), (a,c,d)).
std::vector<Vec3> benchLightPolygon() {
    const Light& light = benchScene().lights[0];
    return {light.geometry[0][0], light.geometry[0][1], light.geometry[0][2], light.geometry[1][2]};
}

std::vector<ReceiverPoint> unoccludedReceivers() {
    std::vector<ReceiverPoint> out;
    for (const ReceiverPoint& r : makeBenchReceivers(20))
        if (clearOfPenumbra(r.position, 0.02)) out.push_back(r);
    return out;
}

// --- a deterministic error bound for the plain estimator ------------------
//
// Plain sums, over every jittered sample that falls on the light, the
// sample's weight w(u, v)·A/bits, where (u, v) is the sample's point on the
// image plane d = 1, A the pixel's area there and w = (n·s)/|s|⁴ with
// s = (u, v, 1) (eq. 3: cosθ·dω = w du dv). The exact value is ∫ w over the
// light's image. Per pixel:
//  * a pixel the light's image covers entirely: each of its `bits` strata
//    is sampled once, and the error of one stratum is |w(sample) − mean of w
//    over the stratum|·A/bits ≤ G·diag·A/bits, G bounding |∇w| on the pixel
//    and diag the stratum's diagonal; the pixel errs by at most G·diag·A;
//  * a pixel the light's boundary crosses: estimate and truth both lie in
//    [0, A·max w], so it errs by at most A·max w;
//  * any other pixel: no sample on the light, no light, no error.
// Bounds on the pixel [u0,u1]×[v0,v1], with q = 1 + u² + v² ≥ q_min,
// ρ = √(u² + v²) ≤ ρ_max and c = max(0, n·s) ≤ c_max (n·s is affine in
// (u, v), so its maximum is at a corner): w ≤ c_max/q_min²; and
// ∇w = n_uv/q² − 4(u, v)(n·s)/q³, so |∇w| ≤ |n_uv|/q_min² + 4ρ_max·c_max/q_min³
// (the sampler skips samples with n·s ≤ 0, so its integrand is max(0, w),
// which has the same bounds).
// The bound is worst-case (every pixel erring its maximum in the same
// direction); the jittered errors are independent and mostly cancel, so the
// errors measured are 2% to 7% of it. It is a check that nothing outside
// this accounting errs (a missed pixel, a wrong weight, a wrong window).
struct PlainBound {
    double total = 0;
    int boundaryPixels = 0;
    int interiorPixels = 0;
};

void addFrustumBound(const SamplingFrustum& f, const std::vector<Vec3>& lightPolygon, const Vec3& n, int size,
                     int bits, PlainBound& bound) {
    // The light in camera coordinates, clipped to the window's pyramid and
    // to the receiver's upper half-space (samples below it weigh nothing).
    Polygon3 cam;
    for (const Vec3& p : lightPolygon) cam.push_back(f.toCamera(p));
    const Vec3 nc(glm::dot(n, f.right), glm::dot(n, f.up), glm::dot(n, f.forward));
    const Vec3 planes[5] = {{1, 0, -f.left}, {-1, 0, f.rightEdge}, {0, 1, -f.bottom}, {0, -1, f.top}, nc};
    for (const Vec3& a : planes)
        if (!cam.empty()) cam = clipPolygon(cam, a, 0.0);
    if (cam.empty()) return;
    std::vector<Vec2> poly;
    for (const Vec3& c : cam) poly.emplace_back(c.x / c.z, c.y / c.z);
    double twiceArea = 0;
    for (size_t i = 0; i < poly.size(); ++i)
        twiceArea += poly[i].x * poly[(i + 1) % poly.size()].y - poly[i].y * poly[(i + 1) % poly.size()].x;
    if (twiceArea < 0) std::reverse(poly.begin(), poly.end());  // counter-clockwise

    int sx = 1, sy = 1;
    jitter::strata(bits, sx, sy);
    const double pw = (f.rightEdge - f.left) / size, ph = (f.top - f.bottom) / size, area = pw * ph;
    const double stratumDiagonal = std::hypot(pw / sx, ph / sy);
    const double nuv = std::hypot(nc.x, nc.y);
    for (int j = 0; j < size; ++j)
        for (int i = 0; i < size; ++i) {
            const double u0 = f.left + i * pw, u1 = u0 + pw, v0 = f.bottom + j * ph, v1 = v0 + ph;
            const Vec2 corners[4] = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}};
            bool allInside = true, separated = false;
            for (size_t e = 0; e < poly.size(); ++e) {
                const Vec2 a = poly[e], b = poly[(e + 1) % poly.size()];
                int outside = 0;
                for (const Vec2& c : corners) {
                    const double side = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
                    if (side < 0) ++outside;
                }
                if (outside > 0) allInside = false;
                if (outside == 4) separated = true;
            }
            if (separated) continue;  // no part of the light here
            const double du = u0 > 0 ? u0 : (u1 < 0 ? -u1 : 0.0);
            const double dv = v0 > 0 ? v0 : (v1 < 0 ? -v1 : 0.0);
            const double qMin = 1 + du * du + dv * dv;
            double rhoMax = 0, cosMax = 0;
            for (const Vec2& c : corners) {
                rhoMax = std::max(rhoMax, glm::length(c));
                cosMax = std::max(cosMax, nc.x * c.x + nc.y * c.y + nc.z);
            }
            if (allInside) {
                const double g = nuv / (qMin * qMin) + 4 * rhoMax * cosMax / (qMin * qMin * qMin);
                bound.total += g * stratumDiagonal * area;
                ++bound.interiorPixels;
            } else {
                bound.total += area * cosMax / (qMin * qMin);
                ++bound.boundaryPixels;
            }
        }
}

// The frusta the sampler uses at (x, n) for the bench light (same eye, same
// alignment edge, same split angle), and the bound over all of them.
std::vector<SamplingFrustum> benchFrusta(const Vec3& x, const Vec3& n) {
    const Light& light = benchScene().lights[0];
    const Vec3 eye = eyePoint(x, n);
    return fitFrusta(visibleLightPieces(light, eye, n), eye, light.geometry[0][1] - light.geometry[0][0],
                     DirectSamplerSettings{}.maxHalfAngleDegrees);
}

PlainBound plainBound(const Vec3& x, const Vec3& n, int size, int bits) {
    PlainBound bound;
    for (const SamplingFrustum& f : benchFrusta(x, n)) addFrustumBound(f, benchLightPolygon(), n, size, bits, bound);
    return bound;
}

// === the eye offset ========================================================

TEST(DirectSampler, EyeLiftCostsLessThanATenThousandth) {
    // For a receiver parallel to the light's plane at height h, with
    // cosθ = cosθ' = h/r: E = ∫ h²/r⁴ dA, and dE/dh = ∫ (2h/r⁴ − 4h³/r⁶) dA,
    // so |dE/dh| ≤ 6E/h. On the bench floor h = 1 and the eye is lifted by
    // δ = 1e-6 × the diagonal (4.36): |Lambert(eye) − Lambert(x)| ≤ 6·E·δ/h
    // = 2.6e-5·E. In the penumbra the lift also moves the occluder's shadow
    // edges by ~δ, a change of the same order; so over the whole grid the
    // lift allowance stays below 1e-4 of Lambert's value, far below every
    // sampling error measured here.
    const double delta = DirectSamplerSettings{}.eyeOffset * benchScene().bounds.diagonal();
    for (const ReceiverPoint& r : unoccludedReceivers()) {
        const double atX = lambertAt(r.position, r.normal);
        const double atEye = lambertAt(eyePoint(r.position, r.normal), r.normal);
        EXPECT_LE(std::abs(atEye - atX), 6 * atX * delta / 1.0);
    }
    for (const ReceiverPoint& r : makeBenchReceivers(20))
        EXPECT_LE(liftAllowance(r.position, r.normal), 1e-4 * lambertAt(r.position, r.normal))
            << "at (" << r.position.x << ", " << r.position.z << ")";
}

// === unoccluded receivers ==================================================

TEST(DirectSampler, ControlVariateIsLambertWhereNothingOccludes) {
    // Where no sample is occluded the control-variate estimate is Lambert's
    // closed form at the receiver with nothing subtracted: the same formula
    // at the same point, over the light's two triangles instead of its
    // outline. The sums differ only by rounding (1e-15 relative); 1e-9
    // leaves room for a different but equally exact summation order.
    const std::vector<ReceiverPoint> receivers = unoccludedReceivers();
    ASSERT_GE(receivers.size(), 100u);
    for (auto [method, size, bits] : {std::tuple{kJittered, 64, 4}, std::tuple{kJittered, 32, 1},
                                      std::tuple{kJittered, 64, 8}, std::tuple{kRegular, 64, 1}}) {
        DirectLightSampler& s = GlEnvironment::sampler(method, kCv, size, bits);
        for (size_t i = 0; i < receivers.size(); ++i) {
            const ReceiverPoint& r = receivers[i];
            // The exact reference agrees that nothing occludes here.
            ASSERT_EQ(benchExact().cosineSolidAngle(0, r.position, r.normal),
                      benchExact().unoccludedCosineSolidAngle(0, r.position, r.normal));
            const DirectSample d = s.sample(0, r.position, r.normal, jitter::seedFor(1, uint32_t(i)));
            const double lambert = cosineSolidAngle(r.position, r.normal, benchLightPolygon());
            EXPECT_EQ(d.visibleSamples, d.lightSamples);
            // Answered in closed form (most of them), no sample is tested;
            // rasterised, the light holds samples.
            EXPECT_EQ(d.lightSamples > 0, d.path == DirectPath::Rasterised);
            EXPECT_EQ(d.frusta, 1u);
            EXPECT_NEAR(d.cosineSolidAngle, lambert, 1e-9 * lambert)
                << directMethodName(method) << " " << size << "² × " << bits << " at (" << r.position.x << ", "
                << r.position.z << ")";
            EXPECT_NEAR(d.unoccluded, lambert, 1e-9 * lambert);
            EXPECT_NEAR(d.irradiance.g, lambert, 1e-9 * lambert);  // Ke = 1
        }
    }
}

TEST(DirectSampler, PlainJitteredErrorIsWithinTheBoundaryPixelBound) {
    const std::vector<ReceiverPoint> receivers = unoccludedReceivers();
    for (auto [size, bits] : {std::pair{32, 1}, std::pair{64, 1}, std::pair{64, 4}, std::pair{32, 8}}) {
        DirectLightSampler& s = GlEnvironment::sampler(kJittered, kPlain, size, bits);
        for (size_t i = 0; i < receivers.size(); ++i) {
            const ReceiverPoint& r = receivers[i];
            const PlainBound bound = plainBound(r.position, r.normal, size, bits);
            // A convex outline crosses at most 2·size columns and 2·size rows
            // of pixels, each crossing entering one new pixel: ≤ 4·size + 4.
            ASSERT_LE(bound.boundaryPixels, 4 * size + 4);
            ASSERT_GT(bound.interiorPixels, size * size / 4);  // the light fills its window
            // The bound is for the image seen from the eye; the lift adds its
            // allowance (below 1e-4 of the value, see above).
            const double exact = lambertAt(r.position, r.normal);
            const double e = sampleValue(s, r.position, r.normal, jitter::seedFor(2, uint32_t(i)));
            EXPECT_LE(std::abs(e - exact), bound.total + liftAllowance(r.position, r.normal))
                << size << "² × " << bits << " at (" << r.position.x << ", " << r.position.z << "): exact " << exact
                << ", boundary pixels " << bound.boundaryPixels << ", interior " << bound.interiorPixels;
        }
    }
    // The bound is not vacuous: of the order of 4·size boundary pixels'
    // weight, a few percent of the answer under the light's centre.
    const PlainBound b = plainBound(Vec3(0, 0, 0), kUp, 64, 4);
    EXPECT_LT(b.total, 0.2 * lambertAt(Vec3(0, 0, 0), kUp));
}

// === jittered sampling is unbiased =========================================

TEST(DirectSampler, JitteredMeanOfManyPassesConvergesToExact) {
    // Each pass draws fresh jitter (seed per pass), so passes are
    // independent, identically distributed estimates; if the scheme is
    // unbiased their mean is within 4 standard errors of the exact value
    // except with probability ~1e-4 (Student's t, 63 degrees of freedom).
    // Over the 40 checks below a correct sampler fails with probability
    // below 1%; the seeds are fixed, so the outcome is reproducible. The
    // lift allowance (≤ 1e-4 of the value) is added: it is a known offset of
    // the expectation, not a sampling bias.
    constexpr int kPasses = 64;
    const std::vector<ReceiverPoint> receivers = penumbraReceivers(10);
    ASSERT_EQ(receivers.size(), 10u);
    for (auto estimator : {kPlain, kCv})
        for (int bits : {1, 4}) {
            DirectLightSampler& s = GlEnvironment::sampler(kJittered, estimator, 64, bits);
            for (size_t i = 0; i < receivers.size(); ++i) {
                const ReceiverPoint& r = receivers[i];
                std::vector<double> passes;
                for (int k = 0; k < kPasses; ++k)
                    passes.push_back(
                        sampleValue(s, r.position, r.normal, jitter::seedFor(3, uint32_t(i), 0, uint32_t(k))));
                test::expectUnbiased(passes, exactAt(r.position, r.normal), liftAllowance(r.position, r.normal),
                                     concat(directEstimatorName(estimator), " × ", bits, " bits at (", r.position.x,
                                            ", ", r.position.z, ")"));
            }
        }
}

// === error against image size and bits =====================================

TEST(DirectSampler, ErrorShrinksWithImageSizeAndBitsAsJitteredEdgesPredict) {
    // Jittered sampling of a region with a smooth edge, with M strata of
    // side h: only the ~L/h strata the edge crosses are uncertain, each by
    // at most its area h², independently, so the error's deviation is
    // ~ √(L/h)·h² ∝ h^(3/2) ∝ M^(−3/4). Quadrupling M (image 32 → 64, or
    // bits 1 → 4, 2×2 strata per pixel) divides the error by 4^(3/4) ≈ 2.83;
    // doubling it (bits 4 → 8) by 2^(3/4) ≈ 1.68. The plain estimator adds
    // the smooth interior's error, which falls faster (M^(−1)).
    //
    // Mean |error| over the 400 points of a 20×20 grid, two passes each:
    // per-point errors spread by about their own size, so the mean is known
    // to ~4% and a ratio to ~6%. We require half the predicted reduction in
    // the logarithm (ratio ≤ 4^(−3/8) = 0.59 and 2^(−3/8) = 0.77), far
    // outside that noise yet failing if the error stopped falling. (The eye's
    // lift, which does not shrink, is ≤ 1e-4 of the value, 2e-6 on average,
    // against mean errors ≥ 5e-5.)
    const std::vector<ReceiverPoint> receivers = makeBenchReceivers(20);
    std::vector<double> exact;
    for (const ReceiverPoint& r : receivers) exact.push_back(exactAt(r.position, r.normal));
    auto meanError = [&](DirectEstimator estimator, int size, int bits) {
        DirectLightSampler& s = GlEnvironment::sampler(kJittered, estimator, size, bits);
        double sum = 0;
        for (uint32_t pass = 0; pass < 2; ++pass)
            for (size_t i = 0; i < receivers.size(); ++i)
                sum += std::abs(sampleValue(s, receivers[i].position, receivers[i].normal,
                                            jitter::seedFor(4, uint32_t(i), 0, pass)) - exact[i]);
        return sum / (2.0 * double(receivers.size()));
    };
    const double quadruple = std::pow(4.0, -0.75), twice = std::pow(2.0, -0.75);
    for (auto estimator : {kPlain, kCv}) {
        const double e32x1 = meanError(estimator, 32, 1), e64x1 = meanError(estimator, 64, 1);
        const double e64x4 = meanError(estimator, 64, 4), e64x8 = meanError(estimator, 64, 8);
        const char* name = directEstimatorName(estimator);
        EXPECT_LE(e64x1 / e32x1, std::sqrt(quadruple)) << name << ": 32² → 64², " << e32x1 << " → " << e64x1;
        EXPECT_LE(e64x4 / e64x1, std::sqrt(quadruple)) << name << ": 1 → 4 bits, " << e64x1 << " → " << e64x4;
        EXPECT_LE(e64x8 / e64x4, std::sqrt(twice)) << name << ": 4 → 8 bits, " << e64x4 << " → " << e64x8;
        // And not faster than a smooth integrand would allow (M^−1 per
        // quadrupling, with the same noise margin): a ratio far below that
        // would mean the small-image error was something else than sampling.
        EXPECT_GE(e64x1 / e32x1, 0.25 * 0.8) << name;
    }
}

// === regular sampling on an edge aligned with the pixel rows ===============

// A line of receivers at x = 0 across the penumbra of the occluder's edge
// z = 0.2. The frustum's rows follow the light's first edge (along x), so
// the occluder's x-parallel edges project onto pixel rows to within a few
// tenths of a pixel over their length. Moving the receiver by dz moves that
// edge's image over the light by dz (the occluder is halfway up), about one
// row of a 64² image per 0.013; 240 points over z ∈ [0.25, 0.55] put ~10
// points in each of ~23 rows.
struct LineErrors {
    std::vector<double> regular, jittered;
};
LineErrors alignedEdgeLine() {
    constexpr int kPoints = 240;
    DirectLightSampler& regular = GlEnvironment::sampler(kRegular, kCv, 64, 1);
    DirectLightSampler& jittered = GlEnvironment::sampler(kJittered, kCv, 64, 1);
    LineErrors out;
    for (int i = 0; i < kPoints; ++i) {
        const Vec3 x(0.0, 0.0, 0.25 + 0.3 * (i + 0.5) / kPoints);
        const double exact = exactAt(x, kUp);
        out.regular.push_back(sampleValue(regular, x, kUp, 0) - exact);
        // A fresh seed per point, as the renderer derives it.
        out.jittered.push_back(sampleValue(jittered, x, kUp, jitter::seedFor(5, uint32_t(i))) - exact);
    }
    return out;
}

TEST(DirectSampler, RegularErrorHasStructureAlongAnAlignedEdgeAndJitteredHasNone) {
    // Regular sampling tests each pixel at its centre: as the edge slides
    // across a row, the covered area changes continuously but the estimate
    // jumps when the edge passes the row's centres. The error is a sawtooth
    // of the edge's phase, one period per row: ~2 sign changes per period,
    // and neighbours a tenth of a period apart correlate by
    // 1 − 6τ(1 − τ) ≈ 0.46 (τ = 0.1; more where the slight slant of the
    // edge smooths the jump). Jittered errors with fresh seeds are
    // independent: sign changes ~ Binomial(239, ½) = 120 ± 8, lag-one
    // correlation 0 ± 0.065.
    const LineErrors e = alignedEdgeLine();
    auto signChanges = [](const std::vector<double>& v) {
        int n = 0;
        for (size_t i = 1; i < v.size(); ++i) n += (v[i] > 0) != (v[i - 1] > 0);
        return n;
    };
    auto lagOneCorrelation = [](const std::vector<double>& v) {
        double num = 0, den = 0;
        for (size_t i = 0; i < v.size(); ++i) {
            den += v[i] * v[i];
            if (i) num += v[i] * v[i - 1];
        }
        return num / den;
    };
    const int third = int(e.regular.size()) / 3;  // 80: 5 deviations below 120
    EXPECT_LT(signChanges(e.regular), third);
    EXPECT_GT(signChanges(e.jittered), third);
    EXPECT_GT(lagOneCorrelation(e.regular), 0.3);
    EXPECT_LT(std::abs(lagOneCorrelation(e.jittered)), 0.3);  // 4.6 deviations
    // And the aligned edge makes regular sampling worse than one jittered
    // test per pixel, at the same cost. In units of one test's weight, with
    // the edge covering a fraction φ (uniform) of a row of L pixels, regular
    // errs by L·(round(φ) − φ), rms L/√12; jittered by a sum of L
    // independent Bernoulli(φ) deviations, rms √(L/6). For L ≈ 60 the ratio
    // √(L/2) is ≈ 5.5; the edge's slant and the other, non-aligned edges
    // lower it (3.5 measured): we require 2.
    double rmsRegular = 0, rmsJittered = 0;
    for (size_t i = 0; i < e.regular.size(); ++i) {
        rmsRegular += e.regular[i] * e.regular[i];
        rmsJittered += e.jittered[i] * e.jittered[i];
    }
    EXPECT_GT(rmsRegular, 2.0 * 2.0 * rmsJittered);  // rms ratio > 2
}

TEST(DirectSampler, RepeatingRegularPassesDoesNotReduceItsErrorButJitteredDoes) {
    // §4.1.2: "resampling it won't increase the obtained irradiance quality,
    // as the same result will be obtained again and again". At the line's
    // point where regular errs most, K passes with different seeds give the
    // same value bit for bit, so their mean errs exactly as much; K = 64
    // jittered passes converge: their mean is within 4 standard errors of the
    // exact value, ~1/8 of one pass's error, far below regular's worst.
    const LineErrors e = alignedEdgeLine();
    size_t worst = 0;
    for (size_t i = 0; i < e.regular.size(); ++i)
        if (std::abs(e.regular[i]) > std::abs(e.regular[worst])) worst = i;
    const Vec3 x(0.0, 0.0, 0.25 + 0.3 * (double(worst) + 0.5) / double(e.regular.size()));
    const double exact = exactAt(x, kUp);

    DirectLightSampler& regular = GlEnvironment::sampler(kRegular, kCv, 64, 1);
    const DirectSample first = regular.sample(0, x, kUp, 11);
    double sum = 0;
    for (uint32_t k = 0; k < 16; ++k) {
        const DirectSample d = regular.sample(0, x, kUp, jitter::seedFor(6, k));
        EXPECT_EQ(std::memcmp(&d.cosineSolidAngle, &first.cosineSolidAngle, sizeof(double)), 0);
        EXPECT_EQ(d.visibleSamples, first.visibleSamples);
        sum += d.cosineSolidAngle;
    }
    // The mean of identical values is that value (up to the rounding of the sum).
    EXPECT_DOUBLE_EQ(sum / 16, first.cosineSolidAngle);
    const double regularMeanError = std::abs(first.cosineSolidAngle - exact);
    EXPECT_GT(regularMeanError, 0.0);

    DirectLightSampler& jittered = GlEnvironment::sampler(kJittered, kCv, 64, 1);
    std::vector<double> passes;
    for (uint32_t k = 0; k < 64; ++k) passes.push_back(sampleValue(jittered, x, kUp, jitter::seedFor(7, k)));
    const MeanAndError m = meanOf(passes);
    EXPECT_LE(std::abs(m.mean - exact), 4 * m.standardError + liftAllowance(x, kUp));
    EXPECT_LT(std::abs(m.mean - exact), 0.25 * regularMeanError)
        << "regular errs by " << regularMeanError << ", jittered mean of 64 by " << std::abs(m.mean - exact);
}

// === occlusion query =======================================================

TEST(DirectSampler, OcclusionQueryScalesLambertByThePixelCountOfRegular) {
    // §4.1.1 as implemented: the light's fragments are counted twice, alone
    // and behind the occluders, each fragment tested at its pixel centre (a
    // 1-bit, unjittered program), and the visible fraction scales the exact
    // unoccluded value. Those are exactly regular sampling's tests, so the
    // counts must be equal integers, and the estimate is
    // Lambert × visible / light up to rounding (Lambert at the receiver, up
    // to the lift's effect on it).
    DirectLightSampler& query = GlEnvironment::sampler(kQuery, kPlain, 64, 1);
    DirectLightSampler& regular = GlEnvironment::sampler(kRegular, kPlain, 64, 1);
    for (const ReceiverPoint& r : makeBenchReceivers(20)) {
        const DirectSample q = query.sample(0, r.position, r.normal, 1);
        const DirectSample g = regular.sample(0, r.position, r.normal, 1);
        ASSERT_EQ(q.lightSamples, g.lightSamples) << "at (" << r.position.x << ", " << r.position.z << ")";
        ASSERT_EQ(q.visibleSamples, g.visibleSamples) << "at (" << r.position.x << ", " << r.position.z << ")";
        const double lambert = lambertAt(r.position, r.normal);
        const double lift = std::abs(lambertAt(eyePoint(r.position, r.normal), r.normal) - lambert);
        EXPECT_NEAR(q.unoccluded, lambert, 1e-9 * lambert + lift);
        EXPECT_NEAR(q.cosineSolidAngle, q.unoccluded * q.visibleSamples / q.lightSamples, 1e-12 * lambert);
        if (clearOfPenumbra(r.position, 0.02)) {
            EXPECT_EQ(q.visibleSamples, q.lightSamples);
        }
    }
}

TEST(DirectSampler, OcclusionQueryIsBiasedBecauseItWeighsEveryPixelAlike) {
    // The visible fraction by pixel count differs from the visible fraction
    // of the cosine-weighted solid angle wherever the hidden pixels weigh
    // more or less than average: across the bench light's image from the
    // floor the weight (eq. 3) varies by a factor up to ~2. That error is a
    // bias: it tends to a non-zero limit as the image grows, while regular
    // and jittered sampling converge (halving the error or better per
    // doubling of the image side). Mean |error| over the penumbra points of
    // the 20×20 grid, where the query can be wrong at all.
    std::vector<ReceiverPoint> penumbra;
    std::vector<double> exact;
    for (const ReceiverPoint& r : makeBenchReceivers(20))
        if (!clearOfPenumbra(r.position, 0.02)) {
            penumbra.push_back(r);
            exact.push_back(exactAt(r.position, r.normal));
        }
    auto meanError = [&](DirectMethod method, int size) {
        DirectLightSampler& s = GlEnvironment::sampler(method, kPlain, size, 1);
        double sum = 0;
        for (size_t i = 0; i < penumbra.size(); ++i)
            sum += std::abs(sampleValue(s, penumbra[i].position, penumbra[i].normal, jitter::seedFor(8, uint32_t(i))) -
                            exact[i]);
        return sum / double(penumbra.size());
    };
    const double query32 = meanError(kQuery, 32), query64 = meanError(kQuery, 64);
    const double regular32 = meanError(kRegular, 32), regular64 = meanError(kRegular, 64);
    const double jittered64 = meanError(kJittered, 64);
    EXPECT_GT(query64, 3 * regular64) << "query " << query64 << ", regular " << regular64;
    EXPECT_GT(query64, 3 * jittered64) << "query " << query64 << ", jittered " << jittered64;
    EXPECT_GT(query64, 0.8 * query32) << "the query's error should not shrink: " << query32 << " → " << query64;
    EXPECT_LT(regular64, 0.6 * regular32) << "regular's error should shrink: " << regular32 << " → " << regular64;
}

// === reproducibility =======================================================

TEST(DirectSampler, SameSeedRepeatsBitForBitAndDifferentSeedsDiffer) {
    const std::vector<ReceiverPoint> receivers = penumbraReceivers(4);
    for (auto estimator : {kPlain, kCv}) {
        DirectLightSampler& s = GlEnvironment::sampler(kJittered, estimator, 64, 4);
        for (const ReceiverPoint& r : receivers) {
            const DirectSample a = s.sample(0, r.position, r.normal, 1234);
            // Another point in between must not leave state behind.
            s.sample(0, Vec3(0.3, 0, 0.3), kUp, 99);
            const DirectSample b = s.sample(0, r.position, r.normal, 1234);
            EXPECT_EQ(std::memcmp(&a.cosineSolidAngle, &b.cosineSolidAngle, sizeof(double)), 0);
            EXPECT_EQ(a.lightSamples, b.lightSamples);
            EXPECT_EQ(a.visibleSamples, b.visibleSamples);
            // A second sampler with the same settings draws the same jitter.
            DirectSamplerSettings settings = s.settings();
            DirectLightSampler other(test::glContext(), benchScene(), settings);
            const DirectSample c = other.sample(0, r.position, r.normal, 1234);
            EXPECT_EQ(std::memcmp(&a.cosineSolidAngle, &c.cosineSolidAngle, sizeof(double)), 0);
            // In the penumbra, estimates are sums of hundreds of weights at
            // random points: two seeds agreeing exactly would mean the seed
            // is not used.
            std::set<double> values;
            for (uint32_t seed = 0; seed < 8; ++seed)
                values.insert(s.sample(0, r.position, r.normal, jitter::seedFor(9, seed)).cosineSolidAngle);
            EXPECT_EQ(values.size(), 8u) << directEstimatorName(estimator);
        }
    }
}

TEST(DirectSampler, SettingsAreValidated) {
    DirectSamplerSettings s;
    EXPECT_NO_THROW(s.validate());
    s.bits = 3;
    EXPECT_THROW(s.validate(), InputError);
    s = {};
    s.imageSize = 2;
    EXPECT_THROW(s.validate(), InputError);
    EXPECT_THROW(DirectLightSampler(test::glContext(), benchScene(), s), InputError);
    EXPECT_THROW(parseDirectMethod("stochastic"), InputError);
    EXPECT_THROW(parseDirectEstimator("mis"), InputError);
    for (auto m : {kQuery, kRegular, kJittered}) EXPECT_EQ(parseDirectMethod(directMethodName(m)), m);
    for (auto e : {kPlain, kCv}) EXPECT_EQ(parseDirectEstimator(directEstimatorName(e)), e);
}

// === cheap pairs: nothing between, no GL ==================================

// Counts the calls that reach the stubs below.
int stubbedGlCalls = 0;

template <class F>
struct CountingStub;
template <class R, class... A>
struct CountingStub<R (*)(A...)> {
    static R call(A...) {
        ++stubbedGlCalls;
        return R();
    }
};

// A context sharing the test context's GL, whose entry points can be
// swapped for stubs that only count calls: a sampler made while they are
// real can then be asked for a sample while they are stubs, and any GL call
// it makes shows.
class CountingGlContext : public GlContext {
public:
    explicit CountingGlContext(GlContext& real) : real_(real) { gl_ = real.gl(); }
    void makeCurrent() override { real_.makeCurrent(); }
    GlBackend backend() const override { return real_.backend(); }

    // Runs `f` with every GL call counted and dropped; returns the count.
    template <class F>
    int countCalls(F&& f) {
#define ML_GL_STUB(type, name) gl_.name = &CountingStub<type>::call;
        ML_GL_FUNCTIONS(ML_GL_STUB)
#undef ML_GL_STUB
        stubbedGlCalls = 0;
        struct Restore {
            CountingGlContext& c;
            ~Restore() { c.gl_ = c.real_.gl(); }
        } restore{*this};
        f();
        return stubbedGlCalls;
    }

private:
    GlContext& real_;
};

DirectSamplerSettings cvSettings(DirectMethod method, int bits) {
    DirectSamplerSettings s;
    s.method = method;
    s.bits = bits;
    return s;
}

void expectSameSample(const DirectSample& a, const DirectSample& b, const std::string& where) {
    EXPECT_EQ(std::memcmp(&a.cosineSolidAngle, &b.cosineSolidAngle, sizeof(double)), 0) << where;
    EXPECT_EQ(a.irradiance, b.irradiance) << where;
    EXPECT_EQ(a.unoccluded, b.unoccluded) << where;
    EXPECT_EQ(a.lightSamples, b.lightSamples) << where;
    EXPECT_EQ(a.visibleSamples, b.visibleSamples) << where;
    EXPECT_EQ(a.frusta, b.frusta) << where;
}

std::string at(const Vec3& x) { return concat("at (", x.x, ", ", x.y, ", ", x.z, ")"); }

TEST(DirectSampler, PairsWithNothingBetweenAreAnsweredOnTheCpuAsTheGpuWould) {
    // The control variate subtracts the occluded samples from Lambert's
    // closed form; where culling leaves no occluder in any frustum, nothing
    // is subtracted and the sampler answers on the CPU with no GL call. The
    // GPU, made to rasterise the same pair (cpuUnoccludedPairs off: the
    // culled leaves drawn; cullOccluders off: every triangle drawn), must
    // find no occluded sample and return the same value. Points in the
    // occluder's shadow must be rasterised. Regular sampling with the
    // control variate weighs the light the same way (at pixel centres), so
    // it takes the CPU path as well.
    const Scene& bench = benchScene();
    std::vector<ReceiverPoint> receivers = makeBenchReceivers(20);
    receivers.push_back({Vec3(0.1, 1.0 - 1e-3, 0.05), kUp});  // under the light: split among cube faces
    for (auto [method, bits] : {std::pair{kJittered, 8}, std::pair{kJittered, 4}, std::pair{kRegular, 1}}) {
        const DirectSamplerSettings settings = cvSettings(method, bits);
        DirectSamplerSettings culledLeaves = settings, everything = settings;
        culledLeaves.cpuUnoccludedPairs = false;
        everything.cullOccluders = false;
        CountingGlContext counting(test::glContext());
        DirectLightSampler cheap(counting, bench, settings);
        DirectLightSampler gpu(test::glContext(), bench, culledLeaves), all(test::glContext(), bench, everything);
        int onCpu = 0, shadowed = 0, split = 0;
        for (size_t i = 0; i < receivers.size(); ++i) {
            const ReceiverPoint& r = receivers[i];
            const std::string where = concat(directMethodName(method), " × ", bits, " ", at(r.position));
            const uint32_t seed = jitter::seedFor(12, uint32_t(i));
            DirectSample a;
            const int glCalls = counting.countCalls([&] { a = cheap.sample(0, r.position, r.normal, seed); });
            const DirectPhaseTimes times = cheap.lastTimes();
            const DirectSample b = gpu.sample(0, r.position, r.normal, seed);
            const DirectSample c = all.sample(0, r.position, r.normal, seed);
            EXPECT_EQ(b.path, DirectPath::Rasterised) << where;
            EXPECT_EQ(c.path, DirectPath::Rasterised) << where;
            // In the shadow: 14 points of the grid lie on its outline (x =
            // −0.9 or z = 0.9), where the shadow has no area and the exact
            // values differ by rounding (2e-16) only.
            if (exactAt(r.position, r.normal) < (1 - 1e-9) * lambertAt(r.position, r.normal)) {
                ++shadowed;
                EXPECT_EQ(a.path, DirectPath::Rasterised) << where << " is in the occluder's shadow";
            }
            if (a.path == DirectPath::Unoccluded) {
                ++onCpu;
                split += a.frusta > 1;
                EXPECT_EQ(glCalls, 0) << where;
                EXPECT_EQ(a.trianglesDrawn, 0u) << where;
                EXPECT_GT(times.setup, 0.0) << where;
                EXPECT_EQ(times.draw + times.readback + times.weighting, 0.0) << where;
                // No sample tested (DirectSample::lightSamples).
                EXPECT_EQ(a.lightSamples, 0u) << where;
                EXPECT_EQ(a.visibleSamples, 0u) << where;
                EXPECT_FALSE(a.partiallyVisible()) << where;
                for (const DirectSample& g : {b, c}) {
                    EXPECT_GT(g.lightSamples, 0u) << where;
                    EXPECT_EQ(g.visibleSamples, g.lightSamples) << where << ": GL found an occluded sample";
                    EXPECT_NEAR(a.irradiance.g, g.irradiance.g, 1e-12 * g.irradiance.g) << where;  // Ke = 1
                    EXPECT_NEAR(a.cosineSolidAngle, g.cosineSolidAngle, 1e-12 * g.cosineSolidAngle) << where;
                    EXPECT_EQ(a.unoccluded, g.unoccluded) << where;
                    EXPECT_EQ(a.frusta, g.frusta) << where;
                }
            } else {
                ASSERT_EQ(a.path, DirectPath::Rasterised) << where;
                EXPECT_GT(glCalls, 0) << where;
                // With real GL, the pair is the one rasterised before.
                expectSameSample(cheap.sample(0, r.position, r.normal, seed), b, where);
            }
        }
        // 241 points: the penumbra (x ∈ [−0.9, 1.1], z ∈ [−1.1, 0.9]) holds
        // about 2/3 of the 20×20 grid; of the rest, those whose frustum's
        // window still reaches the occluder are rasterised.
        std::printf("[ cheap    ] bench, %s × %d: %d of %zu pairs on the CPU, %d in the shadow\n",
                    directMethodName(method), bits, onCpu, receivers.size(), shadowed);
        EXPECT_GT(shadowed, 100);
        EXPECT_GT(onCpu, 60);
        EXPECT_EQ(split, 1);
    }
}

TEST(DirectSampler, ALightBelowTheHorizonOrSeenFromBehindGivesZeroWithNoGlCall) {
    const Scene& bench = benchScene();
    const std::vector<ReceiverPoint> receivers = {
        {Vec3(0.2, 0.0, 0.1), -kUp},                                  // on the floor, facing down
        {Vec3(0.0, 2.0, 0.0), kUp},                                   // above the light, facing up
        {Vec3(0.1, 2.0, 0.0), -kUp},                                  // above, facing the light's back
        {Vec3(3.0, 0.5, 0.0), Vec3(1, 0, 0)},                         // beside it, facing away
        {Vec3(0.0, 0.5, 0.0), glm::normalize(Vec3(0.0, -1.0, 1e-3))}  // under it, facing down
    };
    for (auto method : {kQuery, kRegular, kJittered})
        for (auto estimator : {kPlain, kCv}) {
            DirectSamplerSettings settings;
            settings.method = method;
            settings.estimator = estimator;
            settings.bits = method == kJittered ? 8 : 1;
            CountingGlContext counting(test::glContext());
            DirectLightSampler sampler(counting, bench, settings);
            for (const ReceiverPoint& r : receivers) {
                const std::string where =
                    concat(directMethodName(method), " ", directEstimatorName(estimator), " ", at(r.position));
                DirectSample d;
                EXPECT_EQ(counting.countCalls([&] { d = sampler.sample(0, r.position, r.normal, 5); }), 0) << where;
                EXPECT_EQ(d.path, DirectPath::Unlit) << where;
                EXPECT_EQ(d.irradiance, Rgb(0.0)) << where;
                EXPECT_EQ(d.cosineSolidAngle, 0.0) << where;
                EXPECT_EQ(d.unoccluded, 0.0) << where;
                EXPECT_EQ(d.lightSamples, 0u) << where;
                EXPECT_EQ(d.frusta, 0u) << where;
                EXPECT_EQ(d.trianglesDrawn, 0u) << where;
                const DirectPhaseTimes& t = sampler.lastTimes();
                EXPECT_EQ(t.draw + t.readback + t.weighting, 0.0) << where;
                EXPECT_EQ(benchExact().unoccludedCosineSolidAngle(0, r.position, r.normal), 0.0) << where;
            }
        }
    EXPECT_STREQ(directPathName(DirectPath::Unlit), "unlit");
    EXPECT_STREQ(directPathName(DirectPath::Unoccluded), "unoccluded");
    EXPECT_STREQ(directPathName(DirectPath::Rasterised), "rasterised");
}

// The two triangles corner, corner + u, corner + u + v and corner, corner +
// u + v, corner + v, facing u × v.
Mesh quad(const std::string& name, uint32_t material, const Vec3& corner, const Vec3& u, const Vec3& v) {
    Mesh m;
    m.name = name;
    m.positions = {corner, corner + u, corner + u + v, corner + v};
    m.normals.assign(4, glm::normalize(glm::cross(u, v)));
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    m.materials = {material, material};
    m.sourceLines = {0, 0};
    return m;
}

// The bench's light (1 × 1 at y = 1) over a small square at y = 0.95, x ∈
// [0.2, 0.3]: 0.1 below the light a receiver sees it split among five cube
// faces, and the square (elevation 9° to 14° towards +x, in front of the
// light's part beyond x = 0.4) lies in the +x face only.
Scene splitLightScene() {
    Scene scene;
    scene.name = "split";
    Material light, grey;
    light.name = "light";
    light.kd = Rgb(0.0);
    light.ke = Rgb(1.0);
    grey.name = "grey";
    scene.materials = {light, grey};
    scene.meshes = {quad("light", 0, Vec3(-0.5, 1.0, -0.5), Vec3(1, 0, 0), Vec3(0, 0, 1)),
                    quad("occluder", 1, Vec3(0.2, 0.95, -0.05), Vec3(0, 0, 0.1), Vec3(0.1, 0, 0))};
    scene.finalize();
    return scene;
}

TEST(DirectSampler, ASplitLightRasterisesOnlyTheFacesWithAnOccluder) {
    // The +x face is rasterised, the four others weighed on the CPU: the
    // same estimate as rasterising all five, bit for bit.
    const Scene scene = splitLightScene();
    DirectSamplerSettings forced;
    forced.cpuUnoccludedPairs = false;
    DirectLightSampler cheap(test::glContext(), scene, DirectSamplerSettings{});
    DirectLightSampler gpu(test::glContext(), scene, forced);
    const Vec3 x(0.0, 0.9, 0.0);
    for (uint32_t k = 0; k < 8; ++k) {
        const uint32_t seed = jitter::seedFor(13, k);
        const DirectSample a = cheap.sample(0, x, kUp, seed), b = gpu.sample(0, x, kUp, seed);
        ASSERT_EQ(a.frusta, 5u);
        EXPECT_EQ(a.path, DirectPath::Rasterised);
        expectSameSample(a, b, concat("seed ", seed));
        EXPECT_LT(a.visibleSamples, a.lightSamples);  // the square hides part of the light
        // One leaf of four triangles per rasterised face.
        EXPECT_EQ(a.trianglesDrawn, 4u);
        EXPECT_EQ(b.trianglesDrawn, 4u * 5u);
    }
}

// Cache-like points: a barycentric lattice of 15 points on each of the
// box's non-emitting triangles, with the face's normal.
std::vector<ReceiverPoint> cornellPoints(const Scene& box) {
    std::vector<ReceiverPoint> points;
    for (const Mesh& m : box.meshes)
        for (size_t t = 0; t < m.triangles.size(); ++t) {
            if (box.materials[m.materials[t]].emissive()) continue;
            const Triangle3 p = m.triangle(t);
            const Vec3 n = m.normals[m.triangles[t].x];
            constexpr int k = 6;
            for (int i = 0; i < k; ++i)
                for (int j = 0; i + j < k - 1; ++j) {
                    const double a = (i + 0.5) / k, b = (j + 0.5) / k;
                    points.push_back({p[0] + a * (p[1] - p[0]) + b * (p[2] - p[0]), n});
                }
        }
    return points;
}

TEST(DirectSampler, MostCornellBoxPairsAreCheapAndTheirTotalIsUnchanged) {
    // Cache-like points: a barycentric lattice of 15 points on each of the
    // box's 30 non-emitting triangles (walls, floor, ceiling, blocks), with
    // the face's normal. Every pair is sampled twice with the same seed,
    // with and without the CPU path: the same jitter, so a CPU pair must
    // give the rasterised value exactly and a rasterised pair is the same
    // computation. The totals must then agree to rounding (1e-12 relative),
    // far tighter than the sampler's noise (~1e-3 of a pass in the
    // penumbra), which would hide a pair wrongly taken as unoccluded.
    const Scene box = makeCornellBox();
    const std::vector<ReceiverPoint> points = cornellPoints(box);
    ASSERT_EQ(points.size(), 30u * 15u);
    DirectSamplerSettings forced;
    forced.cpuUnoccludedPairs = false;
    DirectLightSampler cheap(test::glContext(), box, DirectSamplerSettings{});
    DirectLightSampler gpu(test::glContext(), box, forced);
    using Clock = std::chrono::steady_clock;
    auto micros = [](Clock::time_point a, Clock::time_point b) {
        return std::chrono::duration<double, std::micro>(b - a).count();
    };
    // By DirectPath: unlit, unoccluded, rasterised, occluded, cpu-rasterised.
    constexpr int kPaths = int(DirectPath::CpuRasterised) + 1;
    int count[kPaths] = {};
    double cheapTime[kPaths] = {}, gpuTime[kPaths] = {};
    Rgb cheapTotal(0.0), gpuTotal(0.0);
    constexpr uint32_t kPasses = 3;  // more points for the timing
    for (uint32_t pass = 0; pass < kPasses; ++pass)
        for (size_t i = 0; i < points.size(); ++i) {
            const ReceiverPoint& r = points[i];
            const uint32_t seed = jitter::seedFor(14, uint32_t(i), 0, pass);
            const Clock::time_point t0 = Clock::now();
            const DirectSample a = cheap.sample(0, r.position, r.normal, seed);
            const Clock::time_point t1 = Clock::now();
            const DirectSample b = gpu.sample(0, r.position, r.normal, seed);
            const Clock::time_point t2 = Clock::now();
            const int path = int(a.path);
            ASSERT_LT(path, kPaths);
            ++count[path];
            cheapTime[path] += micros(t0, t1);
            gpuTime[path] += micros(t1, t2);
            cheapTotal += a.irradiance;
            gpuTotal += b.irradiance;
            if (a.path == DirectPath::Unoccluded) {
                EXPECT_EQ(b.visibleSamples, b.lightSamples) << at(r.position) << ": GL found an occluded sample";
                EXPECT_NEAR(a.irradiance.r, b.irradiance.r, 1e-12 * b.irradiance.r) << at(r.position);
            }
        }
    const int pairs = int(kPasses * points.size());
    const int unlit = count[int(DirectPath::Unlit)], cpu = count[int(DirectPath::Unoccluded)];
    const int raster = count[int(DirectPath::Rasterised)], umbra = count[int(DirectPath::Occluded)];
    const int few = count[int(DirectPath::CpuRasterised)];
    auto each = [&](double (&time)[kPaths], DirectPath path) {
        const int n = count[int(path)];
        return n ? time[int(path)] / n : 0.0;
    };
    std::printf("[ cheap    ] Cornell box, %d pairs: %d unlit, %d unoccluded on the CPU (%.0f%% of the lit), %d in "
                "umbra, %d with few occluders on the CPU, %d rasterised\n"
                "[ cheap    ] us each: unoccluded pair %.1f (rasterised when forced: %.1f), few occluders %.1f, "
                "rasterised pair %.1f, unlit %.1f\n",
                pairs, unlit, cpu, 100.0 * cpu / std::max(pairs - unlit, 1), umbra, few, raster,
                each(cheapTime, DirectPath::Unoccluded), each(gpuTime, DirectPath::Unoccluded),
                each(cheapTime, DirectPath::CpuRasterised), each(cheapTime, DirectPath::Rasterised),
                each(cheapTime, DirectPath::Unlit));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(cheapTotal[c], gpuTotal[c], 1e-12 * gpuTotal[c]) << "channel " << c;
    EXPECT_GT(gpuTotal.r, 0.0);
    // The ceiling (30 points) sees the light's back, the two sides of each
    // block that face away from it (2 × 60 points) nothing of it; the rest
    // sees it past the blocks from most places.
    EXPECT_EQ(unlit, int(kPasses) * 150);
    EXPECT_GT(cpu, 2 * raster);
}

TEST(DirectSampler, PairsInUmbraAreZeroWithoutGlAsTheGpuFindsThem) {
    // The office with desks, partition and cabinets: cache-like points on
    // every non-emitting triangle, each light. Every pair the CPU declares
    // wholly hidden (DirectPath::Occluded) must be one where the GPU, forced
    // to rasterise, sees not one sample of the light: the same answer,
    // zero. And most rasterised pairs of such a room are of that kind.
    const Scene office = makeOfficeScene(OfficeSettings{});
    std::vector<ReceiverPoint> points = cornellPoints(office);
    DirectSamplerSettings forced;
    forced.cpuUnoccludedPairs = false;
    DirectLightSampler cheap(test::glContext(), office, DirectSamplerSettings{});
    DirectLightSampler gpu(test::glContext(), office, forced);
    int occluded = 0, rasterised = 0;
    for (size_t i = 0; i < points.size(); i += 3)  // a third of them: ~1,900 pairs
        for (size_t l = 0; l < office.lights.size(); l += 2) {
            const ReceiverPoint& r = points[i];
            const uint32_t seed = jitter::seedFor(31, uint32_t(i), uint32_t(l));
            const DirectSample a = cheap.sample(l, r.position, r.normal, seed);
            if (a.path == DirectPath::Rasterised) ++rasterised;
            if (a.path != DirectPath::Occluded) continue;
            ++occluded;
            const DirectSample b = gpu.sample(l, r.position, r.normal, seed);
            const std::string where = concat("light ", l, " at ", at(r.position));
            EXPECT_GT(b.lightSamples, 0u) << where;
            EXPECT_EQ(b.visibleSamples, 0u) << where << ": the GPU saw part of the light";
            EXPECT_EQ(a.irradiance, Rgb(0.0)) << where;
            EXPECT_EQ(a.cosineSolidAngle, 0.0) << where;
            EXPECT_GT(a.unoccluded, 0.0) << where;
            EXPECT_EQ(a.lightSamples, 0u) << where;
        }
    std::printf("[ umbra    ] office: %d pairs in umbra answered on the CPU, %d rasterised\n", occluded, rasterised);
    EXPECT_GT(occluded, rasterised) << "most pairs with an occluder in the office are in umbra";
}

TEST(DirectSampler, PairsWithFewOccludersAreDecidedOnTheCpuAsTheGpuDecidesThem) {
    // The office's pairs that still have an occluder in view after the
    // umbra test: with cpuCoverageTriangles their occluded samples are
    // decided on the CPU (CpuCoverage.h), at the jittered points the GPU
    // tests, and weighed by the same code. The CPU decides in double where
    // the GPU decides in float, so a sample within float rounding of an
    // occluder's edge (~1e-7 of the window; a 64x64 image's pixel is
    // 1.6e-2 of it) may fall the other way: of the ~1e5 occluded samples a
    // few hundred pairs hold, a handful at most. Everything else is the
    // GPU's to the bit: samples on the light, Lambert's value, the frusta.
    const Scene office = makeOfficeScene(OfficeSettings{});
    const std::vector<ReceiverPoint> points = cornellPoints(office);
    DirectSamplerSettings onCpu;
    onCpu.cpuCoverageTriangles = 64;
    CountingGlContext counting(test::glContext());
    DirectLightSampler cpu(counting, office, onCpu);
    DirectLightSampler gpu(test::glContext(), office, DirectSamplerSettings{});
    int covered = 0, same = 0, rasterised = 0;
    uint64_t occludedSamples = 0, flipped = 0;
    double cpuSeconds = 0, gpuSeconds = 0;
    using Clock = std::chrono::steady_clock;
    for (size_t i = 0; i < points.size(); i += 3)
        for (size_t l = 0; l < office.lights.size(); l += 2) {
            const ReceiverPoint& r = points[i];
            const uint32_t seed = jitter::seedFor(47, uint32_t(i), uint32_t(l));
            const std::string where = concat("light ", l, " ", at(r.position));
            DirectSample a;
            const Clock::time_point t0 = Clock::now();
            const int glCalls = counting.countCalls([&] { a = cpu.sample(l, r.position, r.normal, seed); });
            const Clock::time_point t1 = Clock::now();
            if (a.path == DirectPath::Rasterised) ++rasterised;
            if (a.path != DirectPath::CpuRasterised) continue;
            ++covered;
            EXPECT_EQ(glCalls, 0) << where;
            const DirectSample b = gpu.sample(l, r.position, r.normal, seed);
            cpuSeconds += std::chrono::duration<double>(t1 - t0).count();
            gpuSeconds += std::chrono::duration<double>(Clock::now() - t1).count();
            ASSERT_EQ(b.path, DirectPath::Rasterised) << where;
            EXPECT_EQ(a.lightSamples, b.lightSamples) << where;
            EXPECT_EQ(a.unoccluded, b.unoccluded) << where;
            EXPECT_EQ(a.frusta, b.frusta) << where;
            occludedSamples += b.lightSamples - b.visibleSamples;
            flipped += uint64_t(std::abs(int64_t(a.visibleSamples) - int64_t(b.visibleSamples)));
            if (a.cosineSolidAngle == b.cosineSolidAngle && a.irradiance == b.irradiance) {
                ++same;
                continue;
            }
            // A flipped sample moves the estimate by its weight, at most
            // the light's whole cosine-weighted solid angle over its
            // samples times a few (the weights vary across the window by
            // far less than that where a frustum is fitted to the light).
            EXPECT_NEAR(a.cosineSolidAngle, b.cosineSolidAngle,
                        4.0 * b.unoccluded / std::max(1u, b.lightSamples) * std::max(1.0, double(flipped)))
                << where;
        }
    std::printf("[ coverage ] office: %d pairs decided on the CPU (%.1f us each, GPU %.1f us), %d rasterised; "
                "%d of them equal to the bit, %llu of %llu occluded samples flipped\n",
                covered, 1e6 * cpuSeconds / std::max(covered, 1), 1e6 * gpuSeconds / std::max(covered, 1),
                rasterised, same, (unsigned long long)flipped, (unsigned long long)occludedSamples);
    EXPECT_GT(covered, 100) << "the office's desks and cabinets leave pairs with an occluder in view";
    EXPECT_GE(same, covered - covered / 100) << "all but a few pairs equal to the bit";
    EXPECT_LE(flipped, occludedSamples / 10000 + 2);
}

TEST(OccluderPolygons, TwoTrianglesOfAFaceHideWhatNeitherHidesAlone) {
    // A unit square occluder at y = 1 made of two triangles, a small light
    // at y = 2 whose projection from the eye straddles the diagonal.
    const Vec3 a(-1, 1, -1), b(1, 1, -1), c(1, 1, 1), d(-1, 1, 1);
    const std::vector<Triangle3> tris = {{a, c, b}, {a, d, c}};
    const std::vector<uint32_t> ids = {0, 0};
    const OccluderPolygons polygons(tris, ids);
    EXPECT_EQ(polygons.quadCount(), 2u);
    const std::vector<OccluderBvh::Range> all = {{0, 2}};
    OccluderPolygons::Rules rules;
    rules.eye = Vec3(0, 0, 0);
    rules.nearDistance = 1e-6;
    rules.lightNormal = Vec3(0, -1, 0);
    rules.lightPoint = Vec3(0, 2, 0);
    rules.planeTolerance = 1e-6;
    const Polygon3 small = {Vec3(-0.2, 2, -0.2), Vec3(0.2, 2, -0.2), Vec3(0.2, 2, 0.2), Vec3(-0.2, 2, 0.2)};
    EXPECT_TRUE(polygons.hideAll({small}, all, rules));
    // Either triangle without the other does not: the light straddles their
    // diagonal. (With both in the scene, either one's range brings the quad.)
    EXPECT_TRUE(polygons.hideAll({small}, {{1, 1}}, rules));
    for (const Triangle3& t : tris) EXPECT_FALSE(OccluderPolygons({t}, {0}).hideAll({small}, {{0, 1}}, rules));
    // A light wider than the square's shadow is not hidden: its projection
    // reaches past the square (half the light's size at half the distance).
    const Polygon3 wide = {Vec3(-2.2, 2, -1), Vec3(2.2, 2, -1), Vec3(2.2, 2, 1), Vec3(-2.2, 2, 1)};
    EXPECT_FALSE(polygons.hideAll({wide}, all, rules));
    // Seen from beside the square, nothing is hidden.
    rules.eye = Vec3(3, 0, 0);
    EXPECT_FALSE(polygons.hideAll({small}, all, rules));
    // An occluder in the light's own plane (within the tolerance) does not occlude it.
    rules.eye = Vec3(0, 0, 0);
    rules.lightPoint = Vec3(0, 1 + 1e-7, 0);
    const Polygon3 onPlane = {Vec3(-0.2, 1 + 1e-7, -0.2), Vec3(0.2, 1 + 1e-7, -0.2), Vec3(0.2, 1 + 1e-7, 0.2),
                              Vec3(-0.2, 1 + 1e-7, 0.2)};
    EXPECT_FALSE(polygons.hideAll({onPlane}, all, rules));
    // Nor does one nearer the eye than the sampler draws.
    rules.lightPoint = Vec3(0, 2, 0);
    rules.nearDistance = 0.1;
    EXPECT_FALSE(polygons.hideAll({small}, all, rules));
    // Triangles that do not make a convex quad stay triangles.
    const std::vector<Triangle3> bent = {{a, c, b}, {a, Vec3(-1, 1.5, 1), c}};
    EXPECT_EQ(OccluderPolygons(bent, ids).quadCount(), 0u);
}

// === batches ================================================================

TEST(DirectSampler, ABatchGivesWhatSampleGivesBitForBit) {
    // A batch draws many sampling images (into several targets) before
    // reading any back; each result must be sample()'s for the same request,
    // bit for bit: unlit, CPU and rasterised pairs mixed, split lights,
    // batches longer than the targets, every estimator and method. The
    // batch runs first, then sample() on the same sampler: whatever state
    // the batch leaves must not reach sample(), nor one image another.
    const Scene box = makeCornellBox(), split = splitLightScene();
    const Scene& bench = benchScene();
    struct Case {
        const char* name;
        const Scene& scene;
        std::vector<SampleRequest> requests;
    };
    auto requestsAt = [](const std::vector<ReceiverPoint>& points, uint32_t user) {
        std::vector<SampleRequest> rs;
        for (size_t i = 0; i < points.size(); ++i)
            rs.push_back({0, points[i].position, points[i].normal, jitter::seedFor(user, uint32_t(i))});
        return rs;
    };
    std::vector<ReceiverPoint> benchPoints = makeBenchReceivers(12);
    benchPoints.push_back({Vec3(0.1, 1.0 - 1e-3, 0.05), kUp});  // under the light: cube faces
    benchPoints.push_back({Vec3(0.2, 0.0, 0.1), -kUp});          // facing away: unlit
    std::vector<ReceiverPoint> splitPoints;
    for (int k = 0; k < 48; ++k)  // 0.1 under the light: five faces, one with the square in it
        splitPoints.push_back({Vec3(-0.3 + 0.0125 * k, 0.9, 0.005 * k - 0.1), kUp});
    std::vector<Case> cases;
    cases.push_back({"Cornell box", box, requestsAt(cornellPoints(box), 21)});
    cases.push_back({"bench", bench, requestsAt(benchPoints, 22)});
    cases.push_back({"split light", split, requestsAt(splitPoints, 23)});

    struct Variant {
        DirectMethod method;
        DirectEstimator estimator;
        int bits;
        bool cpuPairs;
        int coverage = 0;  // cpuCoverageTriangles: pairs with occluders on the CPU, mixed with the others
    };
    const Variant variants[] = {{kJittered, kCv, 8, true},  {kJittered, kCv, 8, false}, {kJittered, kPlain, 8, true},
                                {kJittered, kCv, 32, true}, {kRegular, kCv, 1, true},   {kQuery, kCv, 1, true},
                                {kJittered, kCv, 8, true, 64}};
    for (const Case& c : cases)
        for (const Variant& v : variants) {
            DirectSamplerSettings settings;
            settings.method = v.method;
            settings.estimator = v.estimator;
            settings.bits = v.bits;
            settings.cpuUnoccludedPairs = v.cpuPairs;
            settings.cpuCoverageTriangles = v.coverage;
            DirectLightSampler sampler(test::glContext(), c.scene, settings);
            std::vector<DirectSample> batch;
            sampler.sampleBatch(c.requests, batch);
            ASSERT_EQ(batch.size(), c.requests.size());
            int paths[5] = {0, 0, 0, 0, 0}, split5 = 0;
            for (size_t i = 0; i < c.requests.size(); ++i) {
                const SampleRequest& r = c.requests[i];
                const std::string where = concat(c.name, ", ", directMethodName(v.method), " ",
                                                 directEstimatorName(v.estimator), " × ", v.bits,
                                                 v.cpuPairs ? "" : " (no CPU pairs)", v.coverage ? " (CPU coverage)" : "",
                                                 ", request ", i, " ", at(r.x));
                const DirectSample one = sampler.sample(r.mesh, r.x, r.n, r.seed);
                expectSameSample(batch[i], one, where);
                // Without GL: exactly the unlit, unoccluded and umbra pairs,
                // as sample() answers them (CPU coverage is left to sample()).
                DirectSample noGl;
                const bool cheap = one.path != DirectPath::Rasterised && one.path != DirectPath::CpuRasterised;
                ASSERT_EQ(cheap, sampler.sampleWithoutGl(r.mesh, r.x, r.n, r.seed, noGl)) << where;
                if (cheap) expectSameSample(noGl, one, where);
                EXPECT_EQ(batch[i].path, one.path) << where;
                EXPECT_EQ(batch[i].trianglesDrawn, one.trianglesDrawn) << where;
                ++paths[int(one.path)];
                split5 += one.frusta > 1 && (one.path == DirectPath::Rasterised || one.path == DirectPath::CpuRasterised);
            }
            // Each case holds every kind of pair it is meant to.
            const std::string what = concat(c.name, ", ", directMethodName(v.method), " ", directEstimatorName(v.estimator));
            EXPECT_GT(paths[int(v.coverage ? DirectPath::CpuRasterised : DirectPath::Rasterised)], 16)
                << what << ": too few images to fill the targets";
            if (&c.scene != &split) EXPECT_GT(paths[int(DirectPath::Unlit)], 0) << what;
            else EXPECT_GT(split5, 0) << what;
        }
}

TEST(DirectSampler, ABatchPassesBadInputThroughAsItIs) {
    const Scene& bench = benchScene();
    DirectLightSampler sampler(test::glContext(), bench, DirectSamplerSettings{});
    std::vector<SampleRequest> requests(3, SampleRequest{0, Vec3(0.1, 0.0, 0.1), kUp, 1});
    requests[1].x = Vec3(std::nan(""), 0.0, 0.0);
    std::vector<DirectSample> results;
    EXPECT_THROW(sampler.sampleBatch(requests, results), InputError);
}

// === OccluderBvh ===========================================================

// Does the triangle meet the convex volume ∩ {n·p + d ≥ 0}? Clipping keeps
// a non-empty polygon exactly when a part of positive area is inside;
// triangles touching the volume only along an edge or at a point may go
// either way, and none of the random cases below do.
bool meetsVolume(const Triangle3& t, const std::vector<OccluderBvh::Plane>& planes) {
    Polygon3 p{t[0], t[1], t[2]};
    for (const OccluderBvh::Plane& plane : planes) {
        p = clipPolygon(p, plane.n, plane.d);
        if (p.empty()) return false;
    }
    return true;
}

// Checks the shape of a cull's answer and returns, per original triangle,
// whether it was kept.
std::vector<bool> keptByCull(const OccluderBvh& bvh, const std::vector<OccluderBvh::Plane>& planes) {
    std::vector<OccluderBvh::Range> ranges;
    const uint32_t total = bvh.cull(planes, ranges);
    std::vector<bool> kept(bvh.triangleCount(), false);
    uint32_t sum = 0, end = 0;
    for (size_t k = 0; k < ranges.size(); ++k) {
        EXPECT_GT(ranges[k].count, 0u);
        // Sorted, disjoint and merged: a gap separates consecutive ranges.
        if (k) {
            EXPECT_GT(ranges[k].first, end);
        }
        end = ranges[k].first + ranges[k].count;
        EXPECT_LE(end, bvh.triangleCount());
        sum += ranges[k].count;
        for (uint32_t i = ranges[k].first; i < end && i < bvh.triangleCount(); ++i) kept[bvh.order()[i]] = true;
    }
    EXPECT_EQ(sum, total);
    return kept;
}

std::vector<OccluderBvh::Plane> boxPlanes(const Vec3& lo, const Vec3& hi) {
    return {{{1, 0, 0}, -lo.x}, {{-1, 0, 0}, hi.x}, {{0, 1, 0}, -lo.y},
            {{0, -1, 0}, hi.y}, {{0, 0, 1}, -lo.z}, {{0, 0, -1}, hi.z}};
}

TEST(OccluderBvh, CullingNeverDropsATriangleThatMeetsTheVolume) {
    std::mt19937_64 rng(20240917);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    auto point = [&] { return Vec3(unit(rng), unit(rng), unit(rng)); };
    std::vector<Triangle3> triangles;
    for (int i = 0; i < 600; ++i) {
        // Sizes from 1e-3 to 1 of the domain: slivers, small and large.
        const double size = std::pow(10.0, -3.0 * (0.5 + 0.5 * unit(rng)));
        const Vec3 c = point();
        triangles.push_back({c + size * point(), c + size * point(), c + size * point()});
    }
    for (int leafSize : {1, 4, 16}) {
        const OccluderBvh bvh(triangles, leafSize);
        ASSERT_EQ(bvh.triangleCount(), triangles.size());
        std::vector<uint32_t> sorted = bvh.order();
        std::sort(sorted.begin(), sorted.end());
        for (uint32_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i) << "order is not a permutation";

        size_t droppedTotal = 0;
        for (int trial = 0; trial < 60; ++trial) {
            std::vector<OccluderBvh::Plane> planes;
            if (trial % 2 == 0) {
                const Vec3 a = point(), b = point();
                planes = boxPlanes(glm::min(a, b), glm::max(a, b));
            } else {
                // A frustum-like volume: five random half-spaces through
                // points near a random centre, facing it.
                const Vec3 centre = 0.5 * point();
                for (int k = 0; k < 5; ++k) {
                    const Vec3 n = glm::normalize(point() + Vec3(1e-9));
                    const Vec3 on = centre - 0.4 * std::abs(unit(rng)) * n;
                    planes.push_back({n, -glm::dot(n, on)});
                }
            }
            const std::vector<bool> kept = keptByCull(bvh, planes);
            for (size_t i = 0; i < triangles.size(); ++i) {
                if (meetsVolume(triangles[i], planes)) {
                    EXPECT_TRUE(kept[i]) << "leaf size " << leafSize << ", trial " << trial << ": triangle " << i
                                         << " meets the volume but was culled";
                }
                droppedTotal += !kept[i];
            }
        }
        EXPECT_GT(droppedTotal, 0u) << "culling never dropped anything";
    }
}

TEST(OccluderBvh, DropsFarClustersAndHandlesTrivialVolumes) {
    // Two clusters of 64 triangles, 100 units apart along x: the median
    // split on the longest axis separates them at the root, so a box around
    // the first keeps exactly its 64 triangles.
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::vector<Triangle3> triangles;
    for (int cluster = 0; cluster < 2; ++cluster)
        for (int i = 0; i < 64; ++i) {
            const Vec3 c(100.0 * cluster + unit(rng), unit(rng), unit(rng));
            triangles.push_back({c, c + 0.1 * Vec3(unit(rng), unit(rng), unit(rng)),
                                 c + 0.1 * Vec3(unit(rng), unit(rng), unit(rng))});
        }
    const OccluderBvh bvh(triangles, 8);
    std::vector<OccluderBvh::Range> ranges;
    EXPECT_EQ(bvh.cull(boxPlanes(Vec3(-2.0), Vec3(2.0)), ranges), 64u);
    const std::vector<bool> kept = keptByCull(bvh, boxPlanes(Vec3(-2.0), Vec3(2.0)));
    for (size_t i = 0; i < triangles.size(); ++i) EXPECT_EQ(kept[i], i < 64) << i;
    // A single half-space far from both: nothing.
    EXPECT_EQ(bvh.cull({{{1, 0, 0}, -1000.0}}, ranges), 0u);
    EXPECT_TRUE(ranges.empty());
    // No planes: the whole volume, one range.
    EXPECT_EQ(bvh.cull({}, ranges), 128u);
    ASSERT_EQ(ranges.size(), 1u);
    EXPECT_EQ(ranges[0].first, 0u);
    EXPECT_EQ(ranges[0].count, 128u);
    // An empty hierarchy culls to nothing.
    const OccluderBvh empty(std::vector<Triangle3>{}, 8);
    EXPECT_EQ(empty.cull({}, ranges), 0u);
    EXPECT_TRUE(ranges.empty());
}

// === frusta ================================================================

// Window coordinates of p in f, and whether they lie in the window, with a
// tolerance relative to the window's size for the rounding of the division.
bool inWindow(const SamplingFrustum& f, const Vec3& p) {
    const Vec3 c = f.toCamera(p);
    if (!(c.z > 0)) return false;
    const double u = c.x / c.z, v = c.y / c.z;
    const double tu = 1e-9 * (f.rightEdge - f.left), tv = 1e-9 * (f.top - f.bottom);
    return u >= f.left - tu && u <= f.rightEdge + tu && v >= f.bottom - tv && v <= f.top + tv;
}

void expectOrthonormalBasis(const SamplingFrustum& f) {
    EXPECT_NEAR(glm::length(f.forward), 1.0, 1e-12);
    EXPECT_NEAR(glm::length(f.right), 1.0, 1e-12);
    EXPECT_NEAR(glm::length(f.up), 1.0, 1e-12);
    EXPECT_NEAR(glm::dot(f.forward, f.right), 0.0, 1e-12);
    EXPECT_NEAR(glm::dot(f.forward, f.up), 0.0, 1e-12);
    EXPECT_NEAR(glm::dot(f.right, f.up), 0.0, 1e-12);
    // Left-handed (LightFrustum.h): right × up = −forward.
    EXPECT_NEAR(glm::length(glm::cross(f.right, f.up) + f.forward), 0.0, 1e-12);
}

TEST(LightFrustum, OneFittedWindowHoldsEveryLightCornerFromTheBench) {
    const Light& light = benchScene().lights[0];
    const Vec3 align = light.geometry[0][1] - light.geometry[0][0];
    for (const ReceiverPoint& r : makeBenchReceivers(20)) {
        const Vec3 eye = eyePoint(r.position, r.normal);
        const std::vector<Polygon3> pieces = visibleLightPieces(light, eye, r.normal);
        ASSERT_EQ(pieces.size(), 2u);
        const std::vector<SamplingFrustum> frusta = benchFrusta(r.position, r.normal);
        ASSERT_EQ(frusta.size(), 1u);
        const SamplingFrustum& f = frusta[0];
        expectOrthonormalBasis(f);
        EXPECT_EQ(f.eye, eye);
        // Rows follow the light's first edge: right is that edge made
        // perpendicular to forward.
        const Vec3 flat = align - glm::dot(align, f.forward) * f.forward;
        EXPECT_NEAR(glm::length(glm::cross(f.right, glm::normalize(flat))), 0.0, 1e-12);
        EXPECT_GT(glm::dot(f.right, flat), 0.0);
        double lo[2] = {kInf, kInf}, hi[2] = {-kInf, -kInf};
        for (const Polygon3& piece : pieces)
            for (const Vec3& p : piece) {
                EXPECT_TRUE(inWindow(f, p));
                const Vec3 c = f.toCamera(p);
                for (int k = 0; k < 2; ++k) {
                    lo[k] = std::min(lo[k], c[k] / c.z);
                    hi[k] = std::max(hi[k], c[k] / c.z);
                }
            }
        // Fitted: each side of the window touches a corner (the margin is 1e-7).
        const double w = f.rightEdge - f.left, h = f.top - f.bottom;
        EXPECT_NEAR(f.left, lo[0], 1e-6 * w);
        EXPECT_NEAR(f.rightEdge, hi[0], 1e-6 * w);
        EXPECT_NEAR(f.bottom, lo[1], 1e-6 * h);
        EXPECT_NEAR(f.top, hi[1], 1e-6 * h);
    }
}

TEST(LightFrustum, AReceiverNextToABigLightGetsCubeFacesAndStillSumsToLambert) {
    // 1e-3 below the 1 × 1 light, off its centre: the light fills nearly the
    // whole upper hemisphere, beyond any single frustum's 60° half-angle.
    const Vec3 x(0.1, 1.0 - 1e-3, 0.05);
    const Light& light = benchScene().lights[0];
    const Vec3 eye = eyePoint(x, kUp);
    const std::vector<Polygon3> pieces = visibleLightPieces(light, eye, kUp);
    const std::vector<SamplingFrustum> frusta = benchFrusta(x, kUp);
    ASSERT_GT(frusta.size(), 1u);
    ASSERT_LE(frusta.size(), 6u);
    for (size_t i = 0; i < frusta.size(); ++i) {
        const SamplingFrustum& f = frusta[i];
        expectOrthonormalBasis(f);
        // Windows inside their cube face [−1, 1]², so frusta do not overlap,
        // except for the hair of margin fitWindow adds on every side (1e-7 of
        // the window's size, so that the light's own edges never sit on a
        // window edge): a face clipped at ±1 ends at ±(1 + 2e-7). That
        // sliver is sampled by two faces, an overlap of ~1e-7 of a face,
        // far below any sampling error here.
        const double margin = 1e-6;
        EXPECT_GE(f.left, -1 - margin);
        EXPECT_LE(f.rightEdge, 1 + margin);
        EXPECT_GE(f.bottom, -1 - margin);
        EXPECT_LE(f.top, 1 + margin);
        // ... because their axes are distinct faces of one cube.
        for (size_t j = 0; j < i; ++j) {
            const double c = glm::dot(f.forward, frusta[j].forward);
            EXPECT_TRUE(std::abs(c) < 1e-12 || std::abs(c + 1) < 1e-12) << "faces " << j << ", " << i;
        }
    }
    // Every corner of the light is in some window.
    for (const Polygon3& piece : pieces)
        for (const Vec3& p : piece) {
            bool found = false;
            for (const SamplingFrustum& f : frusta) found = found || inWindow(f, p);
            EXPECT_TRUE(found) << "corner (" << p.x << ", " << p.y << ", " << p.z << ") in no window";
        }

    const double lambert = lambertAt(x, kUp);
    const double lift = liftAllowance(x, kUp);
    EXPECT_LT(lift, 1e-6 * lambert);  // E is flat in h right under a light
    EXPECT_GT(lambert, 0.99 * kPi);   // nearly the whole hemisphere
    // The control variate: Lambert itself (nothing occludes from up here).
    const DirectSample cv = GlEnvironment::sampler(kJittered, kCv, 64, 4).sample(0, x, kUp, 5);
    EXPECT_EQ(cv.frusta, frusta.size());
    EXPECT_NEAR(cv.cosineSolidAngle, lambert, 1e-9 * lambert);
    // The plain sum over the faces: within the boundary-pixel bound summed
    // over the faces (each face is sampled as its own image).
    for (int bits : {1, 4}) {
        const DirectSample plain = GlEnvironment::sampler(kJittered, kPlain, 64, bits).sample(0, x, kUp, 5);
        const PlainBound bound = plainBound(x, kUp, 64, bits);
        EXPECT_EQ(plain.frusta, frusta.size());
        EXPECT_TRUE(std::isfinite(plain.cosineSolidAngle));
        EXPECT_LE(std::abs(plain.cosineSolidAngle - lambert), bound.total + lift)
            << bits << " bits: got " << plain.cosineSolidAngle << ", Lambert " << lambert;
        EXPECT_LT(bound.total, 0.2 * lambert);
        EXPECT_EQ(plain.visibleSamples, plain.lightSamples);
    }
    // The worst-case bound is loose; the mean of 32 passes is a sharper
    // check that no part of the hemisphere is missed or counted twice
    // across the faces (4 standard errors, as in the bench test above).
    DirectLightSampler& plain = GlEnvironment::sampler(kJittered, kPlain, 64, 4);
    std::vector<double> passes;
    for (uint32_t k = 0; k < 32; ++k) passes.push_back(sampleValue(plain, x, kUp, jitter::seedFor(10, k)));
    const MeanAndError m = meanOf(passes);
    EXPECT_LE(std::abs(m.mean - lambert), 4 * m.standardError + lift)
        << "mean " << m.mean << " ± " << m.standardError << ", Lambert " << lambert;
    EXPECT_LT(m.standardError, 1e-3 * lambert);
}

}  // namespace
