#include "Plan.h"

#include "core/image/Photometry.h"

#include "cache/LightCoverage.h"
#include "cache/SharedLightSampler.h"

#include "Commands.h"
#include "cache/CausticCache.h"
#include "cache/GridCache.h"
#include "core/raytrace/EmbreeScene.h"
#include "gpu_sampling/indirect/RadianceProxy.h"
#include "gpu_sampling/indirect/VoxelGrid.h"
#include "core/Error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ml {

namespace {

// A light seen from everywhere in the scene under less than a sampling
// pixel's angle casts shadows no softer than a point light's.
bool actsAsPoint(const Light& light, const Scene& scene, const DirectChoice& choice) {
    const double pixelAngle = 2 * std::tan(glm::radians(choice.sampler.maxHalfAngleDegrees)) / choice.sampler.imageSize;
    // The light's size against the smallest distance that matters: 1% of the
    // scene (closer receivers are few).
    return light.bounds.diagonal() < pixelAngle * 0.01 * scene.bounds.diagonal();
}

}  // namespace

void declareCacheOptions(Options& o) {
    const CacheSettings d;
    o.value("cache-edge", "F", "base cache mesh edges at most F x the scene diagonal", concat(d.maxEdgeFraction));
    o.value("min-edge", "F", "refinement stops at edges of F x the scene diagonal", concat(d.minEdgeFraction));
    o.value("min-edge-pixels", "P", "...and at edges P pixels long on screen", concat(d.minEdgePixels));
    o.value("split-tolerance", "T", "split edges while the predicted relative error exceeds T",
            concat(d.splitTolerance));
    o.value("light-share", "F", "a light keeps a cache mesh of its own where it gives at least F of the direct "
                                "light (by a bound from power, distance, orientation); elsewhere one mesh shared by "
                                "the lights carries it; 0: a mesh per light everywhere",
            concat(d.lightShare));
    o.value("shared-rays", "N",
            "the shared mesh's occluded light from N shadow rays to points on lights drawn by their share, where "
            "more lights are left than the light sampler's pairs would take; 0: the light sampler's pairs always "
            "(--method exact sets 0)",
            concat(d.sharedRays));
    o.value("noise-tolerance", "T", "resample vertices while their relative standard error exceeds T",
            concat(d.noiseTolerance));
    o.value("max-vertices", "N", "vertex budget over all cache meshes", concat(d.maxVertices));
    o.value("light-planes", "on|off",
            "direct light's base meshes are cut where a surface crosses the plane of a planar light near it (behind "
            "it the light gives nothing, in front it grows from 0: a kink no split finds), and where that light "
            "bends in front of the plane when the nearest light is closer than half a base edge (cache/README.md)",
            d.lightPlaneCuts ? std::string("on") : std::string("off"));
}

CacheSettings readCacheSettings(const Options& o) {
    CacheSettings c;
    c.maxEdgeFraction = o.number("cache-edge", 1e-5, 1.0);
    c.minEdgeFraction = o.number("min-edge", 1e-7, 1.0);
    c.minEdgePixels = o.number("min-edge-pixels", 0, 1e4);
    c.splitTolerance = o.number("split-tolerance", 1e-6, 0.999);
    c.lightShare = o.number("light-share", 0, 1);
    const double rays = o.number("shared-rays", 0, 65536);
    if (rays != std::floor(rays))
        throw InputError(concat("--shared-rays: '", o.str("shared-rays"), "' is not a whole number"));
    // The exact reference stays exact where lights share (every command
    // that reads these declares the direct sampler's options).
    c.sharedRays = o.str("method") == "exact" ? 0 : int(rays);
    c.noiseTolerance = o.number("noise-tolerance", 1e-6, 0.999);
    const std::string planes = o.str("light-planes");
    if (planes != "on" && planes != "off")
        throw InputError(concat("--light-planes: '", planes, "' is neither on nor off"));
    c.lightPlaneCuts = planes == "on";
    c.maxVertices = size_t(o.number("max-vertices", 3, 1e9));
    c.validate();
    return c;
}

