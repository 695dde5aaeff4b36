#include "CausticPhotons.h"

#include "core/Error.h"
#include "core/MeshUtil.h"
#include "core/Random.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/SpecularChain.h"

#include <algorithm>
#include <cmath>
#include <thread>

namespace ml {

namespace {

// Uniform numbers from one photon's seed: a hash chain, as the gathers draw.
struct PhotonRandom {
    uint32_t state;
    explicit PhotonRandom(uint32_t seed) : state(hash32(seed ^ 0x6a09e667u)) {}
    double operator()() {
        state = hash32(state + 0x9e3779b9u);
        return (state >> 8) * (1.0 / 16777216.0);
    }
};

size_t pick(const std::vector<double>& cdf, double u) {
    const size_t i = size_t(std::upper_bound(cdf.begin(), cdf.end(), u * cdf.back()) - cdf.begin());
    return std::min(i, cdf.size() - 1);
}

double probability(const std::vector<double>& cdf, size_t i) {
    return (cdf[i] - (i ? cdf[i - 1] : 0.0)) / cdf.back();
}

// 1 − cos of the half-angle of the cone from a point at distance d that
// just holds a sphere of radius r (< d), without cancellation when r ≪ d.
double coneOneMinusCos(double r, double d) {
    const double s2 = (r / d) * (r / d);
    return s2 / (1.0 + std::sqrt(std::max(0.0, 1.0 - s2)));
}

Vec3 pointOnTriangle(const Triangle3& t, double u1, double u2) {
    const double su = std::sqrt(u1);
    return (1 - su) * t[0] + su * (1 - u2) * t[1] + su * u2 * t[2];
}

Vec3 inBasis(const Vec3& axis, double cosTheta, double phi) {
    Vec3 t, b;
    orthonormalBasis(axis, t, b);
    const double sinTheta = std::sqrt(std::max(0.0, 1 - cosTheta * cosTheta));
    return glm::normalize(sinTheta * std::cos(phi) * t + sinTheta * std::sin(phi) * b + cosTheta * axis);
}

}  // namespace

CausticPhotons::CausticPhotons(const Scene& scene, const EmbreeScene& rays) : scene_(scene), rays_(rays) {
    for (const Mesh& m : scene.meshes) closed_.push_back(isClosedMesh(m) ? 1 : 0);
    // The specular objects, each as the sphere around its specular faces,
    // and those faces' area for drawing points on them.
    struct Object {
        CausticTarget sphere;
        std::vector<Triangle3> faces;
        std::vector<double> cdf;
    };
    std::vector<Object> objects;
    for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
        const Mesh& m = scene.meshes[mi];
        Object o;
        Bounds3 b;
        for (size_t t = 0; t < m.triangles.size(); ++t) {
            if (!scene.materials[m.materials[t]].specular() || !(m.area(t) > 0)) continue;
            o.faces.push_back(m.triangle(t));
            o.cdf.push_back((o.cdf.empty() ? 0.0 : o.cdf.back()) + m.area(t));
            for (const Vec3& p : o.faces.back()) b.extend(p);
        }
        if (o.faces.empty()) continue;
        o.sphere.mesh = uint32_t(mi);
        o.sphere.centre = b.center();
        for (const Triangle3& f : o.faces)
            for (const Vec3& p : f) o.sphere.radius = std::max(o.sphere.radius, glm::length(p - o.sphere.centre));
        o.sphere.radius *= 1 + 1e-6;  // its own corners stay inside under rounding
        objects.push_back(std::move(o));
    }
    const double reach = 2 * std::max(scene.bounds.diagonal(), 1e-30);
    targets_.resize(scene.lights.size());
    targetCdf_.resize(scene.lights.size());
    triangleCdf_.resize(scene.lights.size());
    lightProbability_.assign(scene.lights.size(), 0.0);
    for (size_t l = 0; l < scene.lights.size(); ++l) {
        const Light& light = scene.lights[l];
        if (light.kind == LightKind::Area)
            for (const Triangle3& t : light.geometry)
                triangleCdf_[l].push_back((triangleCdf_[l].empty() ? 0.0 : triangleCdf_[l].back()) +
                                          0.5 * glm::length(glm::cross(t[1] - t[0], t[2] - t[0])));
        if (light.kind == LightKind::Area && !(triangleCdf_[l].back() > 0)) continue;
        // Seen: some of 256 rays from the light to points on the object
        // meets a smooth layer first (deterministic: seeds from the pair).
        for (size_t oi = 0; oi < objects.size(); ++oi) {
            const Object& o = objects[oi];
            bool seen = false;
            PhotonRandom random(seedFor(0x5eedu, uint32_t(l), uint32_t(oi)));
            for (int k = 0; k < 256 && !seen; ++k) {
                const Vec3 x = pointOnTriangle(o.faces[pick(o.cdf, random())], random(), random());
                Vec3 origin, direction;
                if (light.kind == LightKind::Area) {
                    const Triangle3& t = light.geometry[pick(triangleCdf_[l], random())];
                    const Vec3 y = pointOnTriangle(t, random(), random());
                    const Vec3 n = glm::normalize(glm::cross(t[1] - t[0], t[2] - t[0]));
                    if (!(glm::dot(x - y, n) > 0)) continue;
                    origin = rays.spawnPoint(y, n, x - y);
                    direction = x - y;
                } else if (light.kind == LightKind::Point) {
                    direction = x - light.emission.position;
                    if (!(luminance(light.emission.intensityToward(glm::normalize(direction))) > 0)) continue;
                    origin = light.emission.position;
                } else {
                    direction = light.emission.axis;
                    origin = x - reach * direction;
                }
                RayHit hit;
                seen = rays.intersect(origin, direction, 0.0, kInf, hit) &&
                       scene.materials[rays.surface(hit).material].specular();
            }
            if (!seen) continue;
            // Aimed at by its share: the cone's solid angle from the light's
            // centre, leaning on the light's normal (or, for a directional
            // light, the disc's area).
            const CausticTarget& s = o.sphere;
            double weight;
            if (light.kind == LightKind::Directional) {
                weight = s.radius * s.radius;
            } else {
                const Vec3 v = s.centre - light.centroid;
                const double d = glm::length(v);
                weight = d > s.radius ? 2 * kPi * coneOneMinusCos(s.radius, d) : 2 * kPi;
                if (light.kind == LightKind::Area && d > s.radius)
                    weight *= std::max(0.1, glm::dot(v / d, light.normal));
            }
            targets_[l].push_back(s);
            targetCdf_[l].push_back((targetCdf_[l].empty() ? 0.0 : targetCdf_[l].back()) + weight);
        }
        if (targets_[l].empty()) continue;
        lightPick_.push_back(uint32_t(l));
        lightCdf_.push_back((lightCdf_.empty() ? 0.0 : lightCdf_.back()) + std::max(luminance(light.power()), 1e-30));
    }
    for (size_t i = 0; i < lightPick_.size(); ++i) lightProbability_[lightPick_[i]] = probability(lightCdf_, i);
}

