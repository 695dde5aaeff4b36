#include "SensorIrradiance.h"

#include "Plan.h"
#include "Progress.h"
#include "SamplerOptions.h"
#include "cache/ProgressiveSession.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/io/InterruptGuard.h"
#include "core/raytrace/EmbreeScene.h"
#include "gpu_sampling/direct/RayTracedLightSampler.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/indirect/RadianceProxy.h"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <istream>
#include <sstream>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

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

bool interruptedNow(const InterruptGuard* interrupt) { return interrupt && interrupt->interrupted(); }

// The bar at 100%, or left where an interrupt stopped it.
void endProgress(Progress& progress, bool complete) {
    if (complete)
        progress.finish();
    else
        progress.abandon();
}

// --method path: the path tracer's irradiance, direct (per light and in all)
// and indirect, each with its standard error.
SensorReadings measurePath(const Scene& scene, const SensorSettings& s, const std::vector<SensorPoint>& points,
                           const char* label, const InterruptGuard* interrupt) {
    const EmbreeScene rays(scene);
    const PathTracer tracer(rays, s.path);
    SensorReadings r;
    r.indirect = true;
    r.samples = s.spp;
    Progress progress(label, points.size());
    for (size_t i = 0; i < points.size(); ++i) {
        const SensorPoint& p = points[i];
        const auto t0 = Clock::now();
        const IrradianceEstimate e = tracer.irradiance(p.position, p.normal, s.spp, uint32_t(i));
        r.values.push_back({e.directPerLight, e.direct, e.indirect, e.directError, e.indirectError, secondsSince(t0)});
        if (interruptedNow(interrupt) && i + 1 < points.size()) break;
        progress.update(i + 1);
    }
    endProgress(progress, r.values.size() == points.size());
    return r;
}

// Direct light at each point, `passes` estimates per light with the raster
// sampler's seeds (so the raster sampler and its ray-traced peer draw the
// same jitter), plus `indirectAt` where given; appended to r.values, point
// after point, until an interrupt (if any) after the point under way.
template <typename Sampler>
void measureDirect(Sampler& sampler, const Scene& scene, const std::vector<SensorPoint>& points, int passes,
                   uint32_t seed, const std::vector<Rgb>* indirectAt, const char* label,
                   const InterruptGuard* interrupt, SensorReadings& r) {
    r.samples = passes * int(scene.lights.size());
    Progress progress(label, points.size());
    for (size_t i = 0; i < points.size(); ++i) {
        const SensorPoint& p = points[i];
        const auto t0 = Clock::now();
        SensorValue v;
        v.directPerLight.assign(scene.lights.size(), Rgb(0.0));
        for (size_t l = 0; l < scene.lights.size(); ++l) {
            for (int k = 0; k < passes; ++k)
                v.directPerLight[l] +=
                    sampler.sample(l, p.position, p.normal, seedFor(seed, uint32_t(i), uint32_t(l), uint32_t(k)))
                        .irradiance;
            v.directPerLight[l] /= double(passes);
        }
        v.seconds = secondsSince(t0);
        for (const Rgb& e : v.directPerLight) v.direct += e;
        if (indirectAt) v.indirect = (*indirectAt)[i];
        r.values.push_back(std::move(v));
        if (interruptedNow(interrupt) && i + 1 < points.size()) break;
        progress.update(i + 1);
    }
    endProgress(progress, r.values.size() == points.size());
}

// --method raytrace: the ray-traced peer of the jittered sampler (same
// frusta, jitter and estimators, Embree shadow rays instead of rasterising).
SensorReadings measureRaytrace(const Scene& scene, const SensorSettings& s, const std::vector<SensorPoint>& points,
                               const char* label, const InterruptGuard* interrupt) {
    const EmbreeScene rays(scene);
    const RayTracedLightSampler sampler(rays, s.raytrace);
    SensorReadings r;
    measureDirect(sampler, scene, points, s.direct.passes, s.direct.seed, nullptr, label, interrupt, r);
    return r;
}