// Where the bounces' base meshes are cut along contacts (ContactCuts.h).
void printContactCuts(const Scene& scene, const CacheSettings& bounces) {
    if (!(bounces.contactCloseness > 0)) {
        std::printf("  contact cuts: none (--contact-cuts 0)\n");
        return;
    }
    ContactCutReport r;
    cacheSurfaces(scene, bounces, &r);
    if (r.receivers)
        std::printf("  contact cuts: the bounces' meshes are cut where a surface hangs within %.3g x its edge's "
                    "length in front of another (indirect light darkens there within the gap's length, and "
                    "the gathers' noise hides it from refinement): %zu triangles cut along %zu segments (outlines, "
                    "and penumbra lines) into %zu, %zu vertices added, %zu faces thinner than 1e-6 of the scene left "
                    "out (cache/ContactCuts.h)\n",
                    bounces.contactCloseness, r.receivers, r.segments, r.triangles, r.vertices, r.dropped);
    else
        std::printf("  contact cuts: none (no surface hangs close in front of another)\n");
}

// Where direct light's base meshes are cut along the lights' planes
// (ContactCuts.h, CutPlane).
void printLightPlaneCuts(const Scene& scene, const CacheSettings& direct) {
    if (!direct.lightPlaneCuts) {
        std::printf("  light planes: not cut (--light-planes off; on, the default, cuts direct light's meshes "
                    "along them: cache/README.md)\n");
        return;
    }
    CacheSettings planesOnly = direct;
    planesOnly.contactCloseness = 0;
    ContactCutReport r;
    cacheSurfaces(scene, planesOnly, &r);
    const size_t planes = r.planes;
    if (r.planeSegments)
        std::printf("  light planes: direct light's meshes are cut where a surface crosses the plane of a planar "
                    "light near it (behind the plane the light gives nothing, in front it grows from 0: a kink "
                    "between vertices that no split finds), and where that light bends if that is nearer than half "
                    "a base edge: %zu planes, %zu triangles cut along %zu segments, %zu vertices added "
                    "(cache/ContactCuts.h)\n",
                    planes, r.receivers, r.planeSegments, r.vertices);
    else
        std::printf("  light planes: no cut (%s)\n",
                    planes ? "no surface crosses a planar light's plane by more than a thousandth of the scene near it"
                           : "no planar area light");
}

// What a light is and how its direct light is sampled, for the plan.
std::string describeLight(const Light& l, const Scene& scene, const DirectChoice& choice) {
    const Photometry photometry;  // lumens in RADIANCE's convention (PunctualLight.h)
    const double s = scene.metresPerUnit;
    const std::string flux = concat(photometry.luminous(l.power()) * s * s, " lm");
    const std::string group = l.group.empty() || l.group == l.name ? std::string() : concat(", group '", l.group, "'");
    if (l.kind == LightKind::Directional)
        return concat("directional, travelling along (", l.emission.axis.x, ", ", l.emission.axis.y, ", ",
                      l.emission.axis.z, "), ", photometry.luminous(l.emission.intensity), " lx on a surface facing it",
                      group, "; direct light by one shadow ray per vertex (parallel light: hard shadows, no "
                      "soft-shadow sampling)");
    if (l.kind == LightKind::Point) {
        const PunctualEmission& e = l.emission;
        return concat("point at (", e.position.x, ", ", e.position.y, ", ", e.position.z, "), ",
                      e.profile.describe(), e.profile.shape == IntensityProfile::Shape::Isotropic
                                                ? std::string()
                                                : concat(" aimed along (", e.axis.x, ", ", e.axis.y, ", ", e.axis.z, ")"),
                      ", peak ", photometry.luminous(e.intensity), " cd, ", flux, group,
                      "; direct light by one shadow ray per vertex (a point: hard shadows, no soft-shadow "
                      "sampling), refined along shadow edges down to the view's pixels");
    }
    const bool point = actsAsPoint(l, scene, choice);
    return concat(l.triangles.size(), " triangles, area ", l.area, ", ", l.planar ? "planar" : "not planar", ", ",
                  flux, group, "; ",
                  point ? "smaller than a sampling pixel from 1% of the scene away: hard shadows, one visibility "
                          "test per pixel would do (still sampled as an area light)"
                        : "an area light: soft shadows, sampled with jittered tests",
                  "; direct light by ", choice.describe());
}