std::string CausticPhotons::describe() const {
    size_t lights = 0;
    std::vector<uint32_t> meshes;
    for (const auto& t : targets_) {
        lights += !t.empty();
        for (const CausticTarget& s : t) meshes.push_back(s.mesh);
    }
    std::sort(meshes.begin(), meshes.end());
    meshes.erase(std::unique(meshes.begin(), meshes.end()), meshes.end());
    if (meshes.empty()) {
        for (const Material& m : scene_.materials)
            if (m.specular()) return "no light sees a specular object";
        return "no specular materials";
    }
    std::string names;
    for (uint32_t m : meshes) names += (names.empty() ? "" : ", ") + scene_.meshes[m].name;
    return concat(meshes.size(), meshes.size() == 1 ? " specular object (" : " specular objects (", names,
                  ") seen by ", lights, " of ", scene_.lights.size(), " lights");
}

void CausticPhotons::trace(uint64_t first, size_t count, uint32_t seed, std::vector<CausticPhoton>& out) const {
    if (!active() || count == 0) return;
    const size_t threads = std::clamp<size_t>(std::thread::hardware_concurrency(), 1, std::max<size_t>(1, count / 1024));
    std::vector<std::vector<CausticPhoton>> parts(threads);
    std::vector<std::thread> pool;
    std::vector<std::exception_ptr> failed(threads);
    for (size_t k = 0; k < threads; ++k)
        pool.emplace_back([&, k] {
            try {
                for (size_t i = count * k / threads; i < count * (k + 1) / threads; ++i)
                    traceOne(first + i, seed, parts[k]);
            } catch (...) {
                failed[k] = std::current_exception();
            }
        });
    for (std::thread& t : pool) t.join();
    for (const std::exception_ptr& e : failed)
        if (e) std::rethrow_exception(e);
    for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
}

