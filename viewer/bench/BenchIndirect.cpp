#include "BenchIndirect.h"

#include "BenchRun.h"
#include "BenchStatistics.h"
#include "BenchTable.h"
#include "Gnuplot.h"
#include "core/ParallelFor.h"

#include "cache/IrradianceCache.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "core/reference/ExactIrradiance.h"
#include "core/scenes/CornellBox.h"
#include "gpu_sampling/indirect/IrradianceVolume.h"
#include "gpu_sampling/indirect/PropagationCompute.h"
#include "gpu_sampling/indirect/PropagationVolume.h"
#include "gpu_sampling/indirect/RayGather.h"
#include "gpu_sampling/indirect/SliceGather.h"
#include "gpu_sampling/indirect/TriangleGather.h"
#include "gpu_sampling/indirect/UpsampledIndirect.h"
#include "gpu_sampling/indirect/VirtualPointLights.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/indirect/VoxelMarchGather.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <thread>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;

// The issue's target: the slice gather at least this many times faster than
// the perspective triangle gather at equal error (the paper: 18 ms against 46 ms).
constexpr double kSpeedupTarget = 2.0;
// The configuration the target is about: the paper's 40×40 fish-eye over 64 voxels.
constexpr int kPaperImage = 40, kPaperVoxels = 64;

// --- Configurations ------------------------------------------------------------

struct Config {
    std::string method;   // as --indirect-method names it
    int imageSize = 40;   // pixels per side (hemicube: of the top face; volume: rays per cube-map face side)
    // Voxels (slices, raymarch), proxy voxels (triangles), probes (volume) or
    // cells (lpv) along the longest side; lights (vpl).
    int resolution = 64;
    int nearVoxels = 0;   // slices, raymarch: GatherSettings::nearVoxels
    bool visibility = true;  // volume: IrradianceVolumeSettings::visibility; lpv: its occlusion

    bool voxels() const { return method == "slices" || method == "slice-quads" || method == "raymarch"; }
    // "slices 40 @64", "slices 40 @64 near1": no commas, also a CSV cell and a gnuplot label.
    std::string label() const { return concat(method, " ", shortLabel()); }
    std::string shortLabel() const {
        if (method == "raytrace") return concat(imageSize * imageSize / 4, " rays");
        if (method == "lpv") return concat(resolution, " cells", visibility ? "" : " blind");
        if (method == "vpl")
            return concat(resolution, " lights", imageSize > 0 ? concat(" +", imageSize, " rays") : std::string(),
                          visibility ? "" : " blind");
        return concat(imageSize, " @", resolution, nearVoxels > 0 ? concat(" near", nearVoxels) : std::string(),
                      visibility ? "" : " blind");
    }
};

struct Workload {
    size_t areaPoints;     // random by area; the fixed corner points come on top
    int referenceSamples;  // path tracer: cosine-weighted directions per point
    int sourceRaysSide;    // exact-geometry gather: side² stratified rays per point
    int passes;            // K gathers per point and configuration
    // The source cache: after its base mesh, refinement rounds with the
    // exact sampler (contacts and shadow edges), up to this many estimates.
    size_t refineEstimates;
    std::vector<Config> configs;
    // The curve of each method: its configurations at this resolution.
    std::map<std::string, int> mainResolution;
};

Workload workloadFor(const BenchOptions& options) {
    Workload p;
    std::vector<Config>& c = p.configs;
    auto sizes = [&](const std::string& method, std::initializer_list<int> ns, int res, int near = 0) {
        for (int n : ns) c.push_back({method, n, res, near});
    };
    // The propagation volume (quick and full alike: it is fast) from 8 to the
    // paper's 32 cells, and at 16 without its geometry volume (Kaplanyan's
    // plain propagation).
    auto lpvRows = [&] {
        for (const int cells : {8, 16, 24, 32}) c.push_back({"lpv", 0, cells});
        c.push_back({"lpv", 0, 16, 0, false});
        p.mainResolution["lpv"] = 16;
    };
    if (options.quick) {
        p.areaPoints = 16;
        p.referenceSamples = 1 << 15;
        p.sourceRaysSide = 64;
        p.passes = 4;
        p.refineEstimates = 4000;
        sizes("slices", {24, 40}, 32);
        sizes("slices", {40}, 32, 1);
        sizes("slice-quads", {40}, 32);
        sizes("raymarch", {40}, 32);
        sizes("fisheye-triangles", {24, 40}, 32);
        sizes("perspective", {64, 128}, 32);
        sizes("hemicube", {32, 64}, 32);
        sizes("raytrace", {24, 40}, 0);
        // The volume's probes at the paper's 4 along a side and at 8; a
        // hemicube of the paper's cube-map face size, for what a GL cube map
        // per probe would cost here.
        sizes("volume", {16}, 4);
        sizes("volume", {16}, 8);
        sizes("hemicube", {16}, 32);
        // Virtual point lights: N lights, with the clamp's compensation by 16
        // rays per estimate, and without it (0).
        sizes("vpl", {16}, 256);
        sizes("vpl", {0, 16}, 1024);
        p.mainResolution = {{"slices", 32},      {"slice-quads", 32}, {"raymarch", 32}, {"fisheye-triangles", 32},
                            {"perspective", 32}, {"hemicube", 32},    {"raytrace", 0}, {"volume", 8}};
        p.mainResolution["vpl"] = 1024;
        lpvRows();
        return p;
    }
    p.areaPoints = 96;
    p.referenceSamples = 1 << 18;
    p.sourceRaysSide = 128;
    p.passes = 6;
    p.refineEstimates = 20000;
    sizes("slices", {16, 24, 32, 40, 64}, 64);
    sizes("slices", {40}, 64, 1);
    sizes("slices", {40}, 64, 2);
    sizes("slices", {40}, 32);
    sizes("slices", {40}, 128);
    sizes("slice-quads", {24, 40}, 64);
    sizes("raymarch", {16, 24, 40, 64}, 64);
    sizes("raymarch", {40}, 64, 1);
    sizes("raymarch", {40}, 32);
    sizes("raymarch", {40}, 128);
    sizes("fisheye-triangles", {16, 24, 32, 40, 64}, 32);
    sizes("fisheye-triangles", {40}, 16);
    sizes("fisheye-triangles", {40}, 64);
    sizes("perspective", {64, 128, 256}, 32);
    sizes("perspective", {64, 128, 256}, 64);
    sizes("perspective", {128}, 16);
    sizes("hemicube", {32, 64, 128}, 32);
    sizes("hemicube", {64}, 16);
    sizes("hemicube", {64}, 64);
    sizes("raytrace", {16, 24, 40, 64}, 0);
    sizes("volume", {8, 16, 32}, 8);
    sizes("volume", {16}, 4);
    sizes("volume", {16}, 16);
    c.push_back({"volume", 16, 8, 0, false});
    sizes("hemicube", {16}, 32);
    // Virtual point lights: the paper's 100-450 and more, with the clamp's
    // compensation by 16 or 64 rays per estimate and without it (0); 1,024
    // without negative lights (the paper's simple indirect light).
    sizes("vpl", {16}, 256);
    sizes("vpl", {0, 16, 64}, 1024);
    sizes("vpl", {16}, 4096);
    c.push_back({"vpl", 16, 1024, 0, false});
    p.mainResolution = {{"slices", 64},      {"slice-quads", 64}, {"raymarch", 64}, {"fisheye-triangles", 32},
                        {"perspective", 32}, {"hemicube", 32},    {"raytrace", 0}, {"volume", 8}};
    p.mainResolution["vpl"] = 1024;
    lpvRows();
    return p;
}

// An estimator with the accessors the bench needs (phases, triangles drawn).
struct Gatherer {
    std::unique_ptr<IndirectEstimator> estimator;
    std::function<void(bool)> timePhases;
    std::function<GatherPhaseTimes()> phases;
    std::function<size_t()> drawn;  // triangles drawn by the last gather (near field for the voxel methods)
    size_t proxyTriangles = 0;
};