// ProgressiveSession::refineUntil in slices of at most 0.1 s, so that an
// interrupt ends the wait within one; true when one did.
bool refineInterruptibly(ProgressiveSession& session, CacheWorker::Reader& reader, const StopRule& stop,
                         const char* label, const InterruptGuard* interrupt) {
    const auto start = Clock::now();
    const auto tick = [label](const CacheSnapshot& s) {
        std::fprintf(stderr, "\r%s: refining the caches: %zu vertices, bounces %d/%d   ", label, s.vertices,
                     s.bouncesFinished, s.bounces);
    };
    for (;;) {
        const double left = stop.seconds ? *stop.seconds - secondsSince(start) : kInf;
        StopRule slice = stop;
        if (interrupt) slice.seconds = std::clamp(left, 0.0, 0.1);
        const CacheSnapshot* snapshot = session.refineUntil(reader, slice, 0, 0.25, tick);
        if (interruptedNow(interrupt)) return true;
        if (!interrupt || left <= 0.1 || session.finished()) return false;
        if (snapshot && snapshot->converged) return false;
    }
}

// Indirect irradiance at the points, as render computes it: the direct
// caches are refined (with bounce after bounce of indirect caches, and the
// caustics' photons) on the worker until converged or `seconds`; then,
// bounce by bounce, each point gathers from the source the bounce's cache
// gathered from (the direct meshes and the caustic mesh for bounce 1,
// bounce n−1's mesh for bounce n), `passes` jittered gathers averaged; and
// each point on a surface adds the caustic mesh's irradiance there (light
// through or off mirrors and glass: the direct sampler treats them as
// opaque). A point off every surface (a work plane in the air) has no
// caustic mesh to read: its caustics are left out. Returns one sum over the
// bounces and the caustics per point.
std::vector<Rgb> measureIndirect(const Scene& scene, const SensorSettings& s, const std::vector<SensorPoint>& points,
                                 const char* label, const InterruptGuard* interrupt, SensorReadings& readings) {
    const DirectChoice& choice = s.direct;
    std::vector<Rgb> sum(points.size(), Rgb(0.0));
    if (s.indirect.solver.bounces == 0) return sum;
    SessionSettings settings;
    settings.cache = s.cache;
    settings.worker.seed = choice.seed;
    // With --time, refine on past the tolerances for as long as asked (the
    // caches tighten level by level); without, stop at them: converging
    // through every level would take hours with the exact sampler.
    settings.worker.refinementLevels = s.seconds ? IrradianceCache::kMaxRefinementLevel : 0;
    settings.indirect = s.indirect.solver;
    ProgressiveSession session(scene, settings, samplerFactory(scene, choice, s.indirect));
    session.start();
    {
        CacheWorker::Reader reader = session.reader();
        StopRule stop;
        stop.seconds = s.seconds;
        if (refineInterruptibly(session, reader, stop, label, interrupt)) {
            readings.interrupted = true;
            readings.cut = concat("refinement after ", std::round(session.seconds() * 10) / 10, " s");
            std::fprintf(stderr, "\nmeshlight: %s: ending the worker's round; evaluating the points from what is cached",
                         interrupt->signalName());
        }
        session.stop();
        session.rethrowIfFailed();
        std::fprintf(stderr, "\n");
    }
    const IrradianceCache& cache = session.cache();
    const IndirectSolver& solver = *session.indirect();
    std::vector<IrradianceMeshCopy> caustics;  // the caustic mesh, if the scene has caustics
    if (session.caustics()) caustics.push_back(session.caustics()->copyMesh());  // null unless active
    std::unique_ptr<GlContext> context = createHeadlessContext(choice.backend);
    std::unique_ptr<IndirectEstimator> estimator = makeIndirectEstimator(*context, scene, s.indirect);
    Progress progress(concat(label, ": gathering"), points.size() * size_t(solver.started()));
    for (int b = 1; b <= solver.started(); ++b) {
        std::vector<IrradianceMeshCopy> source;
        if (b == 1) {
            source = cache.copyMeshes();
            source.insert(source.end(), caustics.begin(), caustics.end());  // as CacheWorker's bounce 1 reflects
        } else
            source.push_back(solver.copyMesh(b - 1));
        // Slot 0 is bounce 1's (where the ray gather would add gathered
        // lights' emission, GatheredLights.h); later bounces use slot 1.
        const size_t slot = b == 1 ? 0 : 1;
        estimator->setSource(slot, source);
        for (size_t i = 0; i < points.size(); ++i) {
            Rgb e(0.0);
            for (int k = 0; k < choice.passes; ++k)
                e += estimator->estimate(slot, points[i].position, points[i].normal,
                                         seedFor(choice.seed, uint32_t(i), 0x1d1ec7u + uint32_t(b), uint32_t(k)));
            sum[i] += e / double(choice.passes);
            progress.update(size_t(b - 1) * points.size() + i + 1);
        }
    }
    if (!caustics.empty()) {
        // A sensor a little off its surface (as a CSV gives it) still reads
        // it: a thousandth of the scene's size.
        const double diagonal = std::max(scene.bounds.diagonal(), 1e-30);
        const MeshIrradianceLookup lookup(caustics.front(), diagonal / 64, 1e-3 * diagonal);
        for (size_t i = 0; i < points.size(); ++i) sum[i] += lookup.at(points[i].position, points[i].normal);
    }
    progress.finish();
    if (!caustics.empty())
        std::fprintf(stderr,
                     "note: the scene has caustics (light through or off mirrors and glass): they are read from "
                     "the surfaces' caustic mesh, so a point off every surface (a work plane in the air) leaves "
                     "them out\n");
    if (solver.started() < solver.bounces())
        std::fprintf(stderr, "warning: only %d of %d bounces were reached in the time given\n", solver.started(),
                     solver.bounces());
    return sum;
}

