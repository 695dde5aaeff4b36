#include "BenchDirect.h"

#include "core/Error.h"
#include "core/io/AtomicFile.h"
#include "core/loaders/ObjLoader.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/reference/ExactIrradiance.h"
#include "core/scenes/BenchScene.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/direct/Jitter.h"
#include "gpu_sampling/direct/RayTracedLightSampler.h"

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

double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

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

double median(std::vector<double> values) {
    if (values.empty()) return 0;
    const auto mid = values.begin() + std::ptrdiff_t(values.size() / 2);
    std::nth_element(values.begin(), mid, values.end());
    if (values.size() % 2) return *mid;
    return 0.5 * (*mid + *std::max_element(values.begin(), mid));
}

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

// `count` items spread evenly through `items` (all of them when there are
// no more), so a subset still covers the whole floor or penumbra.
template <typename T>
std::vector<T> spread(const std::vector<T>& items, size_t count) {
    if (items.size() <= count) return items;
    std::vector<T> out;
    out.reserve(count);
    for (size_t k = 0; k < count; ++k) out.push_back(items[k * items.size() / count]);
    return out;
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
                                     const Workload& work, uint32_t seed, Clock::time_point start) {
    std::vector<AccuracyRow> rows;
    for (const Config& config : accuracyConfigs(work)) {
        std::fprintf(stderr, "[%6.1f s] accuracy: %s\n", secondsSince(start), config.label().c_str());
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
                                      const std::vector<ReceiverPoint>& points, uint32_t seed,
                                      Clock::time_point start) {
    std::vector<SceneTimingRow> rows;
    for (const Config& config : jittered64x4Configs()) {
        std::fprintf(stderr, "[%6.1f s] timing on %s: %s\n", secondsSince(start), name.c_str(), config.label().c_str());
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
                                           Clock::time_point start) {
    std::vector<Config> configs = jittered64x4Configs();
    configs.push_back({DirectMethod::Regular, DirectEstimator::Plain, 64, 1});
    std::vector<int> ks;
    for (int k = 1; k <= work.maxPasses; k *= 2) ks.push_back(k);

    std::vector<ConvergenceRow> rows;
    for (const Config& config : configs) {
        std::fprintf(stderr, "[%6.1f s] convergence: %s\n", secondsSince(start), config.label().c_str());
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
                                     Clock::time_point start) {
    std::vector<size_t> all(bench.points.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = i;
    const std::vector<size_t> ids = spread(all, work.raytracePoints);
    const EmbreeScene rays(scene);
    std::vector<RaytraceRow> rows;
    for (const AccuracyRow& r : accuracy) {
        if (r.config.method != DirectMethod::Jittered || r.config.imageSize != 64 || r.config.bits != work.raytraceBits)
            continue;
        std::fprintf(stderr, "[%6.1f s] ray-traced peer: %s\n", secondsSince(start), r.config.label().c_str());
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

// A table printed aligned on stdout and written as CSV from the same cells,
// so the two never disagree. Cells must not contain commas.
class Table {
public:
    explicit Table(std::vector<std::string> header) : header_(std::move(header)) {}

    void addRow(std::vector<std::string> cells) {
        ML_ASSERT(cells.size() == header_.size(), cells.size(), " cells for ", header_.size(), " columns");
        rows_.push_back(std::move(cells));
    }

    // First column left-aligned (labels), the others right-aligned (numbers).
    std::string aligned() const {
        std::vector<size_t> width(header_.size());
        for (size_t c = 0; c < header_.size(); ++c) {
            width[c] = header_[c].size();
            for (const auto& row : rows_) width[c] = std::max(width[c], row[c].size());
        }
        std::ostringstream os;
        auto line = [&](const std::vector<std::string>& cells) {
            for (size_t c = 0; c < cells.size(); ++c) {
                const std::string pad(width[c] - cells[c].size(), ' ');
                os << (c ? "  " : "") << (c ? pad + cells[c] : cells[c] + pad);
            }
            os << "\n";
        };
        line(header_);
        for (const auto& row : rows_) line(row);
        return os.str();
    }

    std::string csv() const {
        std::ostringstream os;
        auto line = [&](const std::vector<std::string>& cells) {
            for (size_t c = 0; c < cells.size(); ++c) os << (c ? "," : "") << cells[c];
            os << "\n";
        };
        line(header_);
        for (const auto& row : rows_) line(row);
        return os.str();
    }

private:
    std::vector<std::string> header_;
    std::vector<std::vector<std::string>> rows_;
};

// Four significant digits: far finer than the run-to-run noise of timings.
std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}
std::string pct(double fraction) { return num(100 * fraction); }
std::string ms(double seconds) { return num(1e3 * seconds); }

std::vector<std::string> operator+(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

const std::vector<std::string> kErrorHeader = {"mean_rel_pct", "std_rel_pct", "max_rel_pct",
                                               "mean_abs_sr",  "std_abs_sr",  "max_abs_sr"};
std::vector<std::string> errorCells(const ErrorStats& e) {
    return {pct(e.relative.mean()), pct(e.relative.stddev()), pct(e.relative.max()),
            num(e.absolute.mean()), num(e.absolute.stddev()), num(e.absolute.max())};
}

const std::vector<std::string> kTimingHeader = {"setup_ms", "draw_ms", "readback_ms",
                                                "weighting_ms", "timed_total_ms", "total_ms"};
std::vector<std::string> timingCells(const Measurement& m) {
    return {ms(m.phases.setup), ms(m.phases.draw), ms(m.phases.readback),
            ms(m.phases.weighting), ms(m.phases.total), ms(m.total)};
}

Table accuracyTable(const std::vector<AccuracyRow>& rows) {
    Table t(std::vector<std::string>{"config", "points"} + kErrorHeader + kTimingHeader);
    for (const AccuracyRow& r : rows)
        t.addRow(std::vector<std::string>{r.config.label(), std::to_string(r.errors.relative.count())} +
                 errorCells(r.errors) + timingCells(r.timing));
    return t;
}

Table scenesTable(const std::vector<SceneTimingRow>& rows) {
    Table t(std::vector<std::string>{"scene", "triangles", "config", "points", "rendered_pct", "drawn_triangles"} +
            kTimingHeader);
    for (const SceneTimingRow& r : rows)
        t.addRow(std::vector<std::string>{r.scene, std::to_string(r.triangles), r.config.label(),
                                          std::to_string(r.points), pct(r.timing.renderedFraction),
                                          num(r.timing.trianglesDrawn)} +
                 timingCells(r.timing));
    return t;
}

Table convergenceTable(const std::vector<ConvergenceRow>& rows) {
    Table t(std::vector<std::string>{"config", "passes", "points"} + kErrorHeader);
    for (const ConvergenceRow& r : rows)
        t.addRow(std::vector<std::string>{r.config.label(), std::to_string(r.passes),
                                          std::to_string(r.errors.relative.count())} +
                 errorCells(r.errors));
    return t;
}

Table raytraceTable(const std::vector<RaytraceRow>& rows) {
    Table t(std::vector<std::string>{"config", "sampler", "image_size", "light_samples", "points"} + kErrorHeader +
            std::vector<std::string>{"total_ms"});
    for (const RaytraceRow& r : rows)
        t.addRow(std::vector<std::string>{r.config.label(), r.sampler, std::to_string(r.imageSize), num(r.lightSamples),
                                          std::to_string(r.errors.relative.count())} +
                 errorCells(r.errors) + std::vector<std::string>{ms(r.total)});
    return t;
}

// --- Plots ------------------------------------------------------------------------------

const char* const kPlotNames[] = {"direct_error_vs_time.png", "direct_phases.png", "direct_convergence.png"};
const char* const kPlotVariables[] = {"out_error", "out_phases", "out_convergence"};

// A gnuplot script with its data inline. Output names are variables with
// the final names as defaults, so the script also runs alone; the bench
// passes temporary names and renames them once gnuplot has succeeded.
std::string gnuplotScript(const std::vector<AccuracyRow>& accuracy, const std::vector<ConvergenceRow>& convergence,
                          size_t points) {
    std::ostringstream gp;
    gp << "# Written by 'meshlight bench direct'; run with gnuplot in this folder.\n";
    for (int i = 0; i < 3; ++i)
        gp << "if (!exists('" << kPlotVariables[i] << "')) " << kPlotVariables[i] << " = '" << kPlotNames[i] << "'\n";
    gp << "set terminal pngcairo size 1400,900 font ',10'\n"
          "set datafile separator ','\n"
          "set grid\n\n"
          "# label, untimed total ms, mean %, max %, setup, draw, readback, weighting ms\n"
          "$accuracy << EOD\n";
    for (const AccuracyRow& r : accuracy)
        gp << '"' << r.config.label() << "\"," << ms(r.timing.total) << "," << pct(r.errors.relative.mean()) << ","
           << pct(r.errors.relative.max()) << "," << ms(r.timing.phases.setup) << "," << ms(r.timing.phases.draw)
           << "," << ms(r.timing.phases.readback) << "," << ms(r.timing.phases.weighting) << "\n";
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
            gp << r.passes << "," << pct(r.errors.relative.mean()) << "\n";
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

std::string shellQuote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

// Writes the script, runs gnuplot on it if installed, and moves its PNGs
// into place; only a note when gnuplot is missing, since the CSVs hold the data.
void writePlots(const fs::path& dir, const std::string& script) {
    writeTextFileAtomically((dir / "direct_plots.gp").string(), script);
    if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) {
        std::printf("note: gnuplot not found (Debian: apt-get install gnuplot-nox); plots skipped, "
                    "CSVs and %s written\n",
                    (dir / "direct_plots.gp").string().c_str());
        return;
    }
    std::vector<std::unique_ptr<AtomicOutput>> outputs;
    std::string assignments;
    for (int i = 0; i < 3; ++i) {
        outputs.push_back(std::make_unique<AtomicOutput>((dir / kPlotNames[i]).string()));
        // Temporary names are ".NAME.tmp-PID-N": nothing to escape.
        assignments += concat(kPlotVariables[i], "='", outputs.back()->path().filename().string(), "';");
    }
    const std::string command =
        concat("cd ", shellQuote(dir.string()), " && gnuplot -e \"", assignments, "\" direct_plots.gp");
    if (std::system(command.c_str()) != 0)
        throw std::runtime_error(concat("gnuplot failed on ", (dir / "direct_plots.gp").string()));
    for (auto& out : outputs) out->commit();
}

// --- Summary ------------------------------------------------------------------------------

struct RunInfo {
    std::string context;      // GlContext::describe()
    std::string mode;         // "full" or "quick"
    uint32_t seed = 0;
    size_t receivers = 0, skipped = 0;
    double wallSeconds = 0;
};

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
        return concat(r->config.label(), ": mean ", pct(r->errors.relative.mean()), " %, max ",
                      pct(r->errors.relative.max()), " % of unoccluded, ", ms(r->timing.total),
                      " ms median per sample — the fastest configuration with mean ≤ ", pct(kMeanErrorTarget),
                      " % and max ≤ ", pct(kMaxErrorTarget), " %.");
    return concat("No configuration reaches mean ≤ ", pct(kMeanErrorTarget), " % and max ≤ ", pct(kMaxErrorTarget),
                  " % in one pass; no default is recommended by this rule.");
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
    return concat(best->config.label(), ": mean ", pct(best->errors.relative.mean()), " % at ", ms(best->timing.total),
                  " ms per sample — the lowest error² × time, what progressive averaging converges by.");
}

// `heavy`: the rows of the 7,200-triangle scene, checked against its target.
std::string summaryMarkdown(const RunInfo& info, const std::vector<AccuracyRow>& accuracy,
                            const std::vector<SceneTimingRow>& heavy, const std::vector<ConvergenceRow>& convergence,
                            const std::vector<RaytraceRow>& raytrace) {
    std::ostringstream md;
    md << "# Direct-light sampler bench (Fournier & Péroche §6.1)\n\n"
       << "- OpenGL: " << info.context << "\n"
       << "- mode: " << info.mode << ", seed " << info.seed << ", " << info.receivers << " bench receivers";
    if (info.skipped) md << " (" << info.skipped << " more skipped: unoccluded value 0)";
    md << "\n- wall time: " << num(info.wallSeconds) << " s\n";
    if (info.context.find("llvmpipe") != std::string::npos || info.context.find("softpipe") != std::string::npos)
        md << "- timings come from Mesa's software rasteriser on the CPU, not from a GPU\n";

    md << "\n## Recommended default\n\n- one pass: " << recommendationLine(accuracy)
       << "\n- progressive refinement: " << efficiencyLine(accuracy) << "\n\n## Targets\n\n"
       << "| target | measured | met |\n|---|---|---|\n";
    auto target = [&](const std::string& what, double value, double limit, const char* unit, double scale) {
        md << "| " << what << " ≤ " << num(scale * limit) << " " << unit << " | " << num(scale * value) << " " << unit
           << " | " << (value <= limit ? "yes" : "**no**") << " |\n";
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
        md << "- " << label << ": mean error " << pct(first.errors.relative.mean()) << " % at K = " << first.passes
           << ", " << pct(last->errors.relative.mean()) << " % at K = " << last->passes << " (×"
           << num(last->errors.relative.mean() / std::max(first.errors.relative.mean(), 1e-300)) << ")\n";
    }
    md << "\n## Ray-traced peer (Embree shadow rays through the same sample points, one CPU core)\n\n"
       << "| config | sampler | image | rays per estimate | mean error % | max error % | ms per estimate |\n"
       << "|---|---|---|---|---|---|---|\n";
    for (const RaytraceRow& r : raytrace)
        md << "| " << r.config.label() << " | " << r.sampler << " | " << r.imageSize << " | " << num(r.lightSamples)
           << " | " << pct(r.errors.relative.mean()) << " | " << pct(r.errors.relative.max()) << " | " << ms(r.total)
           << " |\n";
    md << "\nJittered passes are independent, so their mean converges (about 1/√K); every regular pass repeats "
          "the same value, so its error cannot fall.\n\nTables: direct_accuracy.csv, direct_timing_scenes.csv, "
          "direct_convergence.csv, direct_raytrace.csv. Times are medians per sample; total_ms is measured without glFinish between "
          "phases (the real cost), timed_total_ms and the phase columns with it.\n";
    return md.str();
}

}  // namespace

int runBenchDirect(const BenchDirectOptions& options) {
    const Clock::time_point start = Clock::now();
    const Workload work = workloadFor(options);
    // Before minutes of work, so that a bad path fails at once.
    makeOutputDirectory(options.outDir);
    const fs::path dir(options.outDir);
    const std::unique_ptr<GlContext> context = createHeadlessContext(options.backend);
    std::printf("OpenGL: %s\n", context->describe().c_str());

    const Scene bench = makeBenchScene();
    const BenchPoints points = benchPoints(bench, work.pointsPerSide);
    std::printf("bench scene: %zu receivers", points.points.size());
    if (points.skipped) std::printf(", %zu skipped (unoccluded value 0: no relative error)", points.skipped);
    std::printf("\n");

    const std::vector<AccuracyRow> accuracy = runAccuracy(*context, bench, points, work, options.seed, start);
    const std::vector<RaytraceRow> raytrace = runRaytrace(bench, points, accuracy, work, options.seed, start);

    const Scene heavy = makeBenchScene(kHeavySubdivisions);
    const int heavySide = int(std::ceil(std::sqrt(double(work.heavyPoints))));
    const std::vector<SceneTimingRow> heavyRows =
        timeScene(*context, heavy, concat("bench-", heavy.triangleCount(), "-triangles"),
                  spread(makeBenchReceivers(heavySide), work.heavyPoints), options.seed, start);
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
                                             start))
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
        runConvergence(*context, bench, points, convergenceIds, work, options.seed, start);

    const Table accuracyT = accuracyTable(accuracy), scenesT = scenesTable(scenes),
                convergenceT = convergenceTable(convergence);
    std::printf("\nAccuracy, one pass (Fig. 7) and median times per sample (Fig. 9), bench scene.\n"
                "Errors |estimate - exact|: relative in %% of each point's unoccluded value, absolute in sr.\n"
                "Phase columns and timed_total with glFinish between phases; total_ms without (the real cost).\n\n%s",
                accuracyT.aligned().c_str());
    std::printf("\nTimings on larger scenes (median ms per sample; rendered_pct: samples that saw the light;\n"
                "drawn_triangles: mean occluder triangles drawn after culling).\n\n%s",
                scenesT.aligned().c_str());
    const Table raytraceT = raytraceTable(raytrace);
    std::printf("\nRay-traced peer (Embree shadow rays through the raster sampler's sample points, one core): at "
                "equal samples (same seeds) and at equal time per estimate; errors over %zu receivers.\n\n%s",
                raytrace.empty() ? size_t(0) : raytrace.front().errors.relative.count(), raytraceT.aligned().c_str());
    std::printf("\nConvergence: error of the mean of K passes at penumbra receivers "
                "(exact between %g%% and %g%% of unoccluded).\n\n%s",
                100 * kPenumbraLow, 100 * kPenumbraHigh, convergenceT.aligned().c_str());

    writeTextFileAtomically((dir / "direct_accuracy.csv").string(), accuracyT.csv());
    writeTextFileAtomically((dir / "direct_timing_scenes.csv").string(), scenesT.csv());
    writeTextFileAtomically((dir / "direct_convergence.csv").string(), convergenceT.csv());
    writeTextFileAtomically((dir / "direct_raytrace.csv").string(), raytraceT.csv());
    writePlots(dir, gnuplotScript(accuracy, convergence, points.points.size()));

    const RunInfo info{context->describe(), options.quick ? "quick" : "full", options.seed, points.points.size(),
                       points.skipped, secondsSince(start)};
    writeTextFileAtomically((dir / "direct_summary.md").string(),
                            summaryMarkdown(info, accuracy, heavyRows, convergence, raytrace));
    std::printf("\nRecommended for one pass: %s\nRecommended for progressive refinement: %s\nWall time %.1f s; files in %s\n",
                recommendationLine(accuracy).c_str(), efficiencyLine(accuracy).c_str(),
                info.wallSeconds, dir.string().c_str());
    return 0;
}

}  // namespace ml