// The three gather classes share these accessors without a common base;
// `drawn` reads the one they name differently.
template <typename Gather, typename Drawn>
Gatherer gathererOf(std::unique_ptr<Gather> gather, Drawn drawn) {
    Gatherer g;
    Gather* p = gather.get();
    g.timePhases = [p](bool on) { p->setTimePhases(on); };
    g.phases = [p] { return p->phases(); };
    g.drawn = [p, drawn] { return drawn(*p); };
    g.proxyTriangles = p->proxy().triangles().size();
    g.estimator = std::move(gather);
    return g;
}

// The estimators that trace or loop on the CPU: no GL phases, nothing drawn.
Gatherer cpuGatherer(std::unique_ptr<IndirectEstimator> estimator) {
    Gatherer g;
    g.estimator = std::move(estimator);
    g.timePhases = [](bool) {};
    g.phases = [] { return GatherPhaseTimes{}; };
    g.drawn = [] { return size_t(0); };
    return g;
}

Gatherer makeGatherer(GlContext& context, const Scene& scene, const Config& c) {
    auto nearCount = [](const auto& gather) { return gather.lastNearCount(); };
    if (c.method == "vpl") {
        VirtualPointLightSettings s;
        s.lights = c.resolution;
        s.nearRays = c.imageSize;
        s.visibility = c.visibility;
        return cpuGatherer(std::make_unique<VirtualPointLights>(scene, s));
    }
    if (c.method == "lpv") {
        PropagationVolumeSettings s;
        s.cells = c.resolution;
        s.occlusion = c.visibility;
        return cpuGatherer(std::make_unique<PropagationVolume>(scene, s));
    }
    if (c.method == "raytrace") {
        RayGatherSettings s;
        s.rays = c.imageSize * c.imageSize / 4;
        return cpuGatherer(std::make_unique<RayGather>(scene, s));
    }
    if (c.method == "volume") {
        IrradianceVolumeSettings s;
        s.faceSize = c.imageSize;
        s.probes = c.resolution;
        s.visibility = c.visibility;
        return cpuGatherer(std::make_unique<IrradianceVolume>(scene, s));
    }
    if (c.method == "slices" || c.method == "slice-quads") {
        GatherSettings s;
        s.imageSize = c.imageSize;
        s.resolution = c.resolution;
        s.quadPerFace = c.method == "slice-quads";
        s.nearVoxels = c.nearVoxels;
        return gathererOf(std::make_unique<SliceGather>(context, scene, s), nearCount);
    }
    if (c.method == "raymarch") {
        GatherSettings s;
        s.imageSize = c.imageSize;
        s.resolution = c.resolution;
        s.nearVoxels = c.nearVoxels;
        return gathererOf(std::make_unique<VoxelMarchGather>(context, scene, s), nearCount);
    }
    TriangleGatherSettings s;
    s.imageSize = c.imageSize;
    s.resolution = c.resolution;
    bool known = false;
    for (TriangleProjection p :
         {TriangleProjection::Fisheye, TriangleProjection::Perspective, TriangleProjection::Hemicube})
        if (c.method == triangleProjectionName(p)) s.projection = p, known = true;
    ML_ASSERT(known, "bench indirect: unknown method ", c.method);
    return gathererOf(std::make_unique<TriangleGather>(context, scene, s),
                      [](const TriangleGather& gather) { return gather.lastTriangles(); });
}

// --- Points -------------------------------------------------------------------------

// Where a point lies, for errors by group: the methods differ most on the
// rotated blocks (slanted in the voxel grid) and in corners and contacts.
enum class PointGroup { Walls, Blocks, Fixed };
constexpr PointGroup kGroups[] = {PointGroup::Walls, PointGroup::Blocks, PointGroup::Fixed};
const char* groupName(PointGroup g) {
    switch (g) {
        case PointGroup::Walls:
            return "walls";  // random, on the box's walls, floor and ceiling
        case PointGroup::Blocks:
            return "blocks";  // random, on the two blocks
        case PointGroup::Fixed:
            return "corners";  // the fixed points: corners, contacts, beside the light
    }
    return "?";
}

struct BenchPoint {
    Vec3 x{0.0}, n{0.0};
    std::string kind;  // "area" or what the fixed point is (no commas)
    PointGroup group = PointGroup::Fixed;
};

// Whether the ray from a surface point along its normal first meets the back
// of a surface: the point is inside something (the floor under a block).
bool inside(const EmbreeScene& rays, const Vec3& x, const Vec3& n) {
    RayHit hit;
    if (!rays.intersect(rays.spawnPoint(x, n, n), n, 0.0, kInf, hit)) return false;
    return glm::dot(rays.surface(hit).geometricNormal, n) > 0;
}

std::vector<BenchPoint> areaPoints(const Scene& scene, const EmbreeScene& rays, size_t count, uint32_t seed) {
    std::vector<Triangle3> triangles;
    std::vector<double> areas;
    std::vector<PointGroup> groups;
    for (const Mesh& mesh : scene.meshes)
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            if (scene.materials[mesh.materials[t]].emissive() || !(mesh.area(t) > 0)) continue;
            triangles.push_back(mesh.triangle(t));
            areas.push_back(mesh.area(t));
            groups.push_back(mesh.name.find("Block") != std::string::npos ? PointGroup::Blocks : PointGroup::Walls);
        }
    std::mt19937 rng(seed);
    std::discrete_distribution<size_t> pick(areas.begin(), areas.end());
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<BenchPoint> points;
    for (size_t tries = 0; points.size() < count && tries < 100 * count + 100; ++tries) {
        const size_t k = pick(rng);
        const Triangle3& t = triangles[k];
        const double r = std::sqrt(unit(rng)), s = unit(rng);
        const Vec3 p = (1 - r) * t[0] + r * (1 - s) * t[1] + r * s * t[2];
        const Vec3 n = glm::normalize(glm::cross(t[1] - t[0], t[2] - t[0]));
        if (inside(rays, p, n)) continue;
        points.push_back({p, n, "area", groups[k]});
    }
    return points;
}

// The point of the scene's non-emitting surfaces nearest to `approx` among
// triangles facing within 25° of `facing`, with that triangle's normal; none
// within 10 scene units (millimetres here) is a bench bug.
BenchPoint snapped(const Scene& scene, const Vec3& approx, const Vec3& facing, const std::string& kind) {
    double best = 10.0;
    std::optional<BenchPoint> found;
    const Vec3 f = glm::normalize(facing);
    for (const Mesh& mesh : scene.meshes)
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            if (scene.materials[mesh.materials[t]].emissive() || !(mesh.area(t) > 0)) continue;
            const Triangle3 tri = mesh.triangle(t);
            const Vec3 n = glm::normalize(mesh.areaNormal(t));
            if (glm::dot(n, f) < std::cos(25.0 * kPi / 180)) continue;
            // Project onto the plane; keep it if inside (barycentrics, with a hair of slack).
            const Vec3 p = approx - glm::dot(approx - tri[0], n) * n;
            const Vec3 e1 = tri[1] - tri[0], e2 = tri[2] - tri[0], w = p - tri[0];
            const double d11 = glm::dot(e1, e1), d12 = glm::dot(e1, e2), d22 = glm::dot(e2, e2);
            const double dw1 = glm::dot(w, e1), dw2 = glm::dot(w, e2), det = d11 * d22 - d12 * d12;
            const double b1 = (d22 * dw1 - d12 * dw2) / det, b2 = (d11 * dw2 - d12 * dw1) / det;
            if (b1 < -1e-9 || b2 < -1e-9 || b1 + b2 > 1 + 1e-9) continue;
            const double d = glm::length(p - approx);
            if (d < best) best = d, found = BenchPoint{tri[0] + b1 * e1 + b2 * e2, n, kind, PointGroup::Fixed};
        }
    ML_ASSERT(found.has_value(), "bench indirect: no surface near the fixed point ", kind);
    return *found;
}