// GPU and exact direct light, each point `passes` estimates per light, and
// indirect light from the refined caches.
SensorReadings measureCache(const Scene& scene, SensorSettings& s, const std::vector<SensorPoint>& points,
                            const char* label, const InterruptGuard* interrupt) {
    s.indirect.decide(scene);
    // The direct columns sample every light at the points themselves, so no
    // light may also come through the gather (GatheredLights.h).
    s.indirect.solver.gatheredLights.clear();
    s.indirect.gatheredReason = "every light is sampled directly (probe and grid report each light's direct light)";
    if (s.indirect.enabled) std::printf("indirect light: %s\n", s.indirect.bounceCount.reason.c_str());
    SensorReadings r;
    r.indirect = s.indirect.enabled;
    const std::vector<Rgb> indirectAt =
        s.indirect.enabled ? measureIndirect(scene, s, points, label, interrupt, r) : std::vector<Rgb>{};
    // A signal during refinement has had its effect: the points are all evaluated.
    const InterruptGuard* pointsInterrupt = r.interrupted ? nullptr : interrupt;

    ConfiguredDirectSampler sampler(scene, s.direct);
    measureDirect(sampler, scene, points, s.direct.passes, s.direct.seed, r.indirect ? &indirectAt : nullptr, label,
                  pointsInterrupt, r);
    return r;
}

}  // namespace

