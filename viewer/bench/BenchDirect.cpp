#include "BenchDirect.h"

#include "BenchRun.h"
#include "BenchStatistics.h"
#include "BenchTable.h"

#include "core/Error.h"
#include "core/loaders/ObjLoader.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/reference/ExactIrradiance.h"
#include "core/scenes/BenchScene.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/direct/Jitter.h"
#include "gpu_sampling/direct/RayTracedLightSampler.h"
#include "gpu_sampling/gl/GlContext.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <sstream>

namespace ml {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The targets of the issue, and the rule for the recommended default: the
// fastest configuration whose one-pass error meets both error targets.
constexpr double kMeanErrorTarget = 0.002;  // mean |error| / unoccluded
constexpr double kMaxErrorTarget = 0.01;    // max |error| / unoccluded
constexpr double kBenchTimeTarget = 0.1e-3; // s per sample, jittered 64×4, bench scene
constexpr double kHeavyTimeTarget = 0.5e-3; // s per sample, jittered 64×4, 7,200 occluder triangles
// Convergence is measured where samplers err: points whose exact value lies
// strictly between these fractions of their unoccluded value.
constexpr double kPenumbraLow = 0.05, kPenumbraHigh = 0.95;
constexpr int kHeavySubdivisions = 60;  // 60 × 60 × 2 = 7,200 occluder triangles

// --- Sizes of a run ------------------------------------------------------------

struct Workload {
    int pointsPerSide;            // bench receivers per side
    std::vector<int> imageSizes;  // pixels per side
    std::vector<int> bits;        // jittered tests per pixel
    size_t convergencePoints;     // penumbra receivers
    int maxPasses;                // K doubles from 1 up to this
    size_t heavyPoints;           // receivers on the 7,200-triangle scene
    size_t waterPoints;           // receivers on the Water scene; 0 skips it
    int raytraceBits;             // the jittered 64×bits configurations the ray-traced peer repeats
    size_t raytracePoints;        // bench receivers it is measured at
};

Workload workloadFor(const BenchDirectOptions& options) {
    if (options.quick) return {20, {32, 64}, {1, 4}, 40, 8, 300, 0, 4, 100};
    return {options.pointsPerSide, {32, 48, 64}, {1, 4, 8}, 200, 32, 2000, 2000, 8, 2000};
}

// --- Configurations --------------------------------------------------------------

struct Config {
    DirectMethod method;
    DirectEstimator estimator;  // ignored by the occlusion query
    int imageSize;              // pixels per side
    int bits;                   // jittered tests per pixel; 1 for query and regular

    DirectSamplerSettings settings() const {
        DirectSamplerSettings s;
        s.method = method;
        s.estimator = estimator;
        s.imageSize = imageSize;
        s.bits = bits;
        return s;
    }
    bool isJittered64x4() const { return method == DirectMethod::Jittered && imageSize == 64 && bits == 4; }
    // "query 32", "regular 48 cv", "jittered 64x4 plain": no commas, so it
    // is also a CSV cell and a gnuplot label.
    std::string label() const {
        std::string s = concat(directMethodName(method), " ", imageSize);
        if (method == DirectMethod::Jittered) s += concat("x", bits);
        if (method != DirectMethod::OcclusionQuery) s += concat(" ", directEstimatorName(estimator));
        return s;
    }
};

constexpr DirectEstimator kEstimators[] = {DirectEstimator::Plain, DirectEstimator::ControlVariate};

// Fig. 7's schemes, grouped by method; bits vary for jittered sampling only.
std::vector<Config> accuracyConfigs(const Workload& work) {
    std::vector<Config> configs;
    for (int size : work.imageSizes) configs.push_back({DirectMethod::OcclusionQuery, DirectEstimator::Plain, size, 1});
    for (int size : work.imageSizes)
        for (DirectEstimator e : kEstimators) configs.push_back({DirectMethod::Regular, e, size, 1});
    for (int size : work.imageSizes)
        for (int bits : work.bits)
            for (DirectEstimator e : kEstimators) configs.push_back({DirectMethod::Jittered, e, size, bits});
    return configs;
}

std::vector<Config> jittered64x4Configs() {
    std::vector<Config> configs;
    for (DirectEstimator e : kEstimators) configs.push_back({DirectMethod::Jittered, e, 64, 4});
    return configs;
}

// --- Statistics -------------------------------------------------------------------

// Mean, population standard deviation and maximum of non-negative values
// (Welford's update: no cancellation however many values).
class Summary {
public:
    void add(double v) {
        ++n_;
        const double d = v - mean_;
        mean_ += d / double(n_);
        m2_ += d * (v - mean_);
        max_ = std::max(max_, v);
    }
    size_t count() const { return n_; }
    double mean() const { return mean_; }
    double stddev() const { return n_ ? std::sqrt(m2_ / double(n_)) : 0.0; }
    double max() const { return max_; }

private:
    size_t n_ = 0;
    double mean_ = 0, m2_ = 0, max_ = 0;
};

// The exact values at one receiver, computed once and reused by every configuration.
struct Reference {
    double exact = 0;       // visible cosine solid angle (sr)
    double unoccluded = 0;  // the same without occluders (sr), > 0
};

// |estimate − exact| over receivers, in sr and relative to each receiver's
// unoccluded value: the one aggregation behind every error column.
struct ErrorStats {
    Summary relative;  // fraction of the unoccluded cosine solid angle
    Summary absolute;  // sr

