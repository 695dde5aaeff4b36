// meshlight probe: irradiance at sensor points (RADIANCE's `rtrace -I`),
// what lighting designers check: direct light per light, indirect light,
// and the illuminance in lux. Points come from a CSV file, or, with
// `--points -`, as RADIANCE's rtrace reads them: "x y z dx dy dz" lines on
// standard input.
#include "Commands.h"
#include "PhotometryOptions.h"
#include "Plan.h"
#include "Progress.h"
#include "SamplerOptions.h"
#include "gpu_sampling/gl/GlContext.h"
#include "cache/ProgressiveSession.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/io/AtomicFile.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "gpu_sampling/direct/RayTracedLightSampler.h"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>

namespace ml {

namespace {

struct SensorPoint {
    Vec3 position, normal;
};

std::vector<std::string> splitCsv(const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) {
        const size_t a = cell.find_first_not_of(" \t\r"), b = cell.find_last_not_of(" \t\r");
        cells.push_back(a == std::string::npos ? std::string() : cell.substr(a, b - a + 1));
    }
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    return cells;
}

// One coordinate of a points file: a finite number, else an error naming
// the line and the column.
double finiteValue(const std::string& text, const SourceLocation& at, const char* column) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || !std::isfinite(v))
        throwInputError(at, "column ", column, ": '", text, "' is not a finite number");
    return v;
}

// A point from its six values, in the order of `columns`; the normal is normalised.
SensorPoint sensorPoint(const std::vector<std::string>& cells, const SourceLocation& at,
                        const std::array<const char*, 6>& columns) {
    double v[6];
    for (size_t k = 0; k < 6; ++k) v[k] = finiteValue(cells[k], at, columns[k]);
    const Vec3 n(v[3], v[4], v[5]);
    if (!(glm::length(n) > 0)) throwInputError(at, "the normal is zero");
    return {Vec3(v[0], v[1], v[2]), glm::normalize(n)};
}