// The display-time specular pass (viewer/compositor/SpecularPaths.h): what
// runs, and where its Phong highlights are an approximation.
static void printSpecularPass(const Scene& scene) {
    size_t smooth = 0, glossy = 0;
    double widestLobe = 0, sharpest = 0;  // sr: ∫cosⁿα dω = 2π/(Ns + 1)
    double largestNs = 0;
    std::vector<char> used(scene.materials.size(), 0);  // by some face, as SpecularPaths::needed counts
    for (const Mesh& m : scene.meshes)
        for (uint32_t material : m.materials) used[material] = 1;
    for (size_t i = 0; i < scene.materials.size(); ++i) {
        const Material& m = scene.materials[i];
        if (!used[i]) continue;
        smooth += m.specular() ? 1 : 0;
        if (!m.glossy()) continue;
        ++glossy;
        const double lobe = 2 * kPi / (std::max(m.ns, 0.0) + 1);
        largestNs = std::max(largestNs, m.ns);
        widestLobe = std::max(widestLobe, lobe);
        sharpest = sharpest > 0 ? std::min(sharpest, lobe) : lobe;
    }
    if (smooth + glossy == 0) {
        std::printf("  specular: no pass (no material is glossy, Ks > 0, or a mirror or glass)\n");
        return;
    }
    std::printf("  specular: a display-time pass, traced on the CPU (Embree) for the sub-pixels inside the screen "
                "rectangles of glossy and specular surfaces, again whenever the view, the lights' switches or the "
                "cache change, and added to the composite (render's EXR: layer 'specular')\n");
    if (smooth > 0)
        std::printf("    mirrors and glass (%zu materials): reflected and refracted (Fresnel, Ni, Tf) to the surface "
                    "where each path ends, read from the cache there; glass splits into both branches while a "
                    "branch's weight is at least 1e-3; a path still on a specular surface after 8 is black\n",
                    smooth);
    if (glossy == 0) return;
    // A light's largest solid angle Ω seen from a glossy face (its point
    // nearest to the light's centroid): the lobe evaluated towards the
    // light's centroid overstates the highlight's peak by about Ns·Ω/12
    // (cosⁿα ≈ e^(−nα²/2) averaged over a square light; measured +2.6% over
    // the peak's pixels for Ns 50 and Ω 0.01 sr against the path tracer),
    // and blurs its shape less than it should.
    std::printf("    Phong highlights (%zu materials, lobes of %.3g to %.3g sr): each light's cached direct "
                "irradiance times the lobe towards the light's centroid (a punctual light's position); exact for a "
                "light small against the lobe; the mesh lights share (if the cache makes one) gives none\n",
                glossy, sharpest, widestLobe);
    for (const Light& l : scene.lights) {
        if (l.punctual()) continue;
        double widest = 0;
        for (const Mesh& m : scene.meshes)
            for (size_t t = 0; t < m.triangles.size(); ++t) {
                if (!scene.materials[m.materials[t]].glossy()) continue;
                const Triangle3 p = m.triangle(t);
                const Vec3 w = closestBarycentric(l.centroid, p[0], p[1], p[2]);
                const Vec3 d = l.centroid - (w.x * p[0] + w.y * p[1] + w.z * p[2]);
                const double d2 = glm::dot(d, d);
                if (d2 > 0) widest = std::max(widest, std::min(2 * kPi, l.area * std::abs(glm::dot(l.normal, d)) /
                                                                             (d2 * std::sqrt(d2))));
            }
        if (largestNs * widest / 12 > 0.01)
            std::printf("    light '%s' subtends up to %.3g sr from glossy surfaces, not small against the %.3g sr "
                        "lobe: the peaks of its highlights there are too bright by up to about %.2g%% (Ns Ω/12)\n",
                        l.name.c_str(), widest, sharpest, 100 * std::min(1.0, largestNs * widest / 12));
    }
}

// The mirrors and glass the faces use, as the loaders read them, and how
// the reference path tracer treats them.
static void printSpecularMaterials(const Scene& scene) {
    std::vector<char> used(scene.materials.size(), 0);
    for (const Mesh& m : scene.meshes)
        for (uint32_t material : m.materials) used[material] = 1;
    std::string list;
    for (size_t i = 0; i < scene.materials.size(); ++i) {
        const Material& m = scene.materials[i];
        if (!used[i] || !m.specular()) continue;
        const SmoothSpecular& s = m.smooth;
        list += concat(list.empty() ? "" : ", ", "'", m.name, "' ");
        if (s.kind == SpecularKind::Mirror)
            list += concat("mirror (reflectance ", s.reflectance.r, " ", s.reflectance.g, " ", s.reflectance.b,
                           s.schlick ? ", rising to 1 at grazing incidence)" : ")");
        else
            list += concat("glass (ior ", s.ior, ", Tf ", s.transmission.r, " ", s.transmission.g, " ",
                           s.transmission.b, ")");
    }
    if (list.empty()) return;
    std::printf("  specular materials: %s; the path tracer (reference) follows their reflections and refractions, "
                "and finds light reaching other surfaces through them by path sampling only (shadow rays stop at "
                "them)\n",
                list.c_str());
}