    void add(double estimate, const Reference& r) {
        const double e = std::abs(estimate - r.exact);
        absolute.add(e);
        relative.add(e / r.unoccluded);
    }
};

// Medians over samples, in seconds. The paper reports medians (Fig. 9)
// because other threads disturb single timings; so do other processes here.
// `total` is the median of the per-sample totals, not the sum of the medians.
struct PhaseMedians {
    double setup = 0, draw = 0, readback = 0, weighting = 0, total = 0;
};

PhaseMedians medianPhases(const std::vector<DirectPhaseTimes>& times) {
    auto medianOf = [&](auto phase) {
        std::vector<double> v;
        v.reserve(times.size());
        for (const DirectPhaseTimes& t : times) v.push_back(phase(t));
        return median(std::move(v));
    };
    PhaseMedians m;
    m.setup = medianOf([](const DirectPhaseTimes& t) { return t.setup; });
    m.draw = medianOf([](const DirectPhaseTimes& t) { return t.draw; });
    m.readback = medianOf([](const DirectPhaseTimes& t) { return t.readback; });
    m.weighting = medianOf([](const DirectPhaseTimes& t) { return t.weighting; });
    m.total = medianOf([](const DirectPhaseTimes& t) { return t.total(); });
    return m;
}

// --- Measuring -----------------------------------------------------------------------

struct Measurement {
    std::vector<double> estimates;  // cosine solid angle per receiver (sr), from the phase-timed run
    PhaseMedians phases;            // phase-timed run (s per sample)
    double total = 0;               // median s per sample with phase timing off: the real cost
    double trianglesDrawn = 0;      // mean occluder triangles drawn per sample, after culling
    double renderedFraction = 0;    // samples that rendered an image (the others saw no light)
};

// One sample of the scene's first light at each receiver, in two runs with
// the same seeds: phase timing on (estimates, phase medians), then off,
// because the glFinish between phases inflates the total. Receiver i gets
// seed seedFor(seed, i), as pass 0 of the convergence run does.
Measurement measure(GlContext& context, const Scene& scene, const Config& config,
                    const std::vector<ReceiverPoint>& points, uint32_t seed) {
    DirectLightSampler sampler(context, scene, config.settings());
    Measurement m;
    m.estimates.reserve(points.size());
    std::vector<DirectPhaseTimes> timed, untimed;
    timed.reserve(points.size());
    untimed.reserve(points.size());
    double drawn = 0, rendered = 0;
    for (const bool phaseTiming : {true, false}) {
        sampler.setPhaseTiming(phaseTiming);
        for (size_t i = 0; i < points.size(); ++i) {
            const DirectSample s =
                sampler.sample(0, points[i].position, points[i].normal, jitter::seedFor(seed, uint32_t(i)));
            if (!phaseTiming) {
                untimed.push_back(sampler.lastTimes());
                continue;
            }
            timed.push_back(sampler.lastTimes());
            m.estimates.push_back(s.cosineSolidAngle);
            drawn += s.trianglesDrawn;
            rendered += s.frusta > 0 ? 1 : 0;
        }
    }
    m.phases = medianPhases(timed);
    m.total = medianPhases(untimed).total;
    if (!points.empty()) {
        m.trianglesDrawn = drawn / double(points.size());
        m.renderedFraction = rendered / double(points.size());
    }
    return m;
}

// The bench floor's receivers that see some of the light, with their exact values.
struct BenchPoints {
    std::vector<ReceiverPoint> points;
    std::vector<Reference> references;  // parallel to points
    size_t skipped = 0;                 // receivers whose unoccluded value is 0
};

BenchPoints benchPoints(const Scene& scene, int perSide) {
    const ExactDirect exact(scene);
    BenchPoints out;
    for (const ReceiverPoint& p : makeBenchReceivers(perSide)) {
        const double unoccluded = exact.unoccludedCosineSolidAngle(0, p.position, p.normal);
        // A relative error is undefined there; no bench receiver should be
        // such a point, but a changed scene may have some.
        if (!(unoccluded > 0)) {
            ++out.skipped;
            continue;
        }
        out.points.push_back(p);
        out.references.push_back({exact.cosineSolidAngle(0, p.position, p.normal), unoccluded});
    }
    return out;
}

struct AccuracyRow {
    Config config;
    ErrorStats errors;
    Measurement timing;
};

std::vector<AccuracyRow> runAccuracy(GlContext& context, const Scene& scene, const BenchPoints& bench,
                                     const Workload& work, uint32_t seed, const BenchRun& run) {
    std::vector<AccuracyRow> rows;
    for (const Config& config : accuracyConfigs(work)) {
        run.progress("accuracy: %s\n", config.label().c_str());
        AccuracyRow row{config, {}, measure(context, scene, config, bench.points, seed)};
        for (size_t i = 0; i < bench.points.size(); ++i) row.errors.add(row.timing.estimates[i], bench.references[i]);
        rows.push_back(std::move(row));
    }
    return rows;
}

struct SceneTimingRow {
    std::string scene;  // no commas
    size_t triangles = 0;
    Config config;
    size_t points = 0;
    Measurement timing;
};

std::vector<SceneTimingRow> timeScene(GlContext& context, const Scene& scene, const std::string& name,
                                      const std::vector<ReceiverPoint>& points, uint32_t seed, const BenchRun& run) {
    std::vector<SceneTimingRow> rows;
    for (const Config& config : jittered64x4Configs()) {
        run.progress("timing on %s: %s\n", name.c_str(), config.label().c_str());
        rows.push_back({name, scene.triangleCount(), config, points.size(),
                        measure(context, scene, config, points, seed)});
    }
    return rows;
}

// `count` points spread uniformly over the area of the scene's
// non-emitting triangles, as the paper's "samples spread over the whole
// scene", each with its triangle's front-face normal, as a vertex of an
// irradiance mesh would have; points facing away from the light cost
// almost nothing, and the rendered_pct column says how many there are.
std::vector<ReceiverPoint> sceneReceivers(const Scene& scene, size_t count, uint32_t seed) {
    std::vector<Triangle3> triangles;
    std::vector<double> areas;
    for (const Mesh& mesh : scene.meshes)
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            if (scene.materials[mesh.materials[t]].emissive()) continue;
            triangles.push_back(mesh.triangle(t));
            areas.push_back(mesh.area(t));
        }
    if (triangles.empty()) throw InputError(concat(scene.name, ": no non-emitting triangle to place receivers on"));
    std::mt19937 rng(seed);
    std::discrete_distribution<size_t> pick(areas.begin(), areas.end());
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<ReceiverPoint> points;
    points.reserve(count);
    while (points.size() < count) {
        const Triangle3& t = triangles[pick(rng)];
        // Uniform over the triangle (Osada et al.'s square-root warp).
        const double r = std::sqrt(unit(rng)), s = unit(rng);
        const Vec3 p = (1 - r) * t[0] + r * (1 - s) * t[1] + r * s * t[2];
        points.push_back({p, glm::normalize(glm::cross(t[1] - t[0], t[2] - t[0]))});
    }
    return points;
}