void CausticPhotons::traceOne(uint64_t index, uint32_t seed, std::vector<CausticPhoton>& out) const {
    PhotonRandom random(seedFor(seed, uint32_t(index), uint32_t(index >> 32), 0xca05u));
    const uint32_t l = lightPick_[pick(lightCdf_, random())];
    const Light& light = scene_.lights[l];
    const std::vector<CausticTarget>& targets = targets_[l];
    const std::vector<double>& cdf = targetCdf_[l];
    const CausticTarget& aim = targets[pick(cdf, random())];
    Vec3 origin, direction;
    Rgb power(0.0);
    if (light.kind == LightKind::Directional) {
        // A point on the aimed disc; its density is the mixture over every
        // disc holding it.
        const Vec3 a = light.emission.axis;
        Vec3 t, b;
        orthonormalBasis(a, t, b);
        const double r = aim.radius * std::sqrt(random()), phi = 2 * kPi * random();
        const Vec3 x = aim.centre + r * (std::cos(phi) * t + std::sin(phi) * b);
        double pdf = 0;
        for (size_t k = 0; k < targets.size(); ++k) {
            const Vec3 v = x - targets[k].centre;
            const Vec3 across = v - glm::dot(v, a) * a;
            if (glm::dot(across, across) <= targets[k].radius * targets[k].radius)
                pdf += probability(cdf, k) / (kPi * targets[k].radius * targets[k].radius);
        }
        if (!(pdf > 0)) return;
        direction = a;
        origin = x - 2 * std::max(scene_.bounds.diagonal(), 1e-30) * a;
        power = light.emission.intensity / pdf;
    } else {
        Vec3 y, n(0.0);
        double area = 0;
        if (light.kind == LightKind::Area) {
            const Triangle3& tri = light.geometry[pick(triangleCdf_[l], random())];
            y = pointOnTriangle(tri, random(), random());
            n = glm::normalize(glm::cross(tri[1] - tri[0], tri[2] - tri[0]));
            area = triangleCdf_[l].back();
        } else {
            y = light.emission.position;
        }
        // A direction in the aimed cone (or over the emitting hemisphere,
        // or sphere, from inside the target), and the mixture's pdf there.
        const Vec3 v = aim.centre - y;
        const double d = glm::length(v);
        if (d > aim.radius) {
            const double oneMinusCos = coneOneMinusCos(aim.radius, d);
            direction = inBasis(v / d, 1 - random() * oneMinusCos, 2 * kPi * random());
        } else if (light.kind == LightKind::Area) {
            const double u = random();
            direction = inBasis(n, std::sqrt(1 - u), 2 * kPi * random());
        } else {
            direction = inBasis(Vec3(0, 0, 1), 1 - 2 * random(), 2 * kPi * random());
        }
        const double cosLight = light.kind == LightKind::Area ? glm::dot(direction, n) : 1.0;
        if (!(cosLight > 0)) return;
        double pdf = 0;
        for (size_t k = 0; k < targets.size(); ++k) {
            const Vec3 vk = targets[k].centre - y;
            const double dk = glm::length(vk);
            double pk;
            if (dk > targets[k].radius) {
                const double oneMinusCos = coneOneMinusCos(targets[k].radius, dk);
                pk = glm::dot(direction, vk / dk) >= 1 - oneMinusCos ? 1 / (2 * kPi * oneMinusCos) : 0.0;
            } else {
                pk = light.kind == LightKind::Area ? cosLight / kPi : 1 / (4 * kPi);
            }
            pdf += probability(cdf, k) * pk;
        }
        if (!(pdf > 0)) return;
        if (light.kind == LightKind::Area) {
            origin = rays_.spawnPoint(y, n, direction);
            power = light.radiance * (cosLight * area / pdf);
        } else {
            origin = y;
            const double s = light.emission.metresPerUnit;
            power = light.emission.intensityToward(direction) / (pdf * s * s);
        }
    }
    power /= lightProbability_[l];
    followSpecularChain(rays_, closed_, origin, direction, SpecularChainSettings{}, std::ref(random),
                        [&](const ChainVertex& v) {
                            if (v.specular || v.layers == 0) return;
                            out.push_back({v.surface.position, v.side, power * v.weight});
                        });
}

}  // namespace ml