// Where gathers are hardest: corners, contact lines, beside the light
// (Cornell box coordinates, millimetres; see core/scenes/CornellBox.cpp).
std::vector<BenchPoint> fixedPoints(const Scene& scene) {
    const Vec3 up(0, 1, 0), down(0, -1, 0), intoBox(0, 0, -1), fromRight(1, 0, 0), fromLeft(-1, 0, 0);
    const Vec3 shortSide = glm::normalize(Vec3(158, 0, 50));   // short block face between (290,114) and (240,272)
    const Vec3 tallSide = glm::normalize(Vec3(-49, 0, -158));  // tall block face between (423,247) and (265,296)
    return {
        snapped(scene, {4, 0, 555}, up, "floor-corner-back-right"),
        snapped(scene, {545, 0, 555}, up, "floor-corner-back-left"),
        snapped(scene, {268, 0, 194}, up, "floor-by-short-block"),
        snapped(scene, {344, 0, 268}, up, "floor-by-tall-block"),
        snapped(scene, {278, 0, 3}, up, "floor-front-edge"),
        snapped(scene, {4, 548.8, 555}, down, "ceiling-corner"),
        snapped(scene, {278, 548.8, 336}, down, "ceiling-by-light"),
        snapped(scene, {278, 3, 559.2}, intoBox, "back-wall-by-floor"),
        snapped(scene, {4, 4, 559.2}, intoBox, "back-wall-corner"),
        snapped(scene, {0, 3, 300}, fromRight, "right-wall-by-floor"),
        snapped(scene, {0, 545, 300}, fromRight, "right-wall-by-ceiling"),
        snapped(scene, {554.4, 274, 3}, fromLeft, "left-wall-front-edge"),
        snapped(scene, {265, 3, 193}, shortSide, "short-block-by-floor"),
        snapped(scene, {161.9, 165, 245.6}, up, "short-block-top-edge"),
        snapped(scene, {344, 3, 271.5}, tallSide, "tall-block-by-floor"),
        snapped(scene, {344, 327, 271.5}, tallSide, "tall-block-by-top"),
        snapped(scene, {340, 330, 380}, up, "tall-block-top"),
    };
}

// --- References ------------------------------------------------------------------------

struct PointReference {
    double path = 0;    // luminance of the path tracer's one-bounce indirect irradiance
    double pathSe = 0;  // its standard error
    double source = 0;  // luminance of the exact-geometry gather of the source
};

// --- Measuring -----------------------------------------------------------------------------

// Relative RMS error: sqrt(Σ (e − r)² / Σ r²) over the points (luminance),
// and the mean and max of |e − r| / r over points with r > 0.
struct Errors {
    double relRms = 0, meanRel = 0, maxRel = 0;
};
Errors errorsOf(const std::vector<double>& estimates, const std::vector<double>& reference) {
    double num = 0, den = 0, sumRel = 0, maxRel = 0;
    size_t counted = 0;
    for (size_t i = 0; i < estimates.size(); ++i) {
        const double d = estimates[i] - reference[i];
        num += d * d;
        den += reference[i] * reference[i];
        if (reference[i] > 0) {
            const double r = std::abs(d) / reference[i];
            sumRel += r;
            maxRel = std::max(maxRel, r);
            ++counted;
        }
    }
    Errors e;
    e.relRms = den > 0 ? std::sqrt(num / den) : 0;
    e.meanRel = counted ? sumRel / double(counted) : 0;
    e.maxRel = maxRel;
    return e;
}

struct Row {
    Config config;
    size_t proxyTriangles = 0;
    double drawn = 0;         // mean triangles drawn per gather (voxel methods: near-field triangles)
    double buildSeconds = 0;  // constructing the estimator and its source
    double updateSeconds = 0; // setSource alone: the volume's capture of every probe, the others' source
    ProbeGrid probes;         // volume: its grid
    PropagationGrid lpvGrid;           // lpv: its grid
    PropagationVolume::Report lpv;     // lpv: what its update did
    double sourceMB = 0;
    double setupMs = 0, drawMs = 0, readbackMs = 0, timedTotalMs = 0;  // medians, phase-timed pass
    double totalMs = 0;                    // median wall time per gather, passes without phase timing
    Errors single, meanK;                  // against the path tracer
    Errors gatherSingle, gatherMeanK;      // against the exact-geometry gather of the source
    std::map<PointGroup, Errors> byGroup;  // one gather against the path tracer, per group of points
};

Row measure(GlContext& context, const Scene& scene, const std::vector<IrradianceMeshCopy>& source, const Config& c,
            const std::vector<BenchPoint>& points, const std::vector<PointReference>& refs, int passes, uint32_t seed) {
    Row row;
    row.config = c;
    const Clock::time_point t0 = Clock::now();
    Gatherer g = makeGatherer(context, scene, c);
    g.estimator->setSource(0, source);
    row.buildSeconds = secondsSince(t0);
    row.updateSeconds = g.estimator->stats().buildSeconds;
    if (c.method == "volume") row.probes = ProbeGrid(scene.bounds, c.resolution);
    if (const auto* lpv = dynamic_cast<const PropagationVolume*>(g.estimator.get())) {
        row.lpvGrid = lpv->grid();
        row.lpv = lpv->report(0);
    }
    row.sourceMB = double(g.estimator->stats().sourceBytes) / 1e6;
    row.proxyTriangles = g.proxyTriangles;
    // Warm-up, untimed: the first draws of a program compile its variants.
    for (size_t i = 0; i < std::min<size_t>(3, points.size()); ++i)
        g.estimator->estimate(0, points[i].x, points[i].n, seedFor(seed, uint32_t(i), 999));

    std::vector<double> first(points.size()), mean(points.size(), 0.0);
    std::vector<double> setup, draw, readback, timedTotal, total;
    double drawn = 0;
    for (int pass = 0; pass < passes; ++pass) {
        const bool timed = pass == 0;
        g.timePhases(timed);
        for (size_t i = 0; i < points.size(); ++i) {
            const GatherPhaseTimes before = g.phases();
            const Clock::time_point t = Clock::now();
            const Rgb e =
                g.estimator->estimate(0, points[i].x, points[i].n, seedFor(seed, uint32_t(i), uint32_t(pass)));
            const double wall = secondsSince(t);
            const double lum = luminance(e);
            mean[i] += lum / passes;
            if (timed) {
                const GatherPhaseTimes after = g.phases();
                setup.push_back(after.nearField - before.nearField);
                draw.push_back(after.draw - before.draw);
                readback.push_back(after.readback - before.readback);
                timedTotal.push_back(wall);
                first[i] = lum;
                drawn += double(g.drawn());
            } else {
                total.push_back(wall);
            }
        }
    }
    row.setupMs = 1e3 * median(setup);
    row.drawMs = 1e3 * median(draw);
    row.readbackMs = 1e3 * median(readback);
    row.timedTotalMs = 1e3 * median(timedTotal);
    row.totalMs = 1e3 * median(total.empty() ? timedTotal : total);
    row.drawn = points.empty() ? 0 : drawn / double(points.size());
    std::vector<double> path(refs.size()), src(refs.size());
    for (size_t i = 0; i < refs.size(); ++i) path[i] = refs[i].path, src[i] = refs[i].source;
    row.single = errorsOf(first, path);
    row.meanK = errorsOf(mean, path);
    row.gatherSingle = errorsOf(first, src);
    row.gatherMeanK = errorsOf(mean, src);
    for (PointGroup g : kGroups) {
        std::vector<double> e, r;
        for (size_t i = 0; i < points.size(); ++i)
            if (points[i].group == g) e.push_back(first[i]), r.push_back(path[i]);
        row.byGroup[g] = errorsOf(e, r);
    }
    return row;
}