// The Water Cornell box: MESHLIGHT_SCENES_DIR, else ../shared/scenes from
// the current directory. Empty when neither has it.
std::string findWaterScene() {
    const char* dir = std::getenv("MESHLIGHT_SCENES_DIR");
    const fs::path base = dir && *dir ? fs::path(dir) : fs::path("../shared/scenes");
    const fs::path path = base / "mcguire-cornellbox" / "CornellBox-Water.obj";
    std::error_code ec;
    return fs::is_regular_file(path, ec) ? path.string() : std::string();
}

struct ConvergenceRow {
    Config config;
    int passes = 0;  // K
    ErrorStats errors;
};

// The error of the mean of K passes at the receivers `ids` (indices into
// bench.points), K = 1, 2, 4, … up to work.maxPasses. Pass p of receiver i
// uses seedFor(seed, i, 0, p).
std::vector<ConvergenceRow> runConvergence(GlContext& context, const Scene& scene, const BenchPoints& bench,
                                           const std::vector<size_t>& ids, const Workload& work, uint32_t seed,
                                           const BenchRun& run) {
    std::vector<Config> configs = jittered64x4Configs();
    configs.push_back({DirectMethod::Regular, DirectEstimator::Plain, 64, 1});
    std::vector<int> ks;
    for (int k = 1; k <= work.maxPasses; k *= 2) ks.push_back(k);

    std::vector<ConvergenceRow> rows;
    for (const Config& config : configs) {
        run.progress("convergence: %s\n", config.label().c_str());
        DirectLightSampler sampler(context, scene, config.settings());
        std::vector<ErrorStats> byK(ks.size());
        for (size_t id : ids) {
            const ReceiverPoint& p = bench.points[id];
            double sum = 0;
            size_t next = 0;
            for (int pass = 0; pass < ks.back(); ++pass) {
                const uint32_t s = jitter::seedFor(seed, uint32_t(id), 0, uint32_t(pass));
                sum += sampler.sample(0, p.position, p.normal, s).cosineSolidAngle;
                if (pass + 1 == ks[next]) byK[next++].add(sum / (pass + 1), bench.references[id]);
            }
        }
        for (size_t k = 0; k < ks.size(); ++k) rows.push_back({config, ks[k], byK[k]});
    }
    return rows;
}

