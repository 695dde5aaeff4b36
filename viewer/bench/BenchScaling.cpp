#include "BenchScaling.h"

#include "BenchRun.h"
#include "BenchStatistics.h"
#include "BenchTable.h"
#include "Gnuplot.h"
#include "PowerLawFit.h"

#include "cache/IrradianceCache.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/scenes/BenchScene.h"
#include "core/scenes/CornellBox.h"
#include "core/scenes/ScalingScene.h"
#include "gpu_sampling/direct/DirectLightSampler.h"
#include "gpu_sampling/direct/OccluderBvh.h"
#include "gpu_sampling/gl/GlContext.h"
#include "viewer/compositor/Compositor.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iterator>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace ml {

namespace {

// Seconds taken by `work`.
template <typename F>
double timed(F&& work) {
    const auto start = std::chrono::steady_clock::now();
    work();
    return secondsSince(start);
}

// --- Sizes of a run ------------------------------------------------------------

struct Workload {
    // Subdivision levels: the bench scene's 4 non-emissive triangles become
    // 4^(k+1) (k = 4: 1,026 triangles in all; k = 9: 1,048,578); the Cornell
    // box's 30 become 30·4^k (k = 3: 1,922; k = 7: 491,522).
    std::vector<int> benchLevels, cornellLevels;
    std::vector<int> lightCounts;
    size_t receivers;      // fixed receivers per scene, the same at every size
    size_t timedEstimates;  // estimates of the cache's first pass timed per size or light count
    int compositeSize;     // composited image, pixels per side (2×2 supersampled)
};

Workload workloadFor(const BenchOptions& options) {
    if (options.quick) return {{4, 5, 6, 7}, {3, 4, 5}, {1, 2, 4, 8}, 64, 96, 96};
    return {{4, 5, 6, 7, 8, 9}, {3, 4, 5, 6, 7}, {1, 2, 4, 8, 16, 32, 64}, 200, 400, 256};
}

// One-off costs are timed this many times and the median kept: a single
// timing of a few milliseconds is at the mercy of other processes.
constexpr int kOneOffRepeats = 3;

// Median seconds of kOneOffRepeats runs of `work`.
template <typename F>
double medianTimed(F&& work) {
    std::vector<double> t;
    for (int k = 0; k < kOneOffRepeats; ++k) t.push_back(timed(work));
    return median(std::move(t));
}

// --- Measuring -------------------------------------------------------------------

// One sample of light 0 at fixed receivers: medians per sample, in seconds.
struct ReceiverCost {
    double setup = 0, draw = 0, readback = 0, weighting = 0;  // phases, glFinish between them
    double total = 0;           // median total with phase timing off: the real cost
    double trianglesDrawn = 0;  // mean occluder triangles drawn per sample, after culling
};

// Two runs with the same seeds, as bench direct does: phase timing on (the
// split), then off, because the glFinish between phases inflates the total.
ReceiverCost measureReceivers(DirectLightSampler& sampler, const std::vector<ReceiverPoint>& points, uint32_t seed) {
    ReceiverCost c;
    std::vector<double> setup, draw, readback, weighting, total;
    double drawn = 0;
    for (const bool phaseTiming : {true, false}) {
        sampler.setPhaseTiming(phaseTiming);
        for (size_t i = 0; i < points.size(); ++i) {
            const DirectSample s = sampler.sample(0, points[i].position, points[i].normal, seedFor(seed, uint32_t(i)));
            const DirectPhaseTimes& t = sampler.lastTimes();
            if (!phaseTiming) {
                total.push_back(t.total());
                continue;
            }
            setup.push_back(t.setup);
            draw.push_back(t.draw);
            readback.push_back(t.readback);
            weighting.push_back(t.weighting);
            drawn += s.trianglesDrawn;
        }
    }
    sampler.setPhaseTiming(false);
    c.setup = median(setup);
    c.draw = median(draw);
    c.readback = median(readback);
    c.weighting = median(weighting);
    c.total = median(total);
    c.trianglesDrawn = points.empty() ? 0 : drawn / double(points.size());
    return c;
}

// `render`'s work up to its first complete image: build the cache, make one
// estimate at every mesh vertex and grid-cache sample of every light (the
// cache's first pass), composite. The estimates of the first pass are
// listed without sampling (IrradianceCache::sampleUnsampled with a
// recording function), then a fixed number of them, spread evenly through
// the list, are sampled for real and timed: the same points `render` would
// sample, at a cost that does not grow with the scene.
struct CacheCost {
    size_t vertices = 0;     // mesh vertices per light (grid-cache samples not included)
    size_t gridObjects = 0;  // objects cached on a grid instead of a mesh
    double build = 0;        // s, building the cache (all lights; median of kOneOffRepeats)
    size_t estimates = 0;    // estimates of the first pass, all lights
    size_t sampled = 0;      // of those, sampled and timed
    double perEstimate = 0;  // s, mean wall time of the timed estimates
    // s, one image from the cache (its views included, the compositor's
    // shaders and scene upload not: made beforehand); median of kOneOffRepeats.
    double composite = 0;