std::vector<SensorPoint> readSensorCsv(const std::string& path, std::vector<std::string>* surfaces) {
    std::ifstream in(path);
    if (!in) throwInputError(SourceLocation{path}, "cannot open the points file");
    std::string line;
    int lineNo = 0;
    std::vector<SensorPoint> points;
    bool header = false, surfaceColumn = false;
    const std::array<const char*, 6> columns = {"x", "y", "z", "nx", "ny", "nz"};
    const std::vector<std::string> expected(columns.begin(), columns.end());
    std::vector<std::string> withSurface = expected;
    withSurface.push_back("surface");
    const std::string expectedText = surfaces ? "x,y,z,nx,ny,nz or x,y,z,nx,ny,nz,surface" : "x,y,z,nx,ny,nz";
    while (std::getline(in, line)) {
        ++lineNo;
        if (line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t")] == '#')
            continue;
        const std::vector<std::string> cells = splitCsv(line);
        const SourceLocation at{path, lineNo};
        if (!header) {
            surfaceColumn = surfaces && cells == withSurface;
            if (cells != expected && !surfaceColumn) throwInputError(at, "the header must be ", expectedText);
            header = true;
            continue;
        }
        const size_t n = surfaceColumn ? 7 : 6;
        if (cells.size() != n) throwInputError(at, "expected ", n, " values, found ", cells.size());
        points.push_back(sensorPoint(cells, at, columns));
        if (surfaceColumn && cells[6].empty()) throwInputError(at, "the surface name is empty");
        if (surfaces) surfaces->push_back(surfaceColumn ? cells[6] : std::string());
    }
    if (!header) throwInputError(SourceLocation{path}, "empty file: expected the header ", expectedText);
    return points;
}

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

std::string SensorSettings::describe() const {
    switch (kind) {
    case SensorMethod::Path:
        return concat("path tracer: ", spp, " samples per point, max depth ", path.maxDepth, ", seed ", path.seed);
    case SensorMethod::Raytrace: {
        char text[160];
        std::snprintf(text, sizeof text, "raytrace %dx%d, %d bits/pixel, %s estimator, %d %s", raytrace.imageSize,
                      raytrace.imageSize, raytrace.bits, directEstimatorName(raytrace.estimator), direct.passes,
                      direct.passes == 1 ? "pass" : "passes");
        return text;
    }
    case SensorMethod::Cache: break;
    }
    return direct.describe();
}

void declareSensorOptions(Options& o, std::optional<std::string> defaultSeconds) {
    declareDirectOptions(o);
    // The CPU references (--method path: the path tracer; --method raytrace:
    // the jittered sampler with shadow rays) and their own options.
    o.value("spp", "N", "--method path: cosine-weighted directions per point, each with one sample of every "
                        "light (default 1024)");
    o.value("max-depth", "D", "--method path: 1 = direct light only, D = direct + D-1 indirect bounces (default 8)");
    o.value("threads", "T", "--method path: worker threads, 0 = every core (default 0)");
    // GPU and exact direct light: indirect light as render computes it.
    o.flag("direct-only", "GPU and exact methods: direct light only (no E_indirect columns)");
    o.value("time", "S", "GPU and exact methods: refine the caches for at most S seconds before gathering",
            std::move(defaultSeconds));
    declareCacheOptions(o);
    declareIndirectOptions(o);
}

SensorSettings readSensorSettings(const Options& o, const std::vector<std::string>& args) {
    SensorSettings s;
    s.method = o.str("method");
    if (s.method == "path" || s.method == "raytrace") {
        refuseOptions(args, s.method,
                      {"direct-only", "time", "bounces", "indirect-tolerance", "max-bounces", "indirect-method", "voxels",
                       "gather-size", "near-voxels", "slice-supersample", "cache-edge", "min-edge", "min-edge-pixels",
                       "split-tolerance", "noise-tolerance", "max-vertices"});
    }
    if (s.method == "path") {
        s.kind = SensorMethod::Path;
        refuseOptions(args, "path", {"estimator", "image-size", "bits", "passes", "gl"});
        s.path.maxDepth = o.has("max-depth") ? o.integer("max-depth", 1, 1024) : 8;
        s.path.threads = o.has("threads") ? o.integer("threads", 0, 1024) : 0;
        s.path.seed = o.seed("seed");
        s.spp = o.has("spp") ? o.integer("spp", 2, 1 << 24) : 1024;
        return s;
    }
    if (s.method == "raytrace") {
        s.kind = SensorMethod::Raytrace;
        refuseOptions(args, "raytrace", {"gl", "spp", "max-depth", "threads"});
        s.raytrace.method = DirectMethod::Jittered;
        s.raytrace.estimator = parseDirectEstimator(o.str("estimator"));
        s.raytrace.imageSize = o.integer("image-size", 4, 1024);
        s.raytrace.bits = o.integer("bits", 1, 32);
        s.raytrace.validate();
        s.direct.passes = o.integer("passes", 1, 1 << 20);
        s.direct.seed = o.seed("seed");
        return s;
    }
    refuseOptions(args, s.method, {"spp", "max-depth", "threads"});
    s.kind = SensorMethod::Cache;
    s.direct = readDirectOptions(o);
    s.cache = readCacheSettings(o);
    s.indirect = readIndirectOptions(o);
    if (o.has("time")) s.seconds = o.number("time", 0, 1e7);
    s.method = s.direct.exact ? std::string("exact") : directMethodName(s.direct.sampler.method);
    return s;
}

SensorReadings measureSensors(const Scene& scene, SensorSettings& settings, const std::vector<SensorPoint>& points,
                              const char* label, const InterruptGuard* interrupt) {
    SensorReadings r;
    switch (settings.kind) {
    case SensorMethod::Path: r = measurePath(scene, settings, points, label, interrupt); break;
    case SensorMethod::Raytrace: r = measureRaytrace(scene, settings, points, label, interrupt); break;
    case SensorMethod::Cache: r = measureCache(scene, settings, points, label, interrupt); break;
    }
    if (r.values.size() < points.size()) {
        r.interrupted = true;
        r.cut = r.cut.empty() ? std::string("the points") : r.cut + " and the points";
    }
    return r;
}

}  // namespace ml