// --- The ray-traced peer ------------------------------------------------------------

// The raster sampler's jittered configuration next to the ray-traced sampler
// (RayTracedLightSampler.h: the same sample points, decided by Embree shadow
// rays on one CPU core), at equal samples (the same settings and seeds: the
// same estimates up to rounding, so only the time differs) and at equal
// time (the ray-traced image size whose time per estimate matches the
// raster sampler's, from the rays per second measured at equal samples).
struct RaytraceRow {
    Config config;          // the raster configuration compared
    std::string sampler;    // "raster", "rays_equal_samples", "rays_equal_time" (no commas)
    int imageSize = 0;      // pixels per side of the sampling image
    double lightSamples = 0;  // mean samples on the light per estimate (rays traced)
    ErrorStats errors;
    double total = 0;       // median s per estimate
};

struct RaytraceTiming {
    ErrorStats errors;
    double median = 0, lightSamples = 0;
};

RaytraceTiming timeRaytrace(const EmbreeScene& rays, const DirectSamplerSettings& settings, const BenchPoints& bench,
                            const std::vector<size_t>& ids, uint32_t seed) {
    const RayTracedLightSampler sampler(rays, settings);
    RaytraceTiming t;
    std::vector<double> times;
    double samples = 0;
    for (size_t id : ids) {
        const ReceiverPoint& p = bench.points[id];
        const Clock::time_point t0 = Clock::now();
        // The raster run's seed for this receiver (measure()): the same jitter.
        const DirectSample s = sampler.sample(0, p.position, p.normal, jitter::seedFor(seed, uint32_t(id)));
        times.push_back(secondsSince(t0));
        t.errors.add(s.cosineSolidAngle, bench.references[id]);
        samples += s.lightSamples;
    }
    t.median = median(times);
    t.lightSamples = ids.empty() ? 0 : samples / double(ids.size());
    return t;
}

