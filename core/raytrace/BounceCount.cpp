#include "BounceCount.h"

#include "PunctualShadow.h"

#include "EmbreeScene.h"
#include "core/Error.h"
#include "core/Random.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace ml {

void BounceCountSettings::validate() const {
    if (!(missingFraction > 0 && missingFraction < 1))
        throw InputError(concat("indirect tolerance ", missingFraction, " is not in (0, 1)"));
    if (maxBounces < 1 || maxBounces > 256)
        throw InputError(concat("maximum bounce count ", maxBounces, " is not in 1..256"));
    if (forced && (*forced < 0 || *forced > 256)) throw InputError(concat("--bounces ", *forced, " is not in 0..256"));
    if (points < 1 || lightSamples < 1) throw InputError("bounce plan: at least one point and one light sample");
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
    Rgb weighted(0.0), landed(0.0);
    double weight = 0, leaving = 0, carriedWeight = 0;
    if (!tris.empty() && !scene.lights.empty()) {
        const EmbreeScene rt(scene);
        for (int i = 0; i < settings.points; ++i) {
            // Stratified in area: point i lies in the i-th of `points` equal slices.
            const double target = (i + uniform(settings.seed, uint32_t(i), 1)) / settings.points * total;
            const size_t k = std::min(tris.size() - 1, size_t(std::lower_bound(cdf.begin(), cdf.end(), target) - cdf.begin()));
            const Mesh& mesh = scene.meshes[tris[k].mesh];
            const Vec3 n = glm::normalize(mesh.areaNormal(tris[k].tri));
            const Vec3 x = pointOnTriangle(mesh.triangle(tris[k].tri), uniform(settings.seed, uint32_t(i), 2),
                                           uniform(settings.seed, uint32_t(i), 3));
            // Direct irradiance at x, both sides (an open surface may be lit
            // from behind), by shadow rays to area-uniform points of each light.
            double e = 0;
            for (size_t l = 0; l < scene.lights.size(); ++l) {
                const Light& light = scene.lights[l];
                if (light.punctual()) {  // one shadow ray, each side
                    e += luminance(punctualIrradiance(rt, l, x, n).irradiance + punctualIrradiance(rt, l, x, -n).irradiance);
                    continue;
                }
                double sum = 0;
                for (int s = 0; s < settings.lightSamples; ++s) {
                    const uint32_t id = uint32_t(i * settings.lightSamples + s);
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
                e += luminance(light.radiance) * sum / settings.lightSamples;
            }
            // The triangle's own mean over its texture footprint (Mesh::albedo).
            const Rgb kd = scene.albedo(tris[k].mesh, tris[k].tri);
            // What is reflected diffusely from here: by the surface itself,
            // and by the surfaces where what a mirror or glass sends on
            // lands (a caustic), taken as the scene's area-weighted albedo.
            // Without the second a lamp that lights only a mirror over a
            // grey floor would plan no indirect light, and so no caustics.
            const Rgb carried = specularCarry(scene.materials[mesh.materials[tris[k].tri]]) * areaMean;
            weighted += e * glm::min(kd + carried, Rgb(1.0));
            if (luminance(carried) > 0) carriedWeight += e;
            weight += e;
            // Where the light it reflects lands: one cosine-distributed ray
            // on its front side, the albedo there.
            const double reflected = e * luminance(kd);
            if (reflected > 0) {
                const Vec3 t = glm::normalize(std::abs(n.x) > 0.5 ? glm::cross(n, Vec3(0, 1, 0)) : glm::cross(n, Vec3(1, 0, 0)));
                const Vec3 b = glm::cross(n, t);
                const double u1 = uniform(settings.seed, uint32_t(i), 6), u2 = uniform(settings.seed, uint32_t(i), 7);
                const Vec3 w = cosineDirection(n, t, b, u1, u2);
                RayHit hit;
                if (rt.intersect(rt.spawnPoint(x, n, w), w, 0, std::numeric_limits<double>::infinity(), hit))
                    landed += reflected * scene.albedo(hit.mesh, hit.triangle);
                leaving += reflected;
            }
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