// --- Equal error -------------------------------------------------------------------------------

// A configuration reduced to what the comparison needs.
struct Point2 {
    double ms = 0, error = 0;
    std::string label;
};

// The time the cheapest-first sequence `front` (time ascending, each point
// more accurate than all cheaper ones) needs for error e: log-log
// interpolation between the last configuration above e and the first at or
// below it. Empty when none reaches e; `bounded` when even the cheapest
// does (then it costs at most that).
struct AtError {
    bool reached = false, bounded = false;
    double ms = 0;
    std::string how;  // plain words, for the summary
};

std::vector<Point2> paretoFront(std::vector<Point2> pts) {
    std::sort(pts.begin(), pts.end(), [](const Point2& a, const Point2& b) { return a.ms < b.ms; });
    std::vector<Point2> front;
    for (const Point2& p : pts)
        if (front.empty() || p.error < front.back().error) front.push_back(p);
    return front;
}

AtError timeAtError(const std::vector<Point2>& front, double e) {
    AtError r;
    for (size_t k = 0; k < front.size(); ++k) {
        if (front[k].error > e) continue;
        r.reached = true;
        if (k == 0) {
            r.bounded = true;
            r.ms = front[0].ms;
            r.how = concat("its cheapest configuration (", front[0].label, ") is already as accurate");
            return r;
        }
        const Point2 &a = front[k - 1], &b = front[k];
        const double f = (std::log(e) - std::log(a.error)) / (std::log(b.error) - std::log(a.error));
        r.ms = std::exp(std::log(a.ms) + f * (std::log(b.ms) - std::log(a.ms)));
        r.how = concat("interpolated between ", a.label, " and ", b.label);
        return r;
    }
    r.how = front.empty() ? "no configuration" : concat("none reaches it (best: ", front.back().label, ")");
    return r;
}

struct Comparison {
    std::string slices;   // label of the slice configuration
    std::string metric;   // "vs path tracer" or "vs exact gather of the source" (no commas)
    std::string against;  // which perspective configurations
    double slicesMs = 0, slicesError = 0;
    AtError perspective;
    double speedup() const { return perspective.reached && slicesMs > 0 ? perspective.ms / slicesMs : 0; }
};

std::vector<Comparison> compare(const std::vector<Row>& rows) {
    std::vector<Comparison> out;
    // The error: against the path tracer at every point, against the exact
    // gather of the source (the gathers' own), against the path tracer on
    // the walls only (where voxels represent the scene well).
    for (const int metric : {0, 1, 2}) {
        auto error = [&](const Row& r) {
            return metric == 0   ? r.single.relRms
                   : metric == 1 ? r.gatherSingle.relRms
                                 : r.byGroup.at(PointGroup::Walls).relRms;
        };
        std::vector<Point2> all;
        std::map<int, std::vector<Point2>> byProxy;
        for (const Row& r : rows)
            if (r.config.method == "perspective") {
                const Point2 p{r.totalMs, error(r), r.config.label()};
                all.push_back(p);
                byProxy[r.config.resolution].push_back(p);
            }
        for (const Row& s : rows) {
            if (s.config.method != "slices") continue;
            auto add = [&](const std::string& against, const std::vector<Point2>& pts) {
                Comparison c;
                c.slices = s.config.label();
                c.metric = metric == 0   ? "vs path tracer"
                           : metric == 1 ? "vs exact gather of the source"
                                         : "vs path tracer on the walls only";
                c.against = against;
                c.slicesMs = s.totalMs;
                c.slicesError = error(s);
                c.perspective = timeAtError(paretoFront(pts), c.slicesError);
                out.push_back(c);
            };
            add("perspective (any size and proxy)", all);
            if (byProxy.count(s.config.resolution) && byProxy[s.config.resolution].size() < all.size())
                add(concat("perspective on the same proxy (@", s.config.resolution, ")"), byProxy[s.config.resolution]);
        }
    }
    return out;
}

// --- Tables ------------------------------------------------------------------------------------

BenchTable methodsTable(const std::vector<Row>& rows, int passes) {
    BenchTable t({"config",
                  "method",
                  "image_size",
                  "resolution",
                  "near_voxels",
                  "proxy_triangles",
                  "drawn_triangles",
                  "build_s",
                  "update_s",
                  "source_mb",
                  "setup_ms",
                  "draw_ms",
                  "readback_ms",
                  "timed_total_ms",
                  "total_ms",
                  "rel_rms_pct",
                  concat("rel_rms_mean", passes, "_pct"),
                  "mean_rel_pct",
                  "max_rel_pct",
                  "gather_rel_rms_pct",
                  concat("gather_rel_rms_mean", passes, "_pct"),
                  "rel_rms_walls_pct",
                  "rel_rms_blocks_pct",
                  "rel_rms_corners_pct"});
    for (const Row& r : rows)
        t.addRow({r.config.label(),
                  r.config.method,
                  std::to_string(r.config.imageSize),
                  std::to_string(r.config.resolution),
                  r.config.voxels() ? std::to_string(r.config.nearVoxels) : std::string("-"),
                  std::to_string(r.proxyTriangles),
                  benchNumber(r.drawn),
                  benchNumber(r.buildSeconds),
                  benchNumber(r.updateSeconds),
                  benchNumber(r.sourceMB),
                  benchNumber(r.setupMs),
                  benchNumber(r.drawMs),
                  benchNumber(r.readbackMs),
                  benchNumber(r.timedTotalMs),
                  benchNumber(r.totalMs),
                  benchPct(r.single.relRms),
                  benchPct(r.meanK.relRms),
                  benchPct(r.single.meanRel),
                  benchPct(r.single.maxRel),
                  benchPct(r.gatherSingle.relRms),
                  benchPct(r.gatherMeanK.relRms),
                  benchPct(r.byGroup.at(PointGroup::Walls).relRms),
                  benchPct(r.byGroup.at(PointGroup::Blocks).relRms),
                  benchPct(r.byGroup.at(PointGroup::Fixed).relRms)});
    return t;
}

BenchTable comparisonTable(const std::vector<Comparison>& cs) {
    BenchTable t({"slices", "error_metric", "against", "slices_ms", "slices_rel_rms_pct",
                  "perspective_ms_at_equal_error", "speedup", "meets_2x", "how"});
    for (const Comparison& c : cs) {
        std::string how = c.perspective.how;
        std::replace(how.begin(), how.end(), ',', ';');
        t.addRow({c.slices, c.metric, c.against, benchNumber(c.slicesMs), benchPct(c.slicesError),
                  c.perspective.reached ? benchNumber(c.perspective.ms) : std::string("never"),
                  c.perspective.reached ? (c.perspective.bounded ? "<=" : "") + benchNumber(c.speedup())
                                        : std::string(">max"),
                  c.perspective.reached ? (c.speedup() >= kSpeedupTarget ? "yes" : "no") : "yes", how});
    }
    return t;
}

BenchTable pointsTable(const std::vector<BenchPoint>& points, const std::vector<PointReference>& refs) {
    BenchTable t({"kind", "group", "x", "y", "z", "nx", "ny", "nz", "path_indirect", "path_se", "source_gather"});
    for (size_t i = 0; i < points.size(); ++i) {
        const BenchPoint& p = points[i];
        // Nine digits: the points lie on their surfaces (probe can read them back).
        t.addRow({p.kind, groupName(p.group), concat(p.x.x), concat(p.x.y), concat(p.x.z), concat(p.n.x), concat(p.n.y),
                  concat(p.n.z), benchNumber(refs[i].path), benchNumber(refs[i].pathSe), benchNumber(refs[i].source)});
    }
    return t;
}

// --- Plots -----------------------------------------------------------------------------------------

const std::vector<GnuplotOutput> kPlots = {
    {"out_error", "indirect_error_vs_time.png"},
    {"out_gather", "indirect_gather_error_vs_time.png"},
    {"out_phases", "indirect_phases.png"},
};