    // s, `render` to its first complete image: setup, cache build, every
    // estimate of the first pass at the measured mean cost, compositing.
    // Extrapolated from `sampled` estimates, not measured whole.
    double firstImage(double samplerSetup) const {
        return samplerSetup + build + perEstimate * double(estimates) + composite;
    }
};

CacheCost measureCache(GlContext& context, const Scene& scene, DirectLightSampler& sampler, size_t count,
                       int imageSize, uint32_t seed) {
    CacheCost c;
    std::unique_ptr<IrradianceCache> cache;
    c.build = medianTimed([&] {
        cache.reset();
        cache = std::make_unique<IrradianceCache>(scene);
    });
    c.vertices = cache->lightCount() ? cache->vertexCount(0) : 0;
    c.gridObjects = cache->gridObjectCount();

    struct Estimate {
        size_t light;
        Vec3 x, n;
        uint32_t seed;
    };
    std::vector<Estimate> pass;
    // The recorded estimates get a neutral value: compositing costs the same
    // whatever irradiance the cache holds.
    auto record = samplerOf([&](size_t l, const Vec3& x, const Vec3& n, uint32_t s) {
        pass.push_back({l, x, n, s});
        return VertexSample{};
    });
    cache->sampleUnsampled(record, seed);
    c.estimates = pass.size();
    const std::vector<Estimate> timedEstimates = spread(pass, count);
    c.sampled = timedEstimates.size();
    const double t = timed([&] {
        for (const Estimate& e : timedEstimates) sampler.sample(e.light, e.x, e.n, e.seed);
    });
    c.perEstimate = c.sampled ? t / double(c.sampled) : 0;

    CompositorSettings settings;
    settings.width = settings.height = imageSize;
    settings.supersample = 2;
    Compositor compositor(context, scene);
    c.composite = medianTimed([&] {
        std::vector<IrradianceMeshCopy> views = cache->copyMeshes();
        const ImageRgb image = compositor.render(scene.cameraOrDefault(1.0), views, settings);
        ML_ASSERT(image.width == imageSize, "composited width ", image.width);
    });
    return c;
}

struct TriangleRow {
    std::string scene;  // no commas
    int levels = 0;
    size_t triangles = 0;
    size_t receivers = 0;
    // One-off costs, s, medians of kOneOffRepeats.
    double bvh = 0;    // building the occluder BVH alone
    double setup = 0;  // sampler construction: shaders, BVH, upload
    ReceiverCost sample;
    CacheCost cache;
};

TriangleRow measureTriangles(GlContext& context, const Scene& scene, const std::string& family, int levels,
                             const std::vector<ReceiverPoint>& receivers, const Workload& work, uint32_t seed) {
    TriangleRow row;
    row.scene = family;
    row.levels = levels;
    row.triangles = scene.triangleCount();
    row.receivers = receivers.size();
    std::vector<Triangle3> all;
    all.reserve(scene.triangleCount());
    for (const Mesh& m : scene.meshes)
        for (size_t t = 0; t < m.triangles.size(); ++t) all.push_back(m.triangle(t));
    row.bvh = medianTimed([&] {
        const OccluderBvh bvh(all);
        ML_ASSERT(bvh.triangleCount() == all.size(), bvh.triangleCount(), " triangles in the BVH");
    });
    std::unique_ptr<DirectLightSampler> sampler;
    row.setup = medianTimed([&] {
        sampler.reset();
        sampler = std::make_unique<DirectLightSampler>(context, scene, DirectSamplerSettings{});
    });
    row.sample = measureReceivers(*sampler, receivers, seed);
    row.cache = measureCache(context, scene, *sampler, work.timedEstimates, work.compositeSize, seed);
    return row;
}

struct LightRow {
    int lights = 0;
    size_t triangles = 0;
    double setup = 0;  // s, sampler construction (median of kOneOffRepeats)
    CacheCost cache;
    // s, one cache vertex for every light: `lights` estimates.
    double perVertex() const { return cache.perEstimate * lights; }
};

LightRow measureLights(GlContext& context, int lights, const Workload& work, uint32_t seed) {
    const Scene scene = makeCornellLightGrid(lights);
    LightRow row;
    row.lights = lights;
    row.triangles = scene.triangleCount();
    std::unique_ptr<DirectLightSampler> sampler;
    row.setup = medianTimed([&] {
        sampler.reset();
        sampler = std::make_unique<DirectLightSampler>(context, scene, DirectSamplerSettings{});
    });
    row.cache = measureCache(context, scene, *sampler, work.timedEstimates, work.compositeSize, seed);
    return row;
}

// --- Fits ------------------------------------------------------------------------

struct FitRow {
    std::string sweep;     // "triangles" or "lights": the x of the fit
    std::string scene;     // scene family
    std::string quantity;  // a column of the sweep's CSV
    std::optional<PowerLawFit> fit;  // none when the values cannot be fitted
    std::string why;                 // then, the reason
};

FitRow fitColumn(const std::string& sweep, const std::string& scene, const std::string& quantity,
                 const std::vector<double>& x, const std::vector<double>& y) {
    FitRow row{sweep, scene, quantity, std::nullopt, {}};
    try {
        row.fit = fitPowerLaw(x, y);
    } catch (const std::invalid_argument& e) {
        row.why = e.what();
    }
    return row;
}

// The quantities of the triangle sweep, each fitted against triangles.
struct TriangleQuantity {
    const char* name;  // CSV column
    const char* label; // plot and summary label
    std::function<double(const TriangleRow&)> value;
};

const std::vector<TriangleQuantity>& triangleQuantities() {
    static const std::vector<TriangleQuantity> q = {
        {"per_sample_ms", "per sample at fixed receivers", [](const TriangleRow& r) { return 1e3 * r.sample.total; }},
        {"drawn_triangles", "occluder triangles drawn per sample",
         [](const TriangleRow& r) { return r.sample.trianglesDrawn; }},
        {"bvh_build_ms", "occluder BVH build", [](const TriangleRow& r) { return 1e3 * r.bvh; }},
        {"setup_ms", "sampler setup (shaders, BVH, upload)", [](const TriangleRow& r) { return 1e3 * r.setup; }},
        {"cache_build_ms", "cache build", [](const TriangleRow& r) { return 1e3 * r.cache.build; }},
        {"first_pass_estimates", "estimates of the cache's first pass",
         [](const TriangleRow& r) { return double(r.cache.estimates); }},
        {"per_estimate_ms", "per estimate of the cache's first pass",
         [](const TriangleRow& r) { return 1e3 * r.cache.perEstimate; }},
        {"composite_ms", "compositing one image", [](const TriangleRow& r) { return 1e3 * r.cache.composite; }},
        {"first_image_ms", "render to a first image (extrapolated)",
         [](const TriangleRow& r) { return 1e3 * r.cache.firstImage(r.setup); }},
    };
    return q;
}

struct LightQuantity {
    const char* name;
    const char* label;
    std::function<double(const LightRow&)> value;
};

const std::vector<LightQuantity>& lightQuantities() {
    static const std::vector<LightQuantity> q = {
        {"per_vertex_ms", "per cache vertex, all lights", [](const LightRow& r) { return 1e3 * r.perVertex(); }},
        {"per_estimate_ms", "per estimate (one vertex, one light)",
         [](const LightRow& r) { return 1e3 * r.cache.perEstimate; }},
        {"setup_ms", "sampler setup", [](const LightRow& r) { return 1e3 * r.setup; }},
        {"cache_build_ms", "cache build", [](const LightRow& r) { return 1e3 * r.cache.build; }},
        {"composite_ms", "compositing one image", [](const LightRow& r) { return 1e3 * r.cache.composite; }},
        {"first_image_ms", "render to a first image (extrapolated)",
         [](const LightRow& r) { return 1e3 * r.cache.firstImage(r.setup); }},
    };
    return q;
}

std::vector<std::string> families(const std::vector<TriangleRow>& rows) {
    std::vector<std::string> out;
    for (const TriangleRow& r : rows)
        if (std::find(out.begin(), out.end(), r.scene) == out.end()) out.push_back(r.scene);
    return out;
}

std::vector<FitRow> fitAll(const std::vector<TriangleRow>& triangles, const std::vector<LightRow>& lights) {
    std::vector<FitRow> fits;
    for (const std::string& family : families(triangles))
        for (const TriangleQuantity& q : triangleQuantities()) {
            std::vector<double> x, y;
            for (const TriangleRow& r : triangles)
                if (r.scene == family) {
                    x.push_back(double(r.triangles));
                    y.push_back(q.value(r));
                }
            fits.push_back(fitColumn("triangles", family, q.name, x, y));
        }
    for (const LightQuantity& q : lightQuantities()) {
        std::vector<double> x, y;
        for (const LightRow& r : lights) {
            x.push_back(double(r.lights));
            y.push_back(q.value(r));
        }
        fits.push_back(fitColumn("lights", "cornell-light-grid", q.name, x, y));
    }
    return fits;
}

const FitRow* findFit(const std::vector<FitRow>& fits, const std::string& sweep, const std::string& scene,
                      const std::string& quantity) {
    for (const FitRow& f : fits)
        if (f.sweep == sweep && f.scene == scene && f.quantity == quantity) return &f;
    return nullptr;
}

std::string exponentText(const FitRow* f) {
    return f && f->fit ? benchNumber(f->fit->exponent) : std::string("n/a");
}

// --- Tables ------------------------------------------------------------------------

BenchTable trianglesTable(const std::vector<TriangleRow>& rows) {
    BenchTable t({"scene", "levels", "triangles", "receivers", "drawn_triangles", "bvh_build_ms", "setup_ms",
                  "sample_setup_ms", "sample_draw_ms", "sample_readback_ms", "sample_weighting_ms", "per_sample_ms",
                  "cache_vertices", "grid_objects", "cache_build_ms", "first_pass_estimates", "timed_estimates",
                  "per_estimate_ms", "composite_ms", "first_image_ms"});
    for (const TriangleRow& r : rows)
        t.addRow({r.scene, std::to_string(r.levels), std::to_string(r.triangles), std::to_string(r.receivers),
                  benchNumber(r.sample.trianglesDrawn), benchMs(r.bvh), benchMs(r.setup), benchMs(r.sample.setup),
                  benchMs(r.sample.draw), benchMs(r.sample.readback), benchMs(r.sample.weighting),
                  benchMs(r.sample.total), std::to_string(r.cache.vertices), std::to_string(r.cache.gridObjects),
                  benchMs(r.cache.build), std::to_string(r.cache.estimates), std::to_string(r.cache.sampled),
                  benchMs(r.cache.perEstimate), benchMs(r.cache.composite), benchMs(r.cache.firstImage(r.setup))});
    return t;
}

BenchTable lightsTable(const std::vector<LightRow>& rows) {
    BenchTable t({"lights", "triangles", "setup_ms", "cache_vertices", "cache_build_ms", "first_pass_estimates",
                  "timed_estimates", "per_estimate_ms", "per_vertex_ms", "composite_ms", "first_image_ms"});
    for (const LightRow& r : rows)
        t.addRow({std::to_string(r.lights), std::to_string(r.triangles), benchMs(r.setup),
                  std::to_string(r.cache.vertices), benchMs(r.cache.build), std::to_string(r.cache.estimates),
                  std::to_string(r.cache.sampled), benchMs(r.cache.perEstimate), benchMs(r.perVertex()),
                  benchMs(r.cache.composite), benchMs(r.cache.firstImage(r.setup))});
    return t;
}

BenchTable fitsTable(const std::vector<FitRow>& fits) {
    BenchTable t({"sweep", "scene", "quantity", "exponent", "coefficient", "r2", "points"});
    for (const FitRow& f : fits) {
        if (f.fit)
            t.addRow({f.sweep, f.scene, f.quantity, benchNumber(f.fit->exponent), benchNumber(f.fit->coefficient),
                      benchNumber(f.fit->r2), std::to_string(f.fit->points)});
        else
            t.addRow({f.sweep, f.scene, f.quantity, "n/a", "n/a", "n/a", "0"});
    }
    return t;
}

// --- Plots --------------------------------------------------------------------------

const std::vector<GnuplotOutput> kPlots = {
    {"out_sample", "scaling_triangles_sample.png"},
    {"out_setup", "scaling_triangles_setup.png"},
    {"out_lights", "scaling_lights.png"},
};

// "per sample at fixed receivers, bench (∝ n^{0.93})": a plot title in
// gnuplot's enhanced text (quote it with gnuplotQuoted).
std::string seriesTitle(const std::string& label, const FitRow* fit, const char* x) {
    std::string t = label;
    if (fit && fit->fit) t += concat(" (∝ ", x, "^{", benchNumber(fit->fit->exponent), "})");
    return t;
}

// Distinct on white and in grey print; gnuplot's default fifth colour
// (yellow) is hard to read.
const char* const kColours[] = {"#1f5fa8", "#c0392b", "#27914a", "#8e44ad", "#d68910", "#5d6d7e", "#17a2b8"};

// Plots one column of a data block with its fitted line in the same colour.
std::string seriesWithFit(const std::string& block, int column, int colour, int point, const std::string& title,
                          const FitRow* fit) {
    const char* rgb = kColours[size_t(colour - 1) % std::size(kColours)];
    std::string s = concat(block, " using 1:", column, " with linespoints lc rgb '", rgb, "' pt ", point,
                           " ps 1.3 title ", gnuplotQuoted(title));
    if (fit && fit->fit)
        s += concat(", ", benchNumber(fit->fit->coefficient), "*x**", fit->fit->exponent, " with lines lc rgb '", rgb,
                    "' dt 2 notitle");
    return s;
}

std::string gnuplotScript(const std::vector<TriangleRow>& triangles, const std::vector<LightRow>& lights,
                          const std::vector<FitRow>& fits, const Workload& work) {
    std::ostringstream gp;
    gp << "# Written by 'meshlight bench scaling'; run with gnuplot in this folder.\n"
       << gnuplotOutputDefaults(kPlots)
       << "set terminal pngcairo enhanced size 1200,800 font ',11'\n"
          "set datafile separator ','\n"
          "set grid\n"
          "set logscale xy\n"
          "set key below left Left reverse\n\n";
    const std::vector<std::string> fams = families(triangles);
    const std::vector<TriangleQuantity>& tq = triangleQuantities();
    for (size_t f = 0; f < fams.size(); ++f) {
        gp << "# triangles";
        for (const TriangleQuantity& q : tq) gp << ", " << q.name;
        gp << "\n$tri" << f << " << EOD\n";
        for (const TriangleRow& r : triangles) {
            if (r.scene != fams[f]) continue;
            gp << r.triangles;
            for (const TriangleQuantity& q : tq) gp << "," << benchNumber(q.value(r));
            gp << "\n";
        }
        gp << "EOD\n";
    }
    const std::vector<LightQuantity>& lq = lightQuantities();
    gp << "# lights";
    for (const LightQuantity& q : lq) gp << ", " << q.name;
    gp << "\n$lights << EOD\n";
    for (const LightRow& r : lights) {
        gp << r.lights;
        for (const LightQuantity& q : lq) gp << "," << benchNumber(q.value(r));
        gp << "\n";
    }
    gp << "EOD\n\n";

    auto column = [&](const char* name) {
        for (size_t i = 0; i < tq.size(); ++i)
            if (std::string(tq[i].name) == name) return int(i) + 2;
        ML_ASSERT(false, "no triangle quantity ", name);
        return 0;
    };
    // Colour per quantity, point type per scene.
    auto triangleSeries = [&](const std::vector<const char*>& names) {
        std::vector<std::string> parts;
        for (size_t n = 0; n < names.size(); ++n)
            for (size_t f = 0; f < fams.size(); ++f) {
                const FitRow* fit = findFit(fits, "triangles", fams[f], names[n]);
                const auto it = std::find_if(tq.begin(), tq.end(), [&](const TriangleQuantity& q) {
                    return std::string(q.name) == names[n];
                });
                parts.push_back(seriesWithFit(concat("$tri", f), column(names[n]), int(n) + 1, f == 0 ? 7 : 5,
                                              seriesTitle(concat(it->label, ", ", fams[f]), fit, "n"), fit));
            }
        std::string s;
        for (size_t i = 0; i < parts.size(); ++i) s += (i ? ", \\\n     " : "plot ") + parts[i];
        return s + "\n\n";
    };

    size_t fewest = 0, most = 0;
    for (const TriangleRow& r : triangles) {
        fewest = fewest ? std::min(fewest, r.triangles) : r.triangles;
        most = std::max(most, r.triangles);
    }
    gp << "set xrange [" << double(fewest) / 1.25 << ":" << double(most) * 1.25 << "]\n"
          "set format x '10^{%T}'\n"
          "set format y '10^{%T}'\n\n";
    gp << "set output out_sample\n"
          "set title 'Direct light, one light: cost per sample against scene size (dashed: least-squares fits)'\n"
          "set xlabel 'triangles in the scene, n'\n"
          "set ylabel 'ms'\n"
       << triangleSeries({"per_sample_ms", "per_estimate_ms"});

    gp << "set output out_setup\n"
          "set title 'One-off costs against scene size (compositing: " << work.compositeSize << "^2 pixels, "
          "2x2 supersampled)'\n"
       << triangleSeries({"bvh_build_ms", "setup_ms", "cache_build_ms", "composite_ms"});

    gp << "set output out_lights\n"
          "set title 'Cornell box with N ceiling lights of constant total power (" << work.timedEstimates
       << " estimates timed per N)'\n"
          "set xlabel 'lights, N'\n"
          "set logscale x 2\n"
          "set format x '%g'\n"
          "set xrange [0.8:" << (lights.empty() ? 2 : lights.back().lights) * 1.25 << "]\n";
    std::vector<std::string> parts;
    for (size_t i = 0; i < lq.size(); ++i) {
        const FitRow* fit = findFit(fits, "lights", "cornell-light-grid", lq[i].name);
        parts.push_back(seriesWithFit("$lights", int(i) + 2, int(i) + 1, 7, seriesTitle(lq[i].label, fit, "N"), fit));
    }
    for (size_t i = 0; i < parts.size(); ++i) gp << (i ? ", \\\n     " : "plot ") << parts[i];
    gp << "\n";
    return gp.str();
}

// --- Summary --------------------------------------------------------------------------

std::string summaryMarkdown(const BenchRun& run, double wallSeconds, const Workload& work,
                            const std::vector<TriangleRow>& triangles, const std::vector<LightRow>& lights,
                            const std::vector<FitRow>& fits) {
    std::ostringstream md;
    md << "# Scaling bench: cost against scene size and number of lights\n\n"
       << "- OpenGL: " << run.glDescription() << "\n"
       << "- mode: " << run.mode() << ", seed " << run.options().seed
       << ", sampler: default settings (jittered 64×64, 8 bits, cv)\n"
       << "- fixed receivers per scene: " << work.receivers
       << "; estimates of the cache's first pass timed: " << work.timedEstimates
       << "; composited image " << work.compositeSize << "×" << work.compositeSize << ", 2×2 supersampled\n"
       << "- wall time: " << benchNumber(wallSeconds) << " s\n"
       << softwareRasteriserNote(run.glDescription());

    BenchTable growth({"sweep", "scene", "quantity", "from", "to", "b", "r²"});
    for (const FitRow& f : fits) {
        std::string from, to;
        if (f.sweep == "triangles") {
            std::vector<size_t> n;
            for (const TriangleRow& r : triangles)
                if (r.scene == f.scene) n.push_back(r.triangles);
            if (!n.empty()) from = concat(n.front(), " triangles"), to = concat(n.back(), " triangles");
        } else if (!lights.empty()) {
            from = concat(lights.front().lights, lights.front().lights == 1 ? " light" : " lights");
            to = concat(lights.back().lights, lights.back().lights == 1 ? " light" : " lights");
        }
        growth.addRow({f.sweep, f.scene, f.quantity, from, to, exponentText(&f),
                       f.fit ? benchNumber(f.fit->r2) : std::string("n/a")});
    }
    md << "\n## Growth exponents (cost ≈ a·x^b, least squares in log-log)\n\n" << growth.markdown();
    md << "\nb = 1 is linear growth, b = 0 a constant cost. The sampler culls occluders with a BVH, so the cost "
          "per sample follows the triangles drawn after culling (drawn_triangles), not the scene's size; the "
          "bench scene's occluder faces every shadowed receiver (nothing to cull), the Cornell box hides most of "
          "its triangles from any one receiver.\n\nTables: scaling_triangles.csv, scaling_lights.csv, "
          "scaling_fits.csv. Per-sample times are medians with phase timing off (the phase columns are medians "
          "with glFinish between phases). The cache's first pass (one estimate at every mesh vertex and "
          "grid-cache sample of every light: first_pass_estimates) is listed without sampling, and a fixed number "
          "of its estimates, spread evenly through it (timed_estimates), are sampled and timed: per_estimate is "
          "their mean wall time, per_vertex (lights) that times the number of lights. Objects with many small "
          "triangles are cached on a grid (grid_objects), so the first pass need not grow with the triangles. "
          "first_image is extrapolated, not measured whole: sampler setup + cache build + per_estimate × "
          "first_pass_estimates + compositing, what `render` takes to its first complete image. One-off costs "
          "(BVH, sampler setup, cache build, compositing) are medians of 3 runs.\n";
    return md.str();
}

}  // namespace