// A CSV file with the header x,y,z,nx,ny,nz.
std::vector<SensorPoint> readCsvPoints(const std::string& path) {
    std::ifstream in(path);
    if (!in) throwInputError(SourceLocation{path}, "cannot open the points file");
    std::string line;
    int lineNo = 0;
    std::vector<SensorPoint> points;
    bool header = false;
    const std::array<const char*, 6> columns = {"x", "y", "z", "nx", "ny", "nz"};
    const std::vector<std::string> expected(columns.begin(), columns.end());
    while (std::getline(in, line)) {
        ++lineNo;
        if (line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t")] == '#')
            continue;
        const std::vector<std::string> cells = splitCsv(line);
        const SourceLocation at{path, lineNo};
        if (!header) {
            if (cells != expected) throwInputError(at, "the header must be x,y,z,nx,ny,nz");
            header = true;
            continue;
        }
        if (cells.size() != 6) throwInputError(at, "expected 6 values, found ", cells.size());
        points.push_back(sensorPoint(cells, at, columns));
    }
    if (!header) throwInputError(SourceLocation{path}, "empty file: expected the header x,y,z,nx,ny,nz");
    return points;
}

// RADIANCE's rtrace input: a point and a direction a line, "x y z dx dy dz",
// separated by white space; blank lines and '#' comments (to the end of the
// line) are skipped.
std::vector<SensorPoint> readRadiancePoints(std::istream& in, const std::string& name) {
    std::string line;
    int lineNo = 0;
    std::vector<SensorPoint> points;
    const std::array<const char*, 6> columns = {"x", "y", "z", "dx", "dy", "dz"};
    while (std::getline(in, line)) {
        ++lineNo;
        std::istringstream words(line.substr(0, line.find('#')));
        std::vector<std::string> cells;
        for (std::string w; words >> w;) cells.push_back(w);
        if (cells.empty()) continue;
        const SourceLocation at{name, lineNo};
        if (cells.size() != 6) throwInputError(at, "expected 6 numbers (x y z dx dy dz), found ", cells.size());
        points.push_back(sensorPoint(cells, at, columns));
    }
    if (points.empty()) throwInputError(SourceLocation{name}, "no points: expected lines of x y z dx dy dz");
    return points;
}

// `--points -`: RADIANCE's format on standard input; else a CSV file.
std::vector<SensorPoint> readPoints(const std::string& path) {
    return path == "-" ? readRadiancePoints(std::cin, "<stdin>") : readCsvPoints(path);
}

// Light names as CSV column names: letters, digits and '_' only.
std::string columnName(const std::string& name) {
    std::string s;
    for (char c : name) s += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    return s;
}

// Whether the user wrote --name (with or without "=value"): Options reports
// defaults as set, and the CPU methods refuse options they would ignore.
bool written(const std::vector<std::string>& args, const std::string& name) {
    for (const std::string& a : args)
        if (a == "--" + name || a.rfind("--" + name + "=", 0) == 0) return true;
    return false;
}

void refuseOptions(const std::vector<std::string>& args, const std::string& method,
                   std::initializer_list<const char*> names) {
    for (const char* name : names)
        if (written(args, name))
            throw InputError(concat("option --", name, " does not apply to --method ", method));
}

std::string csvHeader(const Scene& scene) {
    std::string h = "x,y,z,nx,ny,nz";
    for (const Light& l : scene.lights) {
        const std::string c = columnName(l.name);
        h += ",E_" + c + "_r,E_" + c + "_g,E_" + c + "_b";
    }
    return h + ",E_r,E_g,E_b";
}

void csvRgb(std::ostringstream& csv, const Rgb& c) { csv << "," << c.r << "," << c.g << "," << c.b; }

// The lux columns: "lux", the illuminance of all the light computed, and
// with indirect light "lux_indirect", its indirect part.
const char* luxHeader(bool indirect) { return indirect ? ",lux,lux_indirect" : ",lux"; }
void csvLux(std::ostringstream& csv, const Photometry& photometry, const Rgb& direct, const Rgb* indirect) {
    csv << "," << photometry.luminous(indirect ? direct + *indirect : direct);
    if (indirect) csv << "," << photometry.luminous(*indirect);
}

void csvPoint(std::ostringstream& csv, const SensorPoint& p) {
    csv << p.position.x << "," << p.position.y << "," << p.position.z << "," << p.normal.x << "," << p.normal.y << ","
        << p.normal.z;
}

// --method path: the path tracer's irradiance, direct (per light and in all,
// the columns every method writes) and indirect, each with its standard error.
int probePath(const Options& o, const std::vector<std::string>& args, const std::vector<SensorPoint>& points,
              const Scene& scene, const std::string& out) {
    refuseOptions(args, "path", {"estimator", "image-size", "bits", "passes", "gl"});
    PathTracerSettings settings;
    settings.maxDepth = o.has("max-depth") ? o.integer("max-depth", 1, 1024) : 8;
    settings.threads = o.has("threads") ? o.integer("threads", 0, 1024) : 0;
    settings.seed = o.seed("seed");
    const int spp = o.has("spp") ? o.integer("spp", 2, 1 << 24) : 1024;
    const Photometry photometry = readPhotometryOption(o);
    const EmbreeScene rays(scene);
    const PathTracer tracer(rays, settings);

    std::ostringstream csv;
    csv.precision(9);
    csv << csvHeader(scene) << ",E_se_r,E_se_g,E_se_b,E_indirect_r,E_indirect_g,E_indirect_b,"
        << "E_indirect_se_r,E_indirect_se_g,E_indirect_se_b" << luxHeader(true) << ",method,samples,max_depth,time_s\n";
    Progress progress("probe", points.size());
    double relative = 0;
    size_t lit = 0;
    for (size_t i = 0; i < points.size(); ++i) {
        const SensorPoint& p = points[i];
        const auto t0 = std::chrono::steady_clock::now();
        const IrradianceEstimate e = tracer.irradiance(p.position, p.normal, spp, uint32_t(i));
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        csvPoint(csv, p);
        for (const Rgb& l : e.directPerLight) csvRgb(csv, l);
        csvRgb(csv, e.direct);
        csvRgb(csv, e.directError);
        csvRgb(csv, e.indirect);
        csvRgb(csv, e.indirectError);
        csvLux(csv, photometry, e.direct, &e.indirect);
        csv << ",path," << spp << "," << settings.maxDepth << "," << seconds << "\n";
        const Rgb total = e.direct + e.indirect;
        if (luminance(total) > 0) {
            relative += luminance(glm::sqrt(e.directError * e.directError + e.indirectError * e.indirectError)) /
                        luminance(total);
            ++lit;
        }
        progress.update(i + 1);
    }
    progress.finish();
    writeTextFileAtomically(out, csv.str());
    std::printf("wrote %s (%zu points, %zu lights, path tracer: %d samples per point, max depth %d, seed %u)\n",
                out.c_str(), points.size(), scene.lights.size(), spp, settings.maxDepth, settings.seed);
    if (lit) std::printf("mean relative standard error of the total irradiance: %.3g %% over %zu lit points\n",
                         100 * relative / double(lit), lit);
    return 0;
}

// --method raytrace: the ray-traced peer of the jittered sampler (same
// frusta, jitter and estimators, Embree shadow rays instead of rasterising).
int probeRaytrace(const Options& o, const std::vector<std::string>& args, const std::vector<SensorPoint>& points,
                  const Scene& scene, const std::string& out) {
    refuseOptions(args, "raytrace", {"gl", "spp", "max-depth", "threads"});
    DirectSamplerSettings settings;
    settings.method = DirectMethod::Jittered;
    settings.estimator = parseDirectEstimator(o.str("estimator"));
    settings.imageSize = o.integer("image-size", 4, 1024);
    settings.bits = o.integer("bits", 1, 32);
    settings.validate();
    const int passes = o.integer("passes", 1, 1 << 20);
    const uint32_t seed = o.seed("seed");
    const Photometry photometry = readPhotometryOption(o);
    const EmbreeScene rays(scene);
    const RayTracedLightSampler sampler(rays, settings);

    std::ostringstream csv;
    csv.precision(9);
    csv << csvHeader(scene) << luxHeader(false) << ",method,samples,time_s\n";
    Progress progress("probe", points.size());
    for (size_t i = 0; i < points.size(); ++i) {
        const SensorPoint& p = points[i];
        const auto t0 = std::chrono::steady_clock::now();
        std::vector<Rgb> perLight(scene.lights.size(), Rgb(0.0));
        for (size_t l = 0; l < scene.lights.size(); ++l) {
            // The raster sampler's seeds, so both draw the same jitter.
            for (int k = 0; k < passes; ++k)
                perLight[l] += sampler.sample(l, p.position, p.normal,
                                              seedFor(seed, uint32_t(i), uint32_t(l), uint32_t(k))).irradiance;
            perLight[l] /= double(passes);
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        Rgb total(0.0);
        csvPoint(csv, p);
        for (const Rgb& e : perLight) {
            csvRgb(csv, e);
            total += e;
        }
        csvRgb(csv, total);
        csvLux(csv, photometry, total, nullptr);
        csv << ",raytrace," << passes * int(scene.lights.size()) << "," << seconds << "\n";
        progress.update(i + 1);
    }
    progress.finish();
    writeTextFileAtomically(out, csv.str());
    std::printf("wrote %s (%zu points, %zu lights, raytrace %dx%d, %d bits/pixel, %s estimator, %d %s)\n",
                out.c_str(), points.size(), scene.lights.size(), settings.imageSize, settings.imageSize,
                settings.bits, directEstimatorName(settings.estimator), passes, passes == 1 ? "pass" : "passes");
    return 0;
}

// Indirect irradiance at the points, as render computes it: the direct
// caches are refined (with bounce after bounce of indirect caches) on the
// worker until converged or `seconds`; then, bounce by bounce, each point
// gathers from the source the bounce's cache gathered from (the direct
// meshes for bounce 1, bounce n−1's mesh for bounce n), `passes` jittered
// gathers averaged. Returns one sum over the bounces per point.
std::vector<Rgb> probeIndirect(const Scene& scene, const DirectChoice& choice, const CacheSettings& cacheSettings,
                               const IndirectChoice& indirect, const std::vector<SensorPoint>& points,
                               std::optional<double> seconds) {
    std::vector<Rgb> sum(points.size(), Rgb(0.0));
    if (indirect.solver.bounces == 0) return sum;
    SessionSettings settings;
    settings.cache = cacheSettings;
    settings.worker.seed = choice.seed;
    settings.indirect = indirect.solver;
    ProgressiveSession session(scene, settings, samplerFactory(scene, choice, indirect));
    session.start();
    {
        CacheWorker::Reader reader = session.reader();
        StopRule stop;
        stop.seconds = seconds;
        session.refineUntil(reader, stop, 0, 0.25, [](const CacheSnapshot& s) {
            std::fprintf(stderr, "\rprobe: refining the caches: %zu vertices, bounces %d/%d   ", s.vertices,
                         s.bouncesFinished, s.bounces);
        });
        session.stop();
        session.rethrowIfFailed();
        std::fprintf(stderr, "\n");
    }
    const IrradianceCache& cache = session.cache();
    const IndirectSolver& solver = *session.indirect();
    std::unique_ptr<GlContext> context = createHeadlessContext(choice.backend);
    std::unique_ptr<IndirectEstimator> estimator = makeIndirectEstimator(*context, scene, indirect);
    Progress progress("probe: gathering", points.size() * size_t(solver.started()));
    for (int b = 1; b <= solver.started(); ++b) {
        std::vector<IrradianceMeshCopy> source;
        if (b == 1)
            source = cache.copyMeshes();
        else
            source.push_back(solver.copyMesh(b - 1));
        estimator->setSource(0, source);
        for (size_t i = 0; i < points.size(); ++i) {
            Rgb e(0.0);
            for (int k = 0; k < choice.passes; ++k)
                e += estimator->estimate(0, points[i].position, points[i].normal,
                                         seedFor(choice.seed, uint32_t(i), 0x1d1ec7u + uint32_t(b), uint32_t(k)));
            sum[i] += e / double(choice.passes);
            progress.update(size_t(b - 1) * points.size() + i + 1);
        }
    }
    progress.finish();
    if (solver.started() < solver.bounces())
        std::fprintf(stderr, "warning: only %d of %d bounces were reached in the time given\n", solver.started(),
                     solver.bounces());
    return sum;
}

}  // namespace

int runProbe(const std::vector<std::string>& args) {
    Options o("probe");
    o.positional("scene", kSceneArgumentHelp);
    o.value("points", "IN.csv|-", "sensor points: a CSV file with columns x,y,z,nx,ny,nz, or - for RADIANCE's rtrace "
                                  "input on standard input: lines of x y z dx dy dz ('#' comments)");
    o.value("out", "OUT.csv", "irradiance per light and in total (RGB, W/m²), and illuminance: lux (all the light "
                              "computed) and lux_indirect (its indirect part, when indirect light is computed)");
    declarePhotometryOption(o);
    declareDirectOptions(o);
    // The CPU references (--method path: the path tracer; --method raytrace:
    // the jittered sampler with shadow rays) and their own options.
    o.value("spp", "N", "--method path: cosine-weighted directions per point, each with one sample of every "
                        "light (default 1024)");
    o.value("max-depth", "D", "--method path: 1 = direct light only, D = direct + D-1 indirect bounces (default 8)");
    o.value("threads", "T", "--method path: worker threads, 0 = every core (default 0)");
    // GPU and exact direct light: indirect light as render computes it.
    o.flag("direct-only", "GPU and exact methods: direct light only (no E_indirect columns)");
    o.value("time", "S", "GPU and exact methods: refine the caches for at most S seconds before gathering");
    declareCacheOptions(o);
    declareIndirectOptions(o);
    if (!o.parseOrPrintHelp(args)) return 0;
    const std::string out = o.str("out");
    checkOutputDirectory(out);
    const std::string methodName = o.str("method");
    if (methodName == "path" || methodName == "raytrace") {
        refuseOptions(args, methodName,
                      {"direct-only", "time", "bounces", "indirect-tolerance", "max-bounces", "indirect-method", "voxels",
                       "gather-size", "near-voxels", "slice-supersample", "cache-edge", "min-edge", "min-edge-pixels",
                       "split-tolerance", "noise-tolerance", "max-vertices"});
        const std::vector<SensorPoint> points = readPoints(o.str("points"));
        const Scene scene = loadSceneArgument(o.positionalValue("scene"));
        for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
        return methodName == "path" ? probePath(o, args, points, scene, out) : probeRaytrace(o, args, points, scene, out);
    }
    refuseOptions(args, methodName, {"spp", "max-depth", "threads"});
    const DirectChoice choice = readDirectOptions(o);
    const CacheSettings cacheSettings = readCacheSettings(o);
    IndirectChoice indirect = readIndirectOptions(o);
    const Photometry photometry = readPhotometryOption(o);
    std::optional<double> timeLimit;
    if (o.has("time")) timeLimit = o.number("time", 0, 1e7);
    const std::vector<SensorPoint> points = readPoints(o.str("points"));
    const Scene scene = loadSceneArgument(o.positionalValue("scene"));
    for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    indirect.decide(scene);
    if (indirect.enabled) std::printf("indirect light: %s\n", indirect.bounceCount.reason.c_str());
    const std::vector<Rgb> indirectAt = indirect.enabled ? probeIndirect(scene, choice, cacheSettings, indirect, points, timeLimit)
                                                         : std::vector<Rgb>{};

    ConfiguredDirectSampler sampler(scene, choice);

    std::ostringstream csv;
    csv.precision(9);
    csv << csvHeader(scene) << (indirect.enabled ? ",E_indirect_r,E_indirect_g,E_indirect_b" : "")
        << luxHeader(indirect.enabled) << ",method,samples,time_s\n";
    const std::string method = choice.exact ? std::string("exact") : directMethodName(choice.sampler.method);

    Progress progress("probe", points.size());
    for (size_t i = 0; i < points.size(); ++i) {
        const SensorPoint& p = points[i];
        const auto t0 = std::chrono::steady_clock::now();
        std::vector<Rgb> perLight(scene.lights.size(), Rgb(0.0));
        for (size_t l = 0; l < scene.lights.size(); ++l) {
            for (int k = 0; k < choice.passes; ++k)
                perLight[l] +=
                    sampler.sample(l, p.position, p.normal, seedFor(choice.seed, uint32_t(i), uint32_t(l), uint32_t(k)))
                        .irradiance;
            perLight[l] /= double(choice.passes);
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        Rgb total(0.0);
        csvPoint(csv, p);
        for (const Rgb& e : perLight) {
            csvRgb(csv, e);
            total += e;
        }
        csvRgb(csv, total);
        if (indirect.enabled) csvRgb(csv, indirectAt[i]);
        csvLux(csv, photometry, total, indirect.enabled ? &indirectAt[i] : nullptr);
        csv << "," << method << "," << choice.passes * int(scene.lights.size()) << "," << seconds << "\n";
        progress.update(i + 1);
    }
    progress.finish();
    writeTextFileAtomically(out, csv.str());
    std::printf("wrote %s (%zu points, %zu lights, %s)\n", out.c_str(), points.size(), scene.lights.size(),
                choice.describe().c_str());
    return 0;
}

}  // namespace ml