const std::vector<std::string> kMethods = {"slices",      "slice-quads", "raymarch", "fisheye-triangles",
                                           "perspective", "hemicube",    "raytrace", "volume",   "vpl", "lpv"};
// One colour per method, in kMethods order (readable on white).
const char* const kColours[] = {"#7b2cbf", "#2a9d8f", "#56b4e9", "#e69f00", "#d62728", "#0072b2", "#222222", "#8c564b", "#cc79a7", "#009e73"};

std::string gnuplotScript(const std::vector<Row>& rows, const Workload& work, double floorError, double pathNoise,
                          size_t pointCount) {
    std::ostringstream gp;
    gp << "# Written by 'meshlight bench indirect'; run with gnuplot in this folder.\n"
       << gnuplotOutputDefaults(kPlots)
       << "set terminal pngcairo noenhanced size 1300,850 font ',11'\n"
          "set datafile separator ','\n"
          "set grid\n\n";
    // Per method: its curve (the main resolution, by image size) and its
    // other configurations (points). Columns: ms, error %, mean-of-K error %,
    // gather-only %, gather-only mean-of-K %, label. Empty blocks are left out.
    std::vector<std::pair<size_t, std::string>> blocks;  // method index, block name
    for (size_t m = 0; m < kMethods.size(); ++m)
        for (const bool main : {true, false}) {
            std::ostringstream data;
            for (const Row& r : rows) {
                if (r.config.method != kMethods[m]) continue;
                const auto it = work.mainResolution.find(r.config.method);
                const bool isMain =
                    it != work.mainResolution.end() && it->second == r.config.resolution && r.config.nearVoxels == 0 &&
                    r.config.visibility;
                if (isMain != main) continue;
                data << benchNumber(r.totalMs) << "," << benchPct(r.single.relRms) << ","
                     << benchPct(r.meanK.relRms) << "," << benchPct(r.gatherSingle.relRms) << ","
                     << benchPct(r.gatherMeanK.relRms) << ",\"" << r.config.shortLabel() << "\"\n";
            }
            if (data.str().empty()) continue;
            const std::string name = concat("$m", m, main ? "main" : "other");
            gp << name << " << EOD\n" << data.str() << "EOD\n";
            blocks.emplace_back(m, name);
        }
    gp << "\n";
    auto curves = [&](int column, int meanColumn, bool floorLines) {
        gp << "plot ";
        for (const auto& [m, name] : blocks) {
            const bool main = name.find("main") != std::string::npos;
            const auto it = work.mainResolution.find(kMethods[m]);
            if (main)
                gp << name << " using 1:" << column << " with linespoints lw 2 pt 7 lc rgb '" << kColours[m]
                   << "' title '" << kMethods[m] << " @" << (it == work.mainResolution.end() ? 0 : it->second)
                   << "', \\\n     " << name << " using 1:" << meanColumn << " with linespoints dt 2 pt 6 lc rgb '"
                   << kColours[m] << "'"
                   << " notitle, \\\n     ";
            else
                gp << name << " using 1:" << column << " with points pt 5 ps 1.3 lc rgb '" << kColours[m]
                   << "' notitle, \\\n     ";
            gp << name << " using 1:" << column << ":6 with labels font ',7' left offset char 0.5,0.4 tc rgb '"
               << kColours[m] << "' notitle, \\\n     ";
        }
        if (floorLines)
            gp << 100 * floorError
               << " with lines dt 3 lw 2 lc rgb 'gray30' title 'floor: exact gather of the source', "
               << "\\\n     " << 100 * pathNoise << " with lines dt 4 lc rgb 'gray60' title 'path tracer noise'\n\n";
        else
            gp << "1/0 notitle\n\n";
    };
    gp << "set output out_error\n"
          "set title \"Cornell box, "
       << pointCount
       << " points: error against the path tracer\\n"
          "solid: one gather; dashed: mean of "
       << work.passes
       << "; squares: other resolutions or near boxes; "
          "labels: N @voxels\"\n"
          "set logscale xy\n"
          "set xlabel 'median time per gather (ms, phases not timed)'\n"
          "set ylabel 'relative RMS error (%)'\n"
          "set key outside right top\n";
    curves(2, 3, true);
    gp << "set output out_gather\n"
          "set title \"The gathers alone: error against the exact-geometry gather of the same source\\n"
          "solid: one gather; dashed: mean of "
       << work.passes << "\"\n";
    curves(4, 5, false);

    gp << "$phases << EOD\n";
    for (const Row& r : rows)
        gp << "\"" << r.config.label() << "\"," << benchNumber(r.setupMs) << "," << benchNumber(r.drawMs) << ","
           << benchNumber(r.readbackMs) << "\n";
    gp << "EOD\n"
          "set output out_phases\n"
          "set title 'Median time of each phase per gather (glFinish between phases)'\n"
          "unset logscale\n"
          "unset xlabel\n"
          "set ylabel 'ms per gather'\n"
          "set key inside top center horizontal\n"
          "set style data histograms\n"
          "set style histogram rowstacked\n"
          "set style fill solid 0.85 border -1\n"
          "set boxwidth 0.75\n"
          "set xtics rotate by -45 left font ',8'\n"
          "set bmargin 10\n"
          "plot $phases using 2:xtic(1) title 'setup (CPU: culling or near field, upload)', "
          "$phases using 3 title 'draw', $phases using 4 title 'readback and sum'\n";
    return gp.str();
}

// --- Summary ---------------------------------------------------------------------------------------

// What the summary says of the run besides its tables.
struct RunInfo {
    size_t points = 0, fixedPoints = 0;
    size_t cacheVertices = 0, refineRounds = 0;
    int referenceSamples = 0, sourceRays = 0, passes = 0;
    double pathNoise = 0;  // RMS over points of the path tracer's relative standard error
    Errors floor;          // exact gather of the source against the path tracer
    double referenceSeconds = 0, wallSeconds = 0;
};

const Row* findRow(const std::vector<Row>& rows, const std::string& method, int size, int res) {
    for (const Row& r : rows)
        if (r.config.method == method && r.config.imageSize == size && r.config.resolution == res) return &r;
    return nullptr;
}

std::string verdictLine(const Comparison& c) {
    if (!c.perspective.reached)
        return concat("**yes**: the perspective gather never reaches its error (", c.perspective.how, ")");
    const double s = c.speedup();
    return concat(s >= kSpeedupTarget ? "**yes**" : "**no**", ": ", benchNumber(c.slicesMs), " ms against ",
                  benchNumber(c.perspective.ms), " ms, ", c.perspective.bounded ? "at most " : "", benchNumber(s),
                  "× (", c.perspective.how, ")");
}

// "walls / blocks / corners": a row's relative RMS error per group of points.
std::string groupErrors(const Row& r) {
    return concat(benchPct(r.byGroup.at(PointGroup::Walls).relRms), " / ",
                  benchPct(r.byGroup.at(PointGroup::Blocks).relRms), " / ",
                  benchPct(r.byGroup.at(PointGroup::Fixed).relRms));
}