int runBenchScaling(const BenchOptions& options) {
    BenchRun run(options);
    const Workload work = workloadFor(options);
    const std::unique_ptr<GlContext> context = run.openContext();

    // The receivers are placed on the base scenes: subdivision does not move
    // a surface, so they are the same points at every size.
    const int side = int(std::ceil(std::sqrt(double(work.receivers))));
    const std::vector<ReceiverPoint> benchReceivers = spread(makeBenchReceivers(side), work.receivers);
    const Scene cornell = makeCornellBox();
    const std::vector<ReceiverPoint> cornellReceivers = surfaceReceivers(cornell, work.receivers, options.seed);

    // Warm-up, untimed: the first shader compilations and allocations of a
    // process are slower than any later one and would bend the smallest size.
    {
        const Scene warm = makeBenchScene();
        DirectLightSampler sampler(*context, warm, DirectSamplerSettings{});
        measureCache(*context, warm, sampler, 8, 16, options.seed);
    }

    std::vector<TriangleRow> triangles;
    auto sweep = [&](const Scene& base, const std::string& family, const std::vector<int>& levels,
                     const std::vector<ReceiverPoint>& receivers) {
        for (int k : levels) {
            const Scene scene = subdivideScene(base, k);
            run.progress("triangles: %s, %zu triangles\n", family.c_str(), scene.triangleCount());
            triangles.push_back(measureTriangles(*context, scene, family, k, receivers, work, options.seed));
        }
    };
    sweep(makeBenchScene(), "bench", work.benchLevels, benchReceivers);
    sweep(cornell, "cornell", work.cornellLevels, cornellReceivers);

    std::vector<LightRow> lights;
    for (int n : work.lightCounts) {
        run.progress("lights: %d\n", n);
        lights.push_back(measureLights(*context, n, work, options.seed));
    }

    const std::vector<FitRow> fits = fitAll(triangles, lights);
    const BenchTable triT = trianglesTable(triangles), lightT = lightsTable(lights), fitT = fitsTable(fits);
    std::printf("\nCost against scene size (ms; per_sample: median at fixed receivers, phase timing off;\n"
                "sample_*: median phases with glFinish; per_estimate: mean wall time over the timed estimates\n"
                "of the cache's first pass; first_image: extrapolated to the whole first pass).\n\n%s",
                triT.aligned().c_str());
    std::printf("\nCost against the number of lights (Cornell box, constant total power; ms).\n\n%s",
                lightT.aligned().c_str());
    std::printf("\nGrowth exponents b of cost = a * x^b (least squares in log-log).\n\n%s", fitT.aligned().c_str());

    run.writeCsv("scaling_triangles.csv", triT);
    run.writeCsv("scaling_lights.csv", lightT);
    run.writeCsv("scaling_fits.csv", fitT);
    run.plot("scaling_plots.gp", gnuplotScript(triangles, lights, fits, work), kPlots);
    const double wall = run.seconds();
    run.write("scaling_summary.md", summaryMarkdown(run, wall, work, triangles, lights, fits));
    std::printf("\nper-sample exponent: bench %s, cornell %s; per-vertex exponent against lights: %s\n",
                exponentText(findFit(fits, "triangles", "bench", "per_sample_ms")).c_str(),
                exponentText(findFit(fits, "triangles", "cornell", "per_sample_ms")).c_str(),
                exponentText(findFit(fits, "lights", "cornell-light-grid", "per_vertex_ms")).c_str());
    run.printWallTime(wall);
    return 0;
}

}  // namespace ml