std::vector<RaytraceRow> runRaytrace(const Scene& scene, const BenchPoints& bench,
                                     const std::vector<AccuracyRow>& accuracy, const Workload& work, uint32_t seed,
                                     const BenchRun& run) {
    std::vector<size_t> all(bench.points.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = i;
    const std::vector<size_t> ids = spread(all, work.raytracePoints);
    const EmbreeScene rays(scene);
    std::vector<RaytraceRow> rows;
    for (const AccuracyRow& r : accuracy) {
        if (r.config.method != DirectMethod::Jittered || r.config.imageSize != 64 || r.config.bits != work.raytraceBits)
            continue;
        run.progress("ray-traced peer: %s\n", r.config.label().c_str());
        RaytraceRow raster{r.config, "raster", r.config.imageSize, 0, {}, r.timing.total};
        for (size_t id : ids) raster.errors.add(r.timing.estimates[id], bench.references[id]);
        rows.push_back(raster);

        DirectSamplerSettings settings = r.config.settings();
        const RaytraceTiming same = timeRaytrace(rays, settings, bench, ids, seed);
        rows.push_back({r.config, "rays_equal_samples", settings.imageSize, same.lightSamples, same.errors, same.median});
        rows[rows.size() - 2].lightSamples = same.lightSamples;  // the raster's: the same points on the light

        // Rays per second at equal samples give the image whose estimates
        // take as long as the raster sampler's (a square image, same bits).
        const double perRay = same.lightSamples > 0 ? same.median / same.lightSamples : 0.0;
        const double affordable = perRay > 0 ? r.timing.total / perRay : 0.0;
        const double fill = same.lightSamples / (64.0 * 64.0 * settings.bits);  // fraction of samples on the light
        settings.imageSize = std::clamp(int(std::lround(std::sqrt(affordable / std::max(fill, 1e-3) / settings.bits))), 4, 1024);
        const RaytraceTiming equal = timeRaytrace(rays, settings, bench, ids, seed);
        rows.push_back({r.config, "rays_equal_time", settings.imageSize, equal.lightSamples, equal.errors, equal.median});
    }
    return rows;
}

// --- Tables ----------------------------------------------------------------------------

std::vector<std::string> operator+(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

const std::vector<std::string> kErrorHeader = {"mean_rel_pct", "std_rel_pct", "max_rel_pct",
                                               "mean_abs_sr",  "std_abs_sr",  "max_abs_sr"};
std::vector<std::string> errorCells(const ErrorStats& e) {
    return {benchPct(e.relative.mean()), benchPct(e.relative.stddev()), benchPct(e.relative.max()),
            benchNumber(e.absolute.mean()), benchNumber(e.absolute.stddev()), benchNumber(e.absolute.max())};
}

const std::vector<std::string> kTimingHeader = {"setup_ms", "draw_ms", "readback_ms",
                                                "weighting_ms", "timed_total_ms", "total_ms"};
std::vector<std::string> timingCells(const Measurement& m) {
    return {benchMs(m.phases.setup),     benchMs(m.phases.draw),  benchMs(m.phases.readback),
            benchMs(m.phases.weighting), benchMs(m.phases.total), benchMs(m.total)};
}

BenchTable accuracyTable(const std::vector<AccuracyRow>& rows) {
    BenchTable t(std::vector<std::string>{"config", "points"} + kErrorHeader + kTimingHeader);
    for (const AccuracyRow& r : rows)
        t.addRow(std::vector<std::string>{r.config.label(), std::to_string(r.errors.relative.count())} +
                 errorCells(r.errors) + timingCells(r.timing));
    return t;
}

BenchTable scenesTable(const std::vector<SceneTimingRow>& rows) {
    BenchTable t(std::vector<std::string>{"scene", "triangles", "config", "points", "rendered_pct",
                                          "drawn_triangles"} +
                 kTimingHeader);
    for (const SceneTimingRow& r : rows)
        t.addRow(std::vector<std::string>{r.scene, std::to_string(r.triangles), r.config.label(),
                                          std::to_string(r.points), benchPct(r.timing.renderedFraction),
                                          benchNumber(r.timing.trianglesDrawn)} +
                 timingCells(r.timing));
    return t;
}

BenchTable convergenceTable(const std::vector<ConvergenceRow>& rows) {
    BenchTable t(std::vector<std::string>{"config", "passes", "points"} + kErrorHeader);
    for (const ConvergenceRow& r : rows)
        t.addRow(std::vector<std::string>{r.config.label(), std::to_string(r.passes),
                                          std::to_string(r.errors.relative.count())} +
                 errorCells(r.errors));
    return t;
}

BenchTable raytraceTable(const std::vector<RaytraceRow>& rows) {
    BenchTable t(std::vector<std::string>{"config", "sampler", "image_size", "light_samples", "points"} +
                 kErrorHeader + std::vector<std::string>{"total_ms"});
    for (const RaytraceRow& r : rows)
        t.addRow(std::vector<std::string>{r.config.label(), r.sampler, std::to_string(r.imageSize),
                                          benchNumber(r.lightSamples), std::to_string(r.errors.relative.count())} +
                 errorCells(r.errors) + std::vector<std::string>{benchMs(r.total)});
    return t;
}

// --- Plots ------------------------------------------------------------------------------

const std::vector<GnuplotOutput> kPlots = {
    {"out_error", "direct_error_vs_time.png"},
    {"out_phases", "direct_phases.png"},
    {"out_convergence", "direct_convergence.png"},
};

// A gnuplot script with its data inline (Gnuplot.h: output names are
// variables with the final names as defaults, so the script also runs alone).
std::string gnuplotScript(const std::vector<AccuracyRow>& accuracy, const std::vector<ConvergenceRow>& convergence,
                          size_t points) {
    std::ostringstream gp;
    gp << "# Written by 'meshlight bench direct'; run with gnuplot in this folder.\n" << gnuplotOutputDefaults(kPlots);
    gp << "set terminal pngcairo size 1400,900 font ',10'\n"
          "set datafile separator ','\n"
          "set grid\n\n"
          "# label, untimed total ms, mean %, max %, setup, draw, readback, weighting ms\n"
          "$accuracy << EOD\n";
    for (const AccuracyRow& r : accuracy)
        gp << '"' << r.config.label() << "\"," << benchMs(r.timing.total) << "," << benchPct(r.errors.relative.mean())
           << "," << benchPct(r.errors.relative.max()) << "," << benchMs(r.timing.phases.setup) << ","
           << benchMs(r.timing.phases.draw) << "," << benchMs(r.timing.phases.readback) << ","
           << benchMs(r.timing.phases.weighting) << "\n";
    gp << "EOD\n\n";

    // One data block per configuration, in order of first appearance.
    std::vector<std::string> labels;
    for (const ConvergenceRow& r : convergence)
        if (std::find(labels.begin(), labels.end(), r.config.label()) == labels.end())
            labels.push_back(r.config.label());
    double firstError = 0;  // jittered plain at K = 1 anchors the 1/√K guide
    int maxPasses = 1;
    for (size_t b = 0; b < labels.size(); ++b) {
        gp << "# passes K, mean %\n$conv" << b << " << EOD\n";
        for (const ConvergenceRow& r : convergence) {
            if (r.config.label() != labels[b]) continue;
            gp << r.passes << "," << benchPct(r.errors.relative.mean()) << "\n";
            if (b == 0 && r.passes == 1) firstError = 100 * r.errors.relative.mean();
            maxPasses = std::max(maxPasses, r.passes);
        }
        gp << "EOD\n";
    }

    gp << "\nset output out_error\n"
          "set title 'One pass on the bench scene (" << points << " receivers): error against cost'\n"
          "set logscale xy\n"
          "set xlabel 'median time per sample (ms, phases not timed)'\n"
          "set ylabel '|error| / unoccluded (%)'\n"
          "set key outside right top\n"
          "plot $accuracy using 2:3 with points pt 7 ps 1.3 title 'mean', \\\n"
          "     $accuracy using 2:4 with points pt 5 ps 1.3 title 'max', \\\n"
          "     $accuracy using 2:3:1 with labels font ',7' left offset char 0.7,0.3 notitle, \\\n"
          "     $accuracy using 2:4:1 with labels font ',7' left offset char 0.7,0.3 notitle, \\\n"
          "     " << 100 * kMeanErrorTarget << " with lines dt 2 lc rgb 'gray40' title 'mean target', \\\n"
          "     " << 100 * kMaxErrorTarget << " with lines dt 3 lc rgb 'gray20' title 'max target'\n\n";

    gp << "set output out_phases\n"
          "set title 'Median time of each phase per sample (glFinish between phases)'\n"
          "unset logscale\n"
          "unset xlabel\n"
          "set ylabel 'ms per sample'\n"
          "set key inside left top\n"
          "set style data histograms\n"
          "set style histogram rowstacked\n"
          "set style fill solid 0.85 border -1\n"
          "set boxwidth 0.75\n"
          "set xtics rotate by -45 left font ',8'\n"
          "set bmargin 9\n"
          "plot $accuracy using 5:xtic(1) title 'setup', $accuracy using 6 title 'draw', \\\n"
          "     $accuracy using 7 title 'readback', $accuracy using 8 title 'weighting'\n\n";

    gp << "set output out_convergence\n"
          "set title 'Mean of K passes at " << (convergence.empty() ? 0 : convergence.front().errors.relative.count())
       << " penumbra points'\n"
          "set style data linespoints\n"
          "set xtics norotate font ',10' (";
    for (int k = 1; k <= maxPasses; k *= 2) gp << (k > 1 ? ", " : "") << k;
    gp << ")\n"
          "set bmargin\n"
          "set logscale xy\n"
          "set xrange [0.8:" << maxPasses * 1.25 << "]\n"
          "set xlabel 'passes averaged, K'\n"
          "set ylabel 'mean |error| / unoccluded (%)'\n"
          "set key outside right top\n"
          "plot ";
    for (size_t b = 0; b < labels.size(); ++b)
        gp << "$conv" << b << " using 1:2 pt 7 title '" << labels[b] << "', ";
    gp << firstError << "/sqrt(x) with lines dt 2 lc rgb 'gray40' title '1/sqrt(K)'\n";
    return gp.str();
}

// --- Summary ------------------------------------------------------------------------------

const AccuracyRow* recommended(const std::vector<AccuracyRow>& rows) {
    const AccuracyRow* best = nullptr;
    for (const AccuracyRow& r : rows)
        if (r.errors.relative.mean() <= kMeanErrorTarget && r.errors.relative.max() <= kMaxErrorTarget &&
            (!best || r.timing.total < best->timing.total))
            best = &r;
    return best;
}

std::string recommendationLine(const std::vector<AccuracyRow>& rows) {
    if (const AccuracyRow* r = recommended(rows))
        return concat(r->config.label(), ": mean ", benchPct(r->errors.relative.mean()), " %, max ",
                      benchPct(r->errors.relative.max()), " % of unoccluded, ", benchMs(r->timing.total),
                      " ms median per sample — the fastest configuration with mean ≤ ", benchPct(kMeanErrorTarget),
                      " % and max ≤ ", benchPct(kMaxErrorTarget), " %.");
    return concat("No configuration reaches mean ≤ ", benchPct(kMeanErrorTarget), " % and max ≤ ",
                  benchPct(kMaxErrorTarget), " % in one pass; no default is recommended by this rule.");
}

// For progressive refinement the figure of merit is different: averaging K
// jittered passes divides the error by about √K, so what a time budget buys
// is set by error² × time per sample. Only jittered configurations qualify
// (regular and query repeat the same value).
std::string efficiencyLine(const std::vector<AccuracyRow>& rows) {
    const AccuracyRow* best = nullptr;
    auto merit = [](const AccuracyRow& r) {
        const double e = r.errors.relative.mean();
        return e * e * r.timing.total;
    };
    for (const AccuracyRow& r : rows)
        if (r.config.method == DirectMethod::Jittered && (!best || merit(r) < merit(*best))) best = &r;
    if (!best) return "no jittered configuration was measured.";
    return concat(best->config.label(), ": mean ", benchPct(best->errors.relative.mean()), " % at ",
                  benchMs(best->timing.total),
                  " ms per sample — the lowest error² × time, what progressive averaging converges by.");
}

// `heavy`: the rows of the 7,200-triangle scene, checked against its target.
std::string summaryMarkdown(const BenchRun& run, double wallSeconds, const BenchPoints& points,
                            const std::vector<AccuracyRow>& accuracy, const std::vector<SceneTimingRow>& heavy,
                            const std::vector<ConvergenceRow>& convergence, const std::vector<RaytraceRow>& raytrace) {
    std::ostringstream md;
    md << "# Direct-light sampler bench (Fournier & Péroche §6.1)\n\n"
       << "- OpenGL: " << run.glDescription() << "\n"
       << "- mode: " << run.mode() << ", seed " << run.options().seed << ", " << points.points.size()
       << " bench receivers";
    if (points.skipped) md << " (" << points.skipped << " more skipped: unoccluded value 0)";
    md << "\n- wall time: " << benchNumber(wallSeconds) << " s\n" << softwareRasteriserNote(run.glDescription());

    md << "\n## Recommended default\n\n- one pass: " << recommendationLine(accuracy)
       << "\n- progressive refinement: " << efficiencyLine(accuracy) << "\n\n## Targets\n\n"
       << "| target | measured | met |\n|---|---|---|\n";
    auto target = [&](const std::string& what, double value, double limit, const char* unit, double scale) {
        md << "| " << what << " ≤ " << benchNumber(scale * limit) << " " << unit << " | "
           << benchNumber(scale * value) << " " << unit << " | " << (value <= limit ? "yes" : "**no**") << " |\n";
    };
    for (const AccuracyRow& r : accuracy) {
        if (!r.config.isJittered64x4()) continue;
        const std::string name = r.config.label();
        target(name + ", bench scene, median per sample", r.timing.total, kBenchTimeTarget, "ms", 1e3);
        target(name + ", one pass, mean error", r.errors.relative.mean(), kMeanErrorTarget, "%", 100);
        target(name + ", one pass, max error", r.errors.relative.max(), kMaxErrorTarget, "%", 100);
    }
    for (const SceneTimingRow& r : heavy)
        target(concat(r.config.label(), ", ", r.triangles, "-triangle scene, median per sample"), r.timing.total,
               kHeavyTimeTarget, "ms", 1e3);

    md << "\n## Convergence at penumbra points\n\n";
    std::vector<std::string> seen;
    for (const ConvergenceRow& first : convergence) {
        const std::string label = first.config.label();
        if (std::find(seen.begin(), seen.end(), label) != seen.end()) continue;
        seen.push_back(label);
        const ConvergenceRow* last = &first;
        for (const ConvergenceRow& r : convergence)
            if (r.config.label() == label) last = &r;
        md << "- " << label << ": mean error " << benchPct(first.errors.relative.mean()) << " % at K = " << first.passes
           << ", " << benchPct(last->errors.relative.mean()) << " % at K = " << last->passes << " (×"
           << benchNumber(last->errors.relative.mean() / std::max(first.errors.relative.mean(), 1e-300)) << ")\n";
    }
    BenchTable peer(
        {"config", "sampler", "image", "rays per estimate", "mean error %", "max error %", "ms per estimate"});
    for (const RaytraceRow& r : raytrace)
        peer.addRow({r.config.label(), r.sampler, std::to_string(r.imageSize), benchNumber(r.lightSamples),
                     benchPct(r.errors.relative.mean()), benchPct(r.errors.relative.max()), benchMs(r.total)});
    md << "\n## Ray-traced peer (Embree shadow rays through the same sample points, one CPU core)\n\n"
       << peer.markdown();
    md << "\nJittered passes are independent, so their mean converges (about 1/√K); every regular pass repeats "
          "the same value, so its error cannot fall.\n\nTables: direct_accuracy.csv, direct_timing_scenes.csv, "
          "direct_convergence.csv, direct_raytrace.csv. Times are medians per sample; total_ms is measured without glFinish between "
          "phases (the real cost), timed_total_ms and the phase columns with it.\n";
    return md.str();
}

}  // namespace

int runBenchDirect(const BenchDirectOptions& options) {
    BenchRun run(options);
    const Workload work = workloadFor(options);
    const std::unique_ptr<GlContext> context = run.openContext();

    const Scene bench = makeBenchScene();
    const BenchPoints points = benchPoints(bench, work.pointsPerSide);
    std::printf("bench scene: %zu receivers", points.points.size());
    if (points.skipped) std::printf(", %zu skipped (unoccluded value 0: no relative error)", points.skipped);
    std::printf("\n");

    const std::vector<AccuracyRow> accuracy = runAccuracy(*context, bench, points, work, options.seed, run);
    const std::vector<RaytraceRow> raytrace = runRaytrace(bench, points, accuracy, work, options.seed, run);

    const Scene heavy = makeBenchScene(kHeavySubdivisions);
    const int heavySide = int(std::ceil(std::sqrt(double(work.heavyPoints))));
    const std::vector<SceneTimingRow> heavyRows =
        timeScene(*context, heavy, concat("bench-", heavy.triangleCount(), "-triangles"),
                  spread(makeBenchReceivers(heavySide), work.heavyPoints), options.seed, run);
    std::vector<SceneTimingRow> scenes = heavyRows;
    const std::string waterPath = work.waterPoints ? findWaterScene() : std::string();
    if (!work.waterPoints) {
        std::printf("note: Water scene skipped in quick mode\n");
    } else if (waterPath.empty()) {
        std::printf("note: CornellBox-Water.obj not found under $MESHLIGHT_SCENES_DIR or ../shared/scenes "
                    "(mcguire-cornellbox/); its timings are skipped\n");
    } else {
        const Scene water = loadObj(waterPath);
        for (SceneTimingRow& row : timeScene(*context, water, "CornellBox-Water",
                                             sceneReceivers(water, work.waterPoints, options.seed), options.seed,
                                             run))
            scenes.push_back(std::move(row));
    }

    std::vector<size_t> penumbra;
    for (size_t i = 0; i < points.points.size(); ++i) {
        const Reference& r = points.references[i];
        if (r.exact > kPenumbraLow * r.unoccluded && r.exact < kPenumbraHigh * r.unoccluded) penumbra.push_back(i);
    }
    const std::vector<size_t> convergenceIds = spread(penumbra, work.convergencePoints);
    if (convergenceIds.size() < work.convergencePoints)
        std::printf("note: only %zu penumbra receivers for convergence (%zu asked)\n", convergenceIds.size(),
                    work.convergencePoints);
    const std::vector<ConvergenceRow> convergence =
        runConvergence(*context, bench, points, convergenceIds, work, options.seed, run);

    const BenchTable accuracyT = accuracyTable(accuracy), scenesT = scenesTable(scenes),
                     convergenceT = convergenceTable(convergence);
    std::printf("\nAccuracy, one pass (Fig. 7) and median times per sample (Fig. 9), bench scene.\n"
                "Errors |estimate - exact|: relative in %% of each point's unoccluded value, absolute in sr.\n"
                "Phase columns and timed_total with glFinish between phases; total_ms without (the real cost).\n\n%s",
                accuracyT.aligned().c_str());
    std::printf("\nTimings on larger scenes (median ms per sample; rendered_pct: samples that saw the light;\n"
                "drawn_triangles: mean occluder triangles drawn after culling).\n\n%s",
                scenesT.aligned().c_str());
    const BenchTable raytraceT = raytraceTable(raytrace);
    std::printf("\nRay-traced peer (Embree shadow rays through the raster sampler's sample points, one core): at "
                "equal samples (same seeds) and at equal time per estimate; errors over %zu receivers.\n\n%s",
                raytrace.empty() ? size_t(0) : raytrace.front().errors.relative.count(), raytraceT.aligned().c_str());
    std::printf("\nConvergence: error of the mean of K passes at penumbra receivers "
                "(exact between %g%% and %g%% of unoccluded).\n\n%s",
                100 * kPenumbraLow, 100 * kPenumbraHigh, convergenceT.aligned().c_str());

    run.writeCsv("direct_accuracy.csv", accuracyT);
    run.writeCsv("direct_timing_scenes.csv", scenesT);
    run.writeCsv("direct_convergence.csv", convergenceT);
    run.writeCsv("direct_raytrace.csv", raytraceT);
    run.plot("direct_plots.gp", gnuplotScript(accuracy, convergence, points.points.size()), kPlots);

    const double wall = run.seconds();
    run.write("direct_summary.md", summaryMarkdown(run, wall, points, accuracy, heavyRows, convergence, raytrace));
    std::printf("\nRecommended for one pass: %s\nRecommended for progressive refinement: %s\n",
                recommendationLine(accuracy).c_str(), efficiencyLine(accuracy).c_str());
    run.printWallTime(wall);
    return 0;
}

}  // namespace ml