// The irradiance volume's rows: what an update (every probe captured) and
// an estimate cost, against the paper's GPU timings, and what a GL cube map
// per probe would cost here (the hemicube of the paper's 16-pixel faces
// draws the proxy 5 times at 16×16 and 16×8; a cube map draws it 6 times at
// 16×16, so it costs at least as much).
std::string volumeSection(const std::vector<Row>& rows) {
    BenchTable t({"configuration", "probes", "update s", "ms per probe", "us per estimate", "rel. RMS %",
                  "walls / blocks / corners %"});
    size_t shown = 0;
    for (const Row& r : rows) {
        if (r.config.method != "volume") continue;
        const ProbeGrid& grid = r.probes;
        t.addRow({r.config.label(), concat(grid.dims[0], "x", grid.dims[1], "x", grid.dims[2]),
                  benchNumber(r.updateSeconds), benchNumber(1e3 * r.updateSeconds / double(grid.count())),
                  benchNumber(1e3 * r.totalMs), benchPct(r.single.relRms), groupErrors(r)});
        ++shown;
    }
    if (shown == 0) return {};
    std::ostringstream md;
    md << "\n## The irradiance volume (Nijasure et al.; issue 17)\n\n"
       << "Order-2 SH probes on a uniform grid (N @P: N×N rays per cube-map face, P probes along the box's longest "
          "side), captured by Embree rays reading the cache; 8 probes blended per point, weighted by a ray test to "
          "each (`blind`: without it). An update captures every probe on one thread.\n\n"
       << t.markdown();
    const Row* hemicube = findRow(rows, "hemicube", 16, 32);
    const Row* traced = findRow(rows, "volume", 16, 8);
    if (hemicube && traced) {
        const double rayMs = 1e3 * traced->updateSeconds / double(traced->probes.count());
        md << "\nRays or a GL cube map per probe, on this machine's OpenGL: a 16-pixel hemicube of the radiance proxy "
              "(5 draws, 16×16 and 4 × 16×8 pixels) takes "
           << benchNumber(hemicube->totalMs)
           << " ms, so a 16-pixel cube map (6 draws, twice the pixels) at least that; 1,536 traced rays per probe "
           << benchNumber(rayMs) << " ms, " << benchNumber(rayMs / hemicube->totalMs)
           << "× the hemicube. The volume traces: within a factor of two either way, the rays read the cache meshes "
              "where they land rather than a proxy resampled at voxels.\n";
    }
    md << "\nThe paper's claim (ATI Radeon 9800, 4×4×4 probes, 16×16 cube maps, 9 coefficients; 8,000 and "
          "80,000 triangles): rasterising the cube maps 67-86 ms, shading them 0.3-0.5 ms and the coefficients "
          "with L_indirect 11 ms for 2 iterations, 21-24 ms per frame with a moving light (40+ fps) and 107-110 ms "
          "with moving objects; their CPU+GPU version 2 s. Their error is shown in pictures against RADIANCE, not "
          "measured.\n";
    return md.str();
}

// The virtual point lights' rows: an update (placing the lights, then the
// negative ones with their rays) and an estimate, against the paper's frame
// rates; and the low-resolution pass on the camera's image, timed against
// evaluating every pixel (the paper's Table 2).
std::string vplSection(const std::vector<Row>& rows, const std::string& upsampling) {
    BenchTable t({"configuration", "update s", "us per estimate", "rel. RMS %", "walls / blocks / corners %"});
    size_t shown = 0;
    for (const Row& r : rows) {
        if (r.config.method != "vpl") continue;
        t.addRow({r.config.label(), benchNumber(r.updateSeconds), benchNumber(1e3 * r.totalMs),
                  benchPct(r.single.relRms), groupErrors(r)});
        ++shown;
    }
    if (shown == 0) return {};
    std::ostringstream md;
    md << "\n## Virtual point lights (Cochran & Steele; issue 17)\n\n"
       << "N lights placed by the Halton sequence over the source's reflected power, N/2 negative lights for their "
          "occlusion, picked among 4N candidate points whose first light an Embree ray decides (`blind`: no negative "
          "lights, the paper's simple indirect light); `+R rays`: the clamp's bias compensated by R cosine-weighted "
          "rays per estimate reading the cache near the point (none: the paper's, and contacts lose most of their "
          "light). The update places both on one thread; an estimate sums them. Errors against the path tracer as "
          "the rows above.\n\n"
       << t.markdown() << upsampling
       << "\nThe paper's claim (NVIDIA Quadro FX 5500, 640×480, a box and the 69,451-triangle bunny, one spotlight): "
          "26.5 fps with 100 lights and 50 negative ones, 15.6 with 200 and 100, 11.0 with 300 and 150 (32.6, 19.2 "
          "and 13.6 without negative lights), every frame placing the lights again; the low-resolution pass at "
          "87.5% of the pixels 26.5 fps against 12.6 with none (2.1×) at 0.17% RMS against the full resolution, at "
          "100% 42.5 fps (3.4×) at 1.5%. Their error against a reference is shown in pictures, not measured.\n";
    return md.str();
}

// The low-resolution pass on the Cornell box's camera view, lit by
// `lights` virtual point lights: every pixel evaluated, then the pass at
// 1/2 and 1/4 per axis, each timed (the G-buffers' tracing apart) and
// compared with every pixel evaluated.
std::string upsamplingSection(const Scene& scene, const std::vector<IrradianceMeshCopy>& source, int size, int lights) {
    VirtualPointLightSettings s;
    s.lights = lights;
    s.nearRays = 0;  // the paper's lights alone, as its pass (the compensation's rays are noise per pixel)
    VirtualPointLights vpl(scene, s);
    vpl.setSource(0, source);
    const IrradianceAt irradiance = [&](const Vec3& x, const Vec3& n) { return vpl.estimate(0, x, n, 0); };
    const EmbreeScene rays(scene);
    const Camera camera = scene.cameraOrDefault(1.0);
    Clock::time_point t = Clock::now();
    const ScreenSurfaces full = traceScreenSurfaces(rays, camera, size, size);
    const double traceFull = secondsSince(t);
    t = Clock::now();
    const std::vector<Rgb> reference = fullResolutionIndirect(full, irradiance);
    const double fullSeconds = secondsSince(t);
    double meanE = 0;
    size_t visible = 0;
    for (size_t p = 0; p < reference.size(); ++p)
        if (full.hit[p]) meanE += luminance(reference[p]), ++visible;
    meanE /= double(std::max<size_t>(visible, 1));
    BenchTable table({"pass", "low-res share %", "evaluations", "trace ms", "evaluate ms", "speed-up",
                      "RMS % of mean", "worst % of mean"});
    table.addRow({concat("full ", size, "x", size), "0", std::to_string(visible), benchNumber(1e3 * traceFull),
                  benchNumber(1e3 * fullSeconds), "1", "0", "0"});
    for (const int factor : {2, 4}) {
        UpsamplingSettings us;
        us.factor = factor;
        t = Clock::now();
        const ScreenSurfaces low = traceScreenSurfaces(rays, camera, size, size, factor);
        const double traceLow = secondsSince(t);
        t = Clock::now();
        const UpsampledIndirect up = upsampleIndirect(full, low, us, irradiance);
        const double seconds = secondsSince(t);
        double sum2 = 0, worst = 0;
        for (size_t p = 0; p < reference.size(); ++p) {
            if (!full.hit[p]) continue;
            const double d = luminance(up.irradiance[p]) - luminance(reference[p]);
            sum2 += d * d, worst = std::max(worst, std::abs(d));
        }
        table.addRow({concat("1/", factor, " per axis"), benchNumber(100 * up.lowShare()),
                      std::to_string(up.lowEvaluations + up.fullEvaluations), benchNumber(1e3 * traceLow),
                      benchNumber(1e3 * seconds), benchNumber(fullSeconds / seconds),
                      benchPct(std::sqrt(sum2 / double(std::max<size_t>(visible, 1))) / meanE),
                      benchPct(worst / meanE)});
    }
    std::ostringstream md;
    md << "\nThe low-resolution pass (UpsampledIndirect.h) on the camera's view at " << size << "×" << size << ", "
       << lights << " lights and their negative ones: indirect light evaluated at 1/k per axis and blended, except "
          "where the discontinuity buffer flags a pixel (normals 25° apart, or off the blended point's plane by "
          "1% of the depth), evaluated at full resolution; RMS and worst over every visible pixel, against evaluating "
          "each. Trace: the G-buffer's primary rays (the full one serves both).\n\n"
       << table.markdown();
    return md.str();
}