// Caustics (cache/CausticCache.h): whether a light sees a specular object,
// and how the light it sends on is traced.
static void printCaustics(const Scene& scene, const IndirectChoice& indirect) {
    if (std::none_of(scene.materials.begin(), scene.materials.end(), [](const Material& m) { return m.specular(); })) {
        std::printf("  caustics: none (no mirror or glass)\n");
        return;
    }
    if (!indirect.active()) {
        std::printf("  caustics: not traced: they are indirect light, and indirect light is off\n");
        return;
    }
    const EmbreeScene rays(scene);
    const CausticPhotons photons(scene, rays);
    if (!photons.active()) {
        std::printf("  caustics: none: %s\n", photons.describe().c_str());
        return;
    }
    const CausticSettings c;
    std::printf("  caustics: %s; photons aimed at their bounding spheres and followed through mirrors and glass "
                "(one Fresnel branch each), %zu a round once direct light's first pass is complete, kept where they "
                "first meet a diffuse surface; progressive photon mapping (alpha %.2g, first radius 1/%.0f of the "
                "scene) at the vertices of a mesh of edges 1/%.0f of the scene, until its noise is under %.3g; shown "
                "as indirect light and reflected by bounce 1\n",
                photons.describe().c_str(), c.photonsPerRound, c.alpha, 1 / c.radiusFraction, 1 / c.edgeFraction,
                c.tolerance);
}

