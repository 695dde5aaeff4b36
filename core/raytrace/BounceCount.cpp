#include "BounceCount.h"

#include "PunctualShadow.h"

#include "EmbreeScene.h"
#include "core/Error.h"
#include "core/ParallelFor.h"
#include "core/Random.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <thread>
#include <vector>

namespace ml {

void BounceCountSettings::validate() const {
    if (!(missingFraction > 0 && missingFraction < 1))
        throw InputError(concat("indirect tolerance ", missingFraction, " is not in (0, 1)"));
    if (maxBounces < 1 || maxBounces > 256)
        throw InputError(concat("maximum bounce count ", maxBounces, " is not in 1..256"));
    if (forced && (*forced < 0 || *forced > 256)) throw InputError(concat("--bounces ", *forced, " is not in 0..256"));
    if (points < 1 || lightSamples < 1) throw InputError("bounce plan: at least one point and one light sample");
    if (everyLightUpTo < 1 || threads < 0)
        throw InputError(concat("bounce plan: everyLightUpTo ", everyLightUpTo, " (at least 1) or threads ", threads,
                                " (at least 0) out of range"));
}

namespace {

// "0.568" / "0.62": three significant digits for the plan's lines.
std::string g3(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3g", v);
    return b;
}

double uniform(uint32_t seed, uint32_t a, uint32_t b) { return (hash32(seedFor(seed, a, b)) >> 8) * (1.0 / 16777216.0); }

// The share of the light meeting a material's smooth layer that it sends
// on: a mirror's reflectance (at normal incidence), glass's transmission
// filter (its Fresnel reflection sends on the rest, near enough).
Rgb specularCarry(const Material& m) {
    switch (m.smooth.kind) {
        case SpecularKind::Mirror: return m.smooth.reflectance;
        case SpecularKind::Glass: return m.smooth.transmission;
        default: return Rgb(0.0);
    }
}

Vec3 pointOnTriangle(const Triangle3& t, double u, double v) {
    const double su = std::sqrt(u);
    return (1 - su) * t[0] + su * (1 - v) * t[1] + su * v * t[2];
}

}  // namespace

BounceCount countBounces(const Scene& scene, const BounceCountSettings& settings) {
    settings.validate();
    BounceCount plan;
    // Triangles by cumulative area, for area-uniform points.
    struct Tri {
        uint32_t mesh, tri;
    };
    std::vector<Tri> tris;
    std::vector<double> cdf;
    double total = 0;
    Rgb areaWeighted(0.0);
    for (uint32_t m = 0; m < scene.meshes.size(); ++m)
        for (uint32_t t = 0; t < scene.meshes[m].triangles.size(); ++t) {
            const double a = scene.meshes[m].area(t);
            if (!(a > 0)) continue;
            total += a;
            areaWeighted += a * scene.albedo(m, t);
            tris.push_back({m, t});
            cdf.push_back(total);
        }
    const Rgb areaMean = total > 0 ? areaWeighted / total : Rgb(0.0);
    plan.areaAlbedo = std::clamp(std::max({areaMean.r, areaMean.g, areaMean.b}), 0.0, 1.0);
    // What each point adds, made on every core and summed in the points'
    // order: the same plan whatever the number of threads.
    struct PointResult {
        double e = 0;  // direct irradiance (luminance, both sides)
        Rgb kd{0.0}, carried{0.0};
        double reflected = 0;  // e × luminance(kd)
        Rgb landedKd{0.0};     // the albedo where its reflected ray lands (0: it leaves)
    };
    std::vector<PointResult> results(tris.empty() || scene.lights.empty() ? 0 : size_t(settings.points));
    if (!results.empty()) {
        const EmbreeScene rt(scene);
        // Light l's direct irradiance at x (luminance, both sides of an
        // open surface), by `samples` shadow rays to area-uniform points of
        // it (one each side for a punctual light); `id` numbers the draws.
        const auto lightIrradiance = [&](size_t l, const Vec3& x, const Vec3& n, uint32_t id, int samples) {
            const Light& light = scene.lights[l];
            if (light.punctual())
                return luminance(punctualIrradiance(rt, l, x, n).irradiance +
                                 punctualIrradiance(rt, l, x, -n).irradiance);
            double sum = 0;
            for (int s = 0; s < samples; ++s, ++id) {
                const size_t lt = size_t(uniform(settings.seed ^ 0x9e3779b9u, id, uint32_t(l)) *
                                         light.geometry.size()) % light.geometry.size();
                const Triangle3& g = light.geometry[lt];
                const Vec3 y = pointOnTriangle(g, uniform(settings.seed, id, 4 + uint32_t(l)),
                                               uniform(settings.seed, id, 5 + uint32_t(l)));
                const Vec3 gn = glm::cross(g[1] - g[0], g[2] - g[0]);
                const double ga = 0.5 * glm::length(gn);
                if (!(ga > 0)) continue;
                const Vec3 d = y - x;
                const double r2 = glm::dot(d, d);
                if (!(r2 > 0)) continue;
                const Vec3 w = d / std::sqrt(r2);
                const double cosX = std::abs(glm::dot(n, w)), cosY = -glm::dot(gn / (2 * ga), w);
                if (!(cosY > 0)) continue;
                const Vec3 o = rt.spawnPoint(x, n, w);
                if (rt.occluded(o, d, 0, 1 - 1e-6, RayFilter{int(l), -1, false})) continue;
                // Picking triangle lt has probability 1/count; y is uniform on it.
                sum += cosX * cosY / r2 * ga * double(light.geometry.size());
            }
            return luminance(light.radiance) * sum / samples;
        };
        // Past everyLightUpTo lights, each point draws lightSamples ×
        // everyLightUpTo lights in proportion to their power (stratified
        // over its CDF) instead of lightSamples rays to every light: the
        // 192-panel office's plan traced 12.6 million shadow rays, 1.9 s
        // of a 14-s `render --time 3`. The estimate of each point's
        // irradiance stays unbiased (a draw counts 1/p of its light); only
        // its noise grows, which the 4,096 points average.
        const size_t lights = scene.lights.size();
        std::vector<double> lightCdf;
        if (lights > size_t(settings.everyLightUpTo)) {
            double sum = 0;
            for (const Light& light : scene.lights) lightCdf.push_back(sum += std::max(luminance(light.power()), 0.0));
            if (!(sum > 0)) lightCdf.clear();
        }
        const int threads =
            settings.threads > 0 ? settings.threads : int(std::max(1u, std::thread::hardware_concurrency()));
        parallelFor(results.size(), threads, [&](size_t pi) {
            const int i = int(pi);
            PointResult& r = results[pi];
            // Stratified in area: point i lies in the i-th of `points` equal slices.
            const double target = (i + uniform(settings.seed, uint32_t(i), 1)) / settings.points * total;
            const size_t k = std::min(tris.size() - 1, size_t(std::lower_bound(cdf.begin(), cdf.end(), target) - cdf.begin()));
            const Mesh& mesh = scene.meshes[tris[k].mesh];
            const Vec3 n = glm::normalize(mesh.areaNormal(tris[k].tri));
            const Vec3 x = pointOnTriangle(mesh.triangle(tris[k].tri), uniform(settings.seed, uint32_t(i), 2),
                                           uniform(settings.seed, uint32_t(i), 3));
            // Direct irradiance at x, both sides (an open surface may be lit
            // from behind), by shadow rays to area-uniform points of each light.
            if (lightCdf.empty()) {
                for (size_t l = 0; l < lights; ++l)
                    r.e += lightIrradiance(l, x, n, uint32_t(i * settings.lightSamples), settings.lightSamples);
            } else {
                const int draws = settings.lightSamples * settings.everyLightUpTo;
                const double sum = lightCdf.back();
                for (int s = 0; s < draws; ++s) {
                    const uint32_t id = uint32_t(i * draws + s);
                    const double u = (s + uniform(settings.seed ^ 0x85ebca6bu, id, 8)) / draws * sum;
                    const size_t l = std::min(lights - 1, size_t(std::upper_bound(lightCdf.begin(), lightCdf.end(), u) -
                                                                 lightCdf.begin()));
                    const double p = (lightCdf[l] - (l ? lightCdf[l - 1] : 0.0)) / sum;
                    if (p > 0) r.e += lightIrradiance(l, x, n, id, 1) / (p * draws);
                }
            }
            // The triangle's own mean over its texture footprint (Mesh::albedo).
            r.kd = scene.albedo(tris[k].mesh, tris[k].tri);
            // What is reflected diffusely from here: by the surface itself,
            // and by the surfaces where what a mirror or glass sends on
            // lands (a caustic), taken as the scene's area-weighted albedo.
            // Without the second a lamp that lights only a mirror over a
            // grey floor would plan no indirect light, and so no caustics.
            r.carried = specularCarry(scene.materials[mesh.materials[tris[k].tri]]) * areaMean;
            // Where the light it reflects lands: one cosine-distributed ray
            // on its front side, the albedo there.
            r.reflected = r.e * luminance(r.kd);
            if (r.reflected > 0) {
                const Vec3 t = glm::normalize(std::abs(n.x) > 0.5 ? glm::cross(n, Vec3(0, 1, 0)) : glm::cross(n, Vec3(1, 0, 0)));
                const Vec3 b = glm::cross(n, t);
                const double u1 = uniform(settings.seed, uint32_t(i), 6), u2 = uniform(settings.seed, uint32_t(i), 7);
                const Vec3 w = cosineDirection(n, t, b, u1, u2);
                RayHit hit;
                if (rt.intersect(rt.spawnPoint(x, n, w), w, 0, std::numeric_limits<double>::infinity(), hit))
                    r.landedKd = scene.albedo(hit.mesh, hit.triangle);
            }
        });
    }
    Rgb weighted(0.0), landed(0.0);
    double weight = 0, leaving = 0, carriedWeight = 0;
    for (const PointResult& r : results) {
        weighted += r.e * glm::min(r.kd + r.carried, Rgb(1.0));
        if (luminance(r.carried) > 0) carriedWeight += r.e;
        weight += r.e;
        if (r.reflected > 0) {
            landed += r.reflected * r.landedKd;
            leaving += r.reflected;
        }
    }
    if (weight > 0) plan.albedo = weighted / weight;
    if (leaving > 0) plan.bounceRatio = std::clamp(std::max({landed.r, landed.g, landed.b}) / leaving, 0.0, 1.0);
    plan.meanAlbedo = std::clamp(std::max({plan.albedo.r, plan.albedo.g, plan.albedo.b}), 0.0, 1.0);
    const double a = plan.meanAlbedo;
    auto missingAfter = [&](int n) { return std::pow(a, n + 1); };
    if (settings.forced) {
        plan.bounces = *settings.forced;
        plan.missing = missingAfter(plan.bounces);
        plan.reason = concat(plan.bounces, " bounces as asked (--bounces); the albedo light meets is ", g3(a),
                             ", so about ", g3(100 * plan.missing), "% of the reflected light is left out");
        return plan;
    }
    if (weight == 0) {
        plan.reason = "no surface receives direct light: no indirect light to simulate";
        return plan;
    }
    if (a == 0) {
        plan.reason = "the surfaces that receive direct light are black: they reflect nothing";
        return plan;
    }
    // Says where mirrors and glass made part of ā.
    const std::string carriedNote =
        carriedWeight > 0 ? concat(" (", g3(100 * carriedWeight / weight), "% of the direct light meets mirrors or glass, ",
                                   "counted as what they send on times the area-weighted albedo ", g3(plan.areaAlbedo),
                                   ", where their caustics land)")
                          : std::string();
    int n = 1;
    while (missingAfter(n) > settings.missingFraction && n < settings.maxBounces) ++n;
    plan.bounces = n;
    plan.missing = missingAfter(n);
    plan.capped = plan.missing > settings.missingFraction;
    plan.reason =
        plan.capped
            ? concat(n, " bounces (the cap): the albedo light meets is ", g3(a), carriedNote, ", so ", g3(100 * plan.missing),
                     "% of the reflected light is still missing after them, above the ",
                     g3(100 * settings.missingFraction), "% asked; raise --max-bounces to go on")
            : concat(n, " bounces: the albedo light meets is ", g3(a), " (area- and irradiance-weighted, largest ",
                     "channel)", carriedNote, ", so ", g3(a), "^", n + 1, " = ", g3(100 * plan.missing),
                     "% of the reflected light is left out, below the ", g3(100 * settings.missingFraction), "% asked");
    return plan;
}

}  // namespace ml