// The propagation volume's rows: an update (injection, then propagation)
// and an estimate, against the paper's GPU timings.
std::string lpvSection(const std::vector<Row>& rows) {
    BenchTable t({"configuration", "cells", "steps", "inject s", "propagate s", "ns per cell-step",
                  "us per estimate", "rel. RMS %", "walls / blocks / corners %"});
    size_t shown = 0;
    for (const Row& r : rows) {
        if (r.config.method != "lpv") continue;
        const PropagationGrid& g = r.lpvGrid;
        const double cellSteps = double(g.count()) * std::max(1, r.lpv.steps);
        t.addRow({r.config.label(), concat(g.dims[0], "x", g.dims[1], "x", g.dims[2]), std::to_string(r.lpv.steps),
                  benchNumber(r.lpv.injectSeconds), benchNumber(r.lpv.propagateSeconds),
                  benchNumber(1e9 * r.lpv.propagateSeconds / cellSteps), benchNumber(1e3 * r.totalMs),
                  benchPct(r.single.relRms), groupErrors(r)});
        ++shown;
    }
    if (shown == 0) return {};
    std::ostringstream md;
    md << "\n## Voxel light propagation with occlusion (Mavridis et al.; issue 17)\n\n"
       << "N cells along the box's longest side, order-2 SH per cell, the source injected as virtual point lights "
          "and propagated to the 6 neighbours over (nx-1)+(ny-1)+(nz-1) steps through a geometry volume of the "
          "faces' blocked share (`blind`: without it, Kaplanyan's plain propagation); a surface reads the flux "
          "absorbed at its cell's face. One thread, plain loops. Finer grids take more steps and the lattice's "
          "sideways spread grows with them: the error does not fall with the cell size.\n\n"
       << t.markdown()
       << "\nThe paper's claim (NVIDIA GTX 285, 32³ cells, 4 SH coefficients per channel): voxelization 3-10 ms "
          "and propagation 11-13 ms for 11-12 steps (61 ms for 64 steps in their room), 2.8e-5 ms per cell and "
          "step (28 ns); their error is shown in pictures against a ray-traced reference, not measured.\n";
    return md.str();
}

// The propagation's steps on the CPU (the estimator's loops, double, one
// thread) and as a GL compute shader (PropagationCompute, float), on the
// same injected light of the bench's source: which is faster on this GL.
// Quick mode leaves out 32 cells: 134 s of llvmpipe compute, where 8 and 16
// already show the ratio.
std::string lpvComputeSection(GlContext& context, const Scene& scene, const std::vector<IrradianceMeshCopy>& source,
                              bool quick) {
    BenchTable t({"cells", "steps", "CPU s", "GL compute s", "GL upload + readback ms", "GL / CPU"});
    for (const int cells : quick ? std::vector<int>{8, 16} : std::vector<int>{8, 16, 32}) {
        PropagationVolumeSettings s;
        s.cells = cells;
        PropagationVolume v(scene, s);
        const std::vector<ShRgb> injected = v.inject(source);
        v.propagateInjected(0, injected);
        const PropagationVolume::Report& cpu = v.report(0);
        PropagationCompute gpu(context, v);
        gpu.propagate(injected, 1);  // untimed: the first dispatch compiles the shader
        const PropagationCompute::Result r = gpu.propagate(injected, cpu.steps);
        const PropagationGrid& g = v.grid();
        t.addRow({concat(g.dims[0], "x", g.dims[1], "x", g.dims[2]), std::to_string(cpu.steps),
                  benchNumber(cpu.propagateSeconds), benchNumber(r.propagateSeconds),
                  benchNumber(1e3 * (r.uploadSeconds + r.readbackSeconds)),
                  benchNumber(r.propagateSeconds / cpu.propagateSeconds)});
    }
    std::ostringstream md;
    md << "\nThe same steps as a GL compute shader (propagate_step.comp: a cell per invocation gathering from its 6 "
          "neighbours, 4×4×4 work groups, float) against the estimator's CPU loops (double, one thread), on the "
          "source's injected light:\n\n"
       << t.markdown();
    return md.str();
}

std::string summaryMarkdown(const BenchRun& run, const RunInfo& info, const std::vector<Row>& rows,
                            const std::vector<Comparison>& cs) {
    std::ostringstream md;
    md << "# Indirect light: seven gathers and the irradiance volume on one source, error against time (§6.2)\n\n"
       << "- OpenGL: " << run.glDescription() << "\n"
       << "- mode: " << run.mode() << ", seed " << run.options().seed << ", wall time "
       << benchNumber(info.wallSeconds) << " s\n"
       << "- scene: the Cornell box; source: its direct-light cache sampled exactly (ExactDirect) at every vertex "
          "of its base mesh, then refined "
       << info.refineRounds << " rounds with the exact sampler (" << info.cacheVertices << " vertices)\n"
       << "- points: " << info.points << " (" << info.points - info.fixedPoints
       << " random by area, none inside a block; " << info.fixedPoints
       << " fixed in corners, along contacts, beside the light)\n"
       << "- reference: the path tracer's one-bounce indirect irradiance (max depth 2), " << info.referenceSamples
       << " samples per point; its RMS relative standard error is " << benchPct(info.pathNoise) << " %\n"
       << "- floor: the exact-geometry gather of the source (" << info.sourceRays
       << " stratified cosine-weighted Embree rays per point, the cache's irradiance where they land) is "
       << benchPct(info.floor.relRms) << " % RMS from the path tracer (mean " << benchPct(info.floor.meanRel)
       << " %, max " << benchPct(info.floor.maxRel) << " %): the cache's interpolation error, under every method\n"
       << "- each configuration: one phase-timed gather per point, then " << info.passes - 1
       << " more with fresh jitter; time = median wall time per gather without glFinish between phases\n"
       << softwareRasteriserNote(run.glDescription());

    md << "\n## The target: slices at least " << kSpeedupTarget
       << "× faster than the perspective triangle gather at equal error\n\n";
    const Row* paper = findRow(rows, "slices", kPaperImage, kPaperVoxels);
    std::vector<const Comparison*> shown;
    for (const Comparison& c : cs)
        if (paper ? c.slices == paper->config.label() : true) shown.push_back(&c);
    if (shown.empty()) md << "No slice configuration ran.\n";
    for (const Comparison* c : shown)
        md << "- " << c->slices << ", error " << c->metric << " (" << benchPct(c->slicesError) << " %), against "
           << c->against << ": " << verdictLine(*c) << "\n";
    md << "\nThe paper measured 18 ms (slices, 40×40) against 46 ms (perspective, 128×128) on a 7,000-triangle office "
          "on a GPU. Every slice configuration's comparison is in indirect_equal_error.csv.\n";

    BenchTable methods({"configuration", "ms per gather", "setup / draw / readback ms", "rel. RMS %",
                        concat("mean of ", info.passes, " %"), "gather alone %", "walls / blocks / corners %"});
    for (const Row& r : rows)
        methods.addRow({r.config.label(), benchNumber(r.totalMs),
                        concat(benchNumber(r.setupMs), " / ", benchNumber(r.drawMs), " / ", benchNumber(r.readbackMs)),
                        benchPct(r.single.relRms), benchPct(r.meanK.relRms), benchPct(r.gatherSingle.relRms),
                        concat(benchPct(r.byGroup.at(PointGroup::Walls).relRms), " / ",
                               benchPct(r.byGroup.at(PointGroup::Blocks).relRms), " / ",
                               benchPct(r.byGroup.at(PointGroup::Fixed).relRms))});
    md << "\n## Per method (one gather; error against the path tracer)\n\n" << methods.markdown();
    md << "\nConfigurations are `method N @R [nearK]`: N pixels per side (hemicube: of its top face; its sides are "
          "N × N/2), R voxels along the box's longest side (slices, raymarch: the voxel grid, near box of K voxels "
          "each way, 0 if not said; triangle methods: the radiance proxy they draw, pieces at most two voxels "
          "across). \"gather alone\" is "
          "the error against the exact-geometry gather of the same source, which removes the cache's own error; "
          "walls, blocks and corners split the path-tracer error by where the points lie (random points on the box's "
          "walls, floor and ceiling; random points on the two rotated blocks; the fixed points).\n\n"
          "What each method leaves out: the 160° perspective image misses the grazing directions beyond its field, "
          "2.5% of a uniform sky's irradiance (its error cannot fall below that where light arrives evenly); the "
          "fish-eye triangle gather bends no edges, so triangles near the eye are drawn too small or too large; "
          "the voxel methods see the scene through voxel faces beyond the near box (the point's voxel and `near` "
          "more each way, drawn as triangles): a surface is drawn on the faces of every voxel it passes through, up to "
          "a voxel in front of where it is, so a point on a surface slanted in the grid (the rotated blocks) or "
          "within a voxel of another surface (corners, contacts) is shadowed by voxel faces of its own or its "
          "neighbour's surface; larger near boxes reduce it, at a cost.\n\nTables: indirect_methods.csv (every "
          "configuration), "
          "indirect_equal_error.csv (the target), indirect_points.csv (points and references).\n";
    md << volumeSection(rows);
    return md.str();
}

}  // namespace