void printPlan(const Scene& scene, const DirectChoice& choice, const CacheSettings& cache,
               const IndirectChoice& indirect) {
    std::printf("plan:\n");
    // Many lights: the first few, then a count of each kind.
    constexpr size_t kListed = 8;
    size_t area = 0, punctual = 0;
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        const Light& l = scene.lights[i];
        if (i >= kListed && scene.lights.size() > kListed + 1) {
            (l.punctual() ? punctual : area)++;
            continue;
        }
        std::printf("  light '%s': %s\n", l.name.c_str(), describeLight(l, scene, choice).c_str());
    }
    if (area + punctual > 0)
        std::printf("  ... and %zu more lights (%zu area, %zu punctual), each sampled as its kind is above\n",
                    area + punctual, area, punctual);
    if (scene.lights.empty()) std::printf("  no light (no emissive material, no punctual light): the image is black\n");
    const double maxEdge = cache.maxEdgeFraction * scene.bounds.diagonal();
    size_t grids = 0;
    for (const Mesh& m : scene.meshes) {
        const GridCacheDecision d = decideGridCache(m, maxEdge);
        if (!d.useGrid) continue;
        ++grids;
        std::printf("  grid cache: %s\n", d.reason.c_str());
    }
    std::printf("  cache: one mesh per light over %zu objects, edges at most %.4g (1/%.0f of the scene), refined "
                "where irradiance is not linear or visibility is partial; %s\n",
                scene.meshes.size() - grids, maxEdge, 1 / cache.maxEdgeFraction,
                grids ? "grid caches for the objects above" : "no object is tessellated finely enough for a grid cache");
    printLightPlaneCuts(scene, cache);
    if (scene.lights.size() > 1) {
        const LightCoverage coverage(scene, cache.lightShare, indirect.solver.gatheredLights);
        const std::string rays =
            !coverage.sharing() ? ""
            : cache.sharedRays > 0
                ? concat("; the shared mesh's shadows from ", cache.sharedRays,
                         " shadow rays an estimate, to points on its lights drawn by their share, where over ",
                         SharedLightSampler::kDraws,
                         " lights are left to draw (below that each light's pair is sampled, exact; curved lights "
                         "always by pairs)")
                : concat("; the shared mesh's shadows from ", SharedLightSampler::kDraws,
                         " lights' pairs an estimate (--shared-rays 0)");
        std::printf("  lights: %s%s\n", coverage.describe().c_str(), rays.c_str());
    }
    const BounceCount& b = indirect.bounceCount;
    std::printf("  albedo that direct light meets: %.3f %.3f %.3f (area- and irradiance-weighted), %.3f in its "
                "largest channel; bounce 2 carries %.3f of bounce 1's light (by rays; area-weighted albedo %.3f): "
                "the ratio of the bounces not yet gathered in an early image\n",
                b.albedo.r, b.albedo.g, b.albedo.b, b.meanAlbedo, b.bounceRatio, b.areaAlbedo);
    if (!indirect.enabled) {
        std::printf("  indirect light: not simulated (--direct-only); about %.3g%% of the reflected light is left out\n",
                    100 * b.meanAlbedo);
    } else if (indirect.solver.bounces == 0) {
        std::printf("  indirect light: none: %s\n", b.reason.c_str());
    } else {
        std::printf("  indirect light: %s\n", b.reason.c_str());
        std::printf("  indirect gather: %s; %s\n", indirect.describe().c_str(), indirect.methodReason.c_str());
        std::printf("  gathered lights: %s\n", indirect.gatheredReason.c_str());
        // The slice, raymarch and triangle gathers draw a proxy cut to
        // voxels; the ray gather reads the cache itself, and the volume, the
        // virtual point lights and the propagation volume have grids of their own.
        const bool voxelProxy = indirect.method != "raytrace" && indirect.method != "volume" &&
                                indirect.method != "vpl" && indirect.method != "lpv";
        if (voxelProxy) {
            const VoxelGrid grid = VoxelGrid::fit(scene.bounds, indirect.gather.resolution);
            std::printf("  voxel grid: %s voxels of %.4g, at most %d slice faces of %.1f MB in all per bounce "
                        "(empty faces are freed)\n",
                        grid.describe().c_str(), grid.voxel, 2 * (grid.dims[0] + grid.dims[1] + grid.dims[2]),
                        // RGBA32F radiance and R32F depth per texel, two faces per slice, three axes.
                        20.0 * 2 * (double(grid.dims[0]) * grid.dims[1] * grid.dims[2]) * 3 / 1e6);
        }
        const CacheSettings& ic = indirect.solver.cache;
        const CacheSettings first = bounceCacheSettings(indirect.solver, 1);
        std::printf("  indirect caches: one mesh per bounce, edges at most 1/%.0f of the scene (%s), then split down "
                    "to 1/%.0f once gathered (linear interpolation reads indirect light dark where it falls towards "
                    "corners and contacts, and the gathers' noise hides the curvature that would ask for the splits); "
                    "split tolerance %.3g, noise tolerance %.3g for bounce 1, relaxed by 1/%.3g per further bounce; "
                    "the bounce refined next is the one whose share of the image's error is largest; indirect light "
                    "starts %s\n",
                    1 / ic.maxEdgeFraction, indirect.baseReason.c_str(), 1 / first.uniformEdgeFraction,
                    ic.splitTolerance, ic.noiseTolerance, b.meanAlbedo,
                    concat("once direct light's first pass is complete, or once ", 100 * indirect.solver.startFraction,
                           "% of it is done if the rest would take over ", indirect.solver.startSeconds,
                           " s (a coarse first bounce is then in the first complete image, and bounce 1 is gathered "
                           "again when direct light is complete; not under --samples, whose cache must not depend on "
                           "the machine's speed), and shares the worker with direct light by their errors; a "
                           "bounce's first pass (its base gathered once) spends at most ",
                           indirect.solver.firstPassGathers, " full gathers: a larger base is gathered first with "
                           "that share of a gather's effort each, then refined at full effort").c_str());
        printContactCuts(scene, ic);
    }
    printSpecularPass(scene);
    printSpecularMaterials(scene);
    printCaustics(scene, indirect);
}

int runPlan(const std::vector<std::string>& args) {
    Options o("plan");
    declareSceneOptions(o);
    declareDirectOptions(o);
    declareCacheOptions(o);
    declareIndirectOptions(o);
    o.flag("direct-only", "direct light only");
    if (!o.parseOrPrintHelp(args)) return 0;
    const DirectChoice choice = readDirectOptions(o);
    const CacheSettings cache = readCacheSettings(o);
    IndirectChoice indirect = readIndirectOptions(o);
    const Scene scene = loadScene(o);
    for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    std::printf("scene '%s': %zu meshes, %zu triangles, %zu lights\n", scene.name.c_str(), scene.meshes.size(),
                scene.triangleCount(), scene.lights.size());
    indirect.decide(scene);
    printPlan(scene, choice, cache, indirect);
    return 0;
}

}  // namespace ml
