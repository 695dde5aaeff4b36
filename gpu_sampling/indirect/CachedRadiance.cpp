#include "CachedRadiance.h"

#include "RadianceProxy.h"
#include "core/Error.h"
#include "core/SmoothSpecular.h"

#include <algorithm>
#include <cmath>

namespace ml {

void SpecularSplitSettings::validate() const {
    if (maxSpecularBounces < 0 || maxSpecularBounces > 64)
        throw InputError(concat("specular bounces ", maxSpecularBounces, " is not within 0..64"));
    if (!(minWeight >= 0 && minWeight < 1))
        throw InputError(concat("specular branch weight ", minWeight, " is not within [0, 1)"));
}

namespace {

double maxChannel(const Rgb& c) { return std::max({c.r, c.g, c.b}); }

// The shading normal on wo's side, or the geometric one where the
// interpolated normal leaves wo below its horizon (a silhouette of a
// coarsely tessellated sphere).
Vec3 facingNormal(const SurfacePoint& y, const Vec3& wo) {
    const Vec3 ng = glm::dot(y.geometricNormal, wo) >= 0 ? y.geometricNormal : -y.geometricNormal;
    const Vec3 ns = glm::dot(y.shadingNormal, ng) >= 0 ? y.shadingNormal : -y.shadingNormal;
    return glm::dot(ns, wo) > 0 ? ns : ng;
}

// Unit direction from x towards light l's light (see the header).
bool towardsLight(const Light& light, const Vec3& x, const Vec3& n, Vec3& w) {
    if (light.punctual()) {
        w = punctualIncidence(light, x, n).toLight;
    } else {
        const Vec3 d = light.centroid - x;
        const double len = glm::length(d);
        if (!(len > 0)) return false;
        w = d / len;
    }
    return glm::dot(w, w) > 0.5;
}

Rgb highlight(const CachedRadiance& cache, const SurfacePoint& y, const Vec3& wo) {
    const Material& m = cache.scene.materials[y.material];
    const Vec3 n = facingNormal(y, wo);
    const Vec3 side = glm::dot(y.geometricNormal, wo) >= 0 ? y.geometricNormal : -y.geometricNormal;
    const Vec3 mirror = reflectDirection(wo, n);
    const double exponent = std::max(m.ns, 0.0);
    const double norm = (exponent + 2.0) / (2.0 * kPi);
    Rgb sum(0.0);
    for (const WeightedLookup& source : cache.meshes) {
        if (source.light < 0 || source.weight == Rgb(0.0)) continue;
        Vec3 wl;
        if (!towardsLight(cache.scene.lights[size_t(source.light)], y.position, n, wl)) continue;
        const double cosAlpha = glm::dot(wl, mirror);
        if (glm::dot(wl, n) <= 0 || cosAlpha <= 0) continue;
        // ∫ f L cos θ dω over a small light is f(ω_l) × E_l: the irradiance
        // already holds the cosine the BRDF's integral takes.
        sum += source.weight * source.lookup->at(y.position, side) * (norm * std::pow(cosAlpha, exponent));
    }
    return m.ks * sum;
}

Rgb radianceAlong(const CachedRadiance& cache, const Vec3& origin, const Vec3& direction, int bounces, double weight);

// A mirror's or glass's reflected and transmitted radiance towards wo, after
// `bounces` specular surfaces, the path's weight so far `weight`.
Rgb smoothLayer(const CachedRadiance& cache, const SurfacePoint& y, const Vec3& wo, int bounces, double weight) {
    if (bounces >= cache.settings.maxSpecularBounces) return Rgb(0.0);
    const SmoothSpecular& layer = cache.scene.materials[y.material].smooth;
    const bool entering = glm::dot(y.geometricNormal, wo) >= 0;
    const Vec3 n = facingNormal(y, wo);
    const Vec3 side = entering ? y.geometricNormal : -y.geometricNormal;
    const SpecularResponse r = specularResponse(layer, glm::dot(wo, n), entering);
    Rgb sum(0.0);
    // A direction the shading normal sends to the wrong side of the
    // geometric surface (grazing, near a silhouette) carries nothing, as in
    // the photons' and the gather's chains (core/raytrace/SpecularChain.h, which draws one branch).
    const double reflected = weight * maxChannel(r.reflected);
    const Vec3 wr = glm::normalize(reflectDirection(wo, n));
    if (reflected >= cache.settings.minWeight && glm::dot(wr, side) > 0) {
        const Vec3 origin = cache.rays.spawnPoint(y.position, y.geometricNormal, wr);
        sum += r.reflected * radianceAlong(cache, origin, wr, bounces + 1, reflected);
    }
    const double transmitted = weight * maxChannel(r.transmitted);
    Vec3 wt;
    if (transmitted >= cache.settings.minWeight &&
        refractDirection(wo, n, entering ? layer.ior : 1.0 / layer.ior, wt) && glm::dot(wt, side) < 0) {
        wt = glm::normalize(wt);
        const Vec3 origin = cache.rays.spawnPoint(y.position, y.geometricNormal, wt);
        sum += r.transmitted * radianceAlong(cache, origin, wt, bounces + 1, transmitted);
    }
    return sum;
}

Rgb specularPart(const CachedRadiance& cache, const SurfacePoint& y, const Vec3& wo, int bounces, double weight) {
    const Material& m = cache.scene.materials[y.material];
    if (m.specular()) return smoothLayer(cache, y, wo, bounces, weight);
    if (m.glossy() && cache.highlights) return highlight(cache, y, wo);
    return Rgb(0.0);
}

Rgb radianceAlong(const CachedRadiance& cache, const Vec3& origin, const Vec3& direction, int bounces,
                  double weight) {
    RayHit hit;
    if (!cache.rays.intersect(origin, direction, 0.0, kInf, hit)) return Rgb(0.0);
    const SurfacePoint y = cache.rays.surface(hit);
    return cachedDiffuseRadiance(cache, hit, y, -direction) + specularPart(cache, y, -direction, bounces, weight);
}

}  // namespace

Rgb cachedRadianceAlong(const CachedRadiance& cache, const Vec3& origin, const Vec3& direction) {
    return radianceAlong(cache, origin, direction, 0, 1.0);
}

Rgb specularRadiance(const CachedRadiance& cache, const SurfacePoint& y, const Vec3& wo) {
    return specularPart(cache, y, wo, 0, 1.0);
}

Rgb cachedDiffuseRadiance(const CachedRadiance& cache, const RayHit& hit, const SurfacePoint& y, const Vec3& wo) {
    Rgb result(0.0);
    const bool front = glm::dot(y.geometricNormal, wo) > 0;
    if (front || !cache.closedMeshes[hit.mesh]) {
        const Vec3 side = front ? y.geometricNormal : -y.geometricNormal;
        Rgb e(0.0);
        for (const WeightedLookup& source : cache.meshes)
            if (source.weight != Rgb(0.0)) e += source.weight * source.lookup->at(y.position, side);
        result += y.kd(cache.scene) * (1.0 / kPi) * e;
    }
    if (front && !cache.emission.empty()) {
        const int light = cache.rays.lightOf(hit.mesh, hit.triangle);
        if (light >= 0) {
            // As the compositor shows an emitter: its texture where it has one.
            const Material& m = cache.scene.materials[y.material];
            const Rgb le = m.keMap && y.hasTexcoord ? m.keMap.value(y.texcoord) : cache.scene.lights[size_t(light)].radiance;
            result += cache.emission[size_t(light)] * le;
        }
    }
    return result;
}

}  // namespace ml