int runBenchIndirect(const BenchOptions& options) {
    BenchRun run(options);
    const Workload work = workloadFor(options);
    const std::unique_ptr<GlContext> context = run.openContext();

    // The source: the direct cache's base mesh, sampled exactly.
    const Scene scene = makeCornellBox();
    IrradianceCache cache(scene);
    size_t refineRounds = 0;
    {
        const ExactDirect exact(scene);
        auto irradiance =
            samplerOf([&](size_t light, const Vec3& x, const Vec3& n, uint32_t) { return exact.irradiance(light, x, n); });
        sampleEveryVertex(cache, irradiance, 1, options.seed);
        auto sample = samplerOf([&](size_t light, const Vec3& x, const Vec3& n, uint32_t) {
            VertexSample v;
            v.irradiance = exact.irradiance(light, x, n);
            const double open = exact.unoccludedCosineSolidAngle(light, x, n);
            v.visibility = open > 0 ? std::clamp(exact.cosineSolidAngle(light, x, n) / open, 0.0, 1.0) : 1.0;
            v.partial = v.visibility > 1e-9 && v.visibility < 1 - 1e-9;
            return v;
        });
        for (size_t spent = 0; spent < work.refineEstimates;) {
            const RefineReport r = cache.refine(sample, work.refineEstimates - spent, options.seed);
            ++refineRounds;
            spent += r.estimates;
            if (r.converged() || r.estimates == 0) break;
        }
    }
    run.progress("source cache: %zu vertices after %zu refinement rounds\n", cache.totalVertices(), refineRounds);
    std::vector<IrradianceMeshCopy> source = cache.copyMeshes();

    // Points and references.
    const EmbreeScene rays(scene);
    std::vector<BenchPoint> points = areaPoints(scene, rays, work.areaPoints, options.seed);
    const std::vector<BenchPoint> fixed = fixedPoints(scene);
    points.insert(points.end(), fixed.begin(), fixed.end());
    run.progress("references at %zu points\n", points.size());
    const Clock::time_point refStart = Clock::now();
    std::vector<PointReference> refs(points.size());
    const int threads = int(std::clamp(std::thread::hardware_concurrency(), 1u, 2u));
    {
        PathTracerSettings pts;
        pts.maxDepth = 2;  // direct + one bounce: its `indirect` is the first bounce
        pts.threads = threads;
        pts.seed = options.seed;
        const PathTracer tracer(rays, pts);
        for (size_t i = 0; i < points.size(); ++i) {
            const IrradianceEstimate e =
                tracer.irradiance(points[i].x, points[i].n, work.referenceSamples, uint32_t(i));
            refs[i].path = luminance(e.indirect);
            refs[i].pathSe = luminance(e.indirectError);
        }
        const double diagonal = scene.bounds.diagonal();
        // What a perfect gather of the source gives: the ray gather's own
        // work (gatherCachedRadiance: cosine-weighted rays on exact geometry,
        // each taking Kd/π × the cache's irradiance where it lands), side ×
        // side stratified.
        std::vector<MeshIrradianceLookup> lookups;
        for (const IrradianceMeshCopy& m : source) lookups.emplace_back(m, diagonal / 64, 1e-5 * diagonal);
        std::vector<const MeshIrradianceLookup*> pointers;
        for (const MeshIrradianceLookup& l : lookups) pointers.push_back(&l);
        const std::vector<char> closed = closedMeshesOf(scene);
        parallelFor(points.size(), threads, [&](size_t i) {
            refs[i].source = luminance(gatherCachedRadiance(scene, rays, closed, pointers, points[i].x, points[i].n,
                                                            work.sourceRaysSide, seedFor(options.seed, uint32_t(i), 7)));
        });
    }
    RunInfo info;
    info.referenceSeconds = secondsSince(refStart);
    {
        double sum = 0;
        size_t n = 0;
        std::vector<double> path, src;
        for (const PointReference& r : refs) {
            if (r.path > 0) sum += (r.pathSe / r.path) * (r.pathSe / r.path), ++n;
            path.push_back(r.path);
            src.push_back(r.source);
        }
        info.pathNoise = n ? std::sqrt(sum / double(n)) : 0;
        info.floor = errorsOf(src, path);
    }
    run.progress("references done in %.1f s: path tracer noise %.3g %%, floor %.3g %%\n", info.referenceSeconds,
                 100 * info.pathNoise, 100 * info.floor.relRms);

    std::vector<Row> rows;
    for (const Config& c : work.configs) {
        run.progress("%s\n", c.label().c_str());
        rows.push_back(measure(*context, scene, source, c, points, refs, work.passes, options.seed));
    }
    const std::vector<Comparison> comparisons = compare(rows);

    const BenchTable methodsT = methodsTable(rows, work.passes), compareT = comparisonTable(comparisons);
    std::printf(
        "\nIndirect gathers on the Cornell box, %zu points (ms per gather; rel_rms: relative RMS error of one "
        "gather against the path tracer; gather_rel_rms: against the exact gather of the source).\n"
        "Floor (exact gather of the source against the path tracer): %s %%; path tracer noise %s %%.\n\n%s",
        points.size(), benchPct(info.floor.relRms).c_str(), benchPct(info.pathNoise).c_str(),
        methodsT.aligned().c_str());
    std::printf("\nSlices against the perspective triangle gather at equal error (target: %gx faster).\n\n%s",
                kSpeedupTarget, compareT.aligned().c_str());
    std::printf("%s", volumeSection(rows).c_str());
    const std::string lpv = lpvSection(rows) + lpvComputeSection(*context, scene, source, options.quick);
    std::printf("%s", lpv.c_str());
    const std::string vpl = vplSection(rows, upsamplingSection(scene, source, options.quick ? 128 : 320, 256));
    std::printf("%s", vpl.c_str());

    run.writeCsv("indirect_methods.csv", methodsT);
    run.writeCsv("indirect_equal_error.csv", compareT);
    run.writeCsv("indirect_points.csv", pointsTable(points, refs));
    run.plot("indirect_plots.gp", gnuplotScript(rows, work, info.floor.relRms, info.pathNoise, points.size()), kPlots);
    info.points = points.size();
    info.fixedPoints = fixed.size();
    info.cacheVertices = cache.totalVertices();
    info.refineRounds = refineRounds;
    info.referenceSamples = work.referenceSamples;
    info.sourceRays = work.sourceRaysSide * work.sourceRaysSide;
    info.passes = work.passes;
    info.wallSeconds = run.seconds();
    run.write("indirect_summary.md", summaryMarkdown(run, info, rows, comparisons) + vpl + lpv);
    std::printf("\n");
    run.printWallTime(info.wallSeconds);
    return 0;
}

}  // namespace ml
