#include "VirtualPointLights.h"

#include "RadianceProxy.h"
#include "RayGather.h"
#include "core/Error.h"
#include "core/ParallelFor.h"
#include "core/Random.h"
#include "core/raytrace/EmbreeScene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>

namespace ml {

void VirtualPointLightSettings::validate() const {
    if (lights < 1 || lights > 65536)
        throw InputError(concat("virtual point lights: ", lights, " lights is not within 1..65536"));
    if (!(negativeShare >= 0 && negativeShare <= 4))
        throw InputError(concat("virtual point lights: a negative share of ", negativeShare, " is not within 0..4"));
    if (sitesPerLight < 1 || sitesPerLight > 64)
        throw InputError(concat("virtual point lights: ", sitesPerLight, " candidate points per light is not within 1..64"));
    if (nearRays < 0 || nearRays > 4096)
        throw InputError(concat("virtual point lights: ", nearRays, " near-field rays is not within 0..4096"));
    if (threads < 1 || threads > 1024)
        throw InputError(concat("virtual point lights: ", threads, " threads is not within 1..1024"));
}

// --- Sampling ------------------------------------------------------------------------------

double radicalInverse(uint32_t base, uint64_t i) {
    const double inverse = 1.0 / base;
    double result = 0, digit = inverse;
    for (; i > 0; i /= base, digit *= inverse) result += double(i % base) * digit;
    return result;
}

Vec3 sampleLinearDensity(const Vec3& f, double pick, double u, double v) {
    const double total = f.x + f.y + f.z;
    int k = 2;
    if (pick * total < f.x) k = 0;
    else if (pick * total < f.x + f.y) k = 1;
    // b_k has the density 6 s (1 − s) (the segment at b_k = s is 1 − s
    // long): its distribution 3s² − 2s³ = u inverts to
    // s = 1/2 + cos(acos(1 − 2u)/3 + 4π/3).
    const double s = std::clamp(0.5 + std::cos(std::acos(std::clamp(1 - 2 * u, -1.0, 1.0)) / 3 + 4 * kPi / 3), 0.0, 1.0);
    Vec3 b;
    b[k] = s;
    b[(k + 1) % 3] = (1 - s) * v;
    b[(k + 2) % 3] = (1 - s) * (1 - v);
    return b;
}

namespace {

// The index of the interval of a cumulative distribution (last entry 1)
// that u falls in, and u rescaled to [0, 1) within it.
size_t pickFrom(const std::vector<double>& cdf, double u, double& rest) {
    const size_t i = std::min(size_t(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()), cdf.size() - 1);
    const double lo = i > 0 ? cdf[i - 1] : 0.0, width = cdf[i] - lo;
    rest = width > 0 ? std::clamp((u - lo) / width, 0.0, 1.0 - 1e-16) : 0.0;
    return i;
}

// The weights, normalised and summed: empty when they add up to nothing.
std::vector<double> cumulative(const std::vector<double>& weights) {
    std::vector<double> cdf(weights.size());
    double sum = 0;
    for (size_t i = 0; i < weights.size(); ++i) cdf[i] = sum += weights[i];
    if (!(sum > 0)) return {};
    for (double& c : cdf) c /= sum;
    cdf.back() = 1.0;
    return cdf;
}

// Halton point i ≥ 1 in bases 2, 3, 5 (the paper's first two, and one for
// the second coordinate on a surface).
struct HaltonPoint {
    double u2, u3, u5;
    explicit HaltonPoint(uint64_t i) : u2(radicalInverse(2, i)), u3(radicalInverse(3, i)), u5(radicalInverse(5, i)) {}
};

const VirtualPointLightSettings& validated(const VirtualPointLightSettings& s) {
    s.validate();
    return s;
}

}  // namespace

Rgb virtualLightIrradiance(const std::vector<VirtualLight>& lights, const Vec3& x, const Vec3& n) {
    Rgb e(0.0);
    for (const VirtualLight& l : lights) {
        const Vec3 d = l.position - x;
        const double d2 = glm::dot(d, d);
        if (!(d2 > 0)) continue;
        const double cosX = glm::dot(n, d), cosL = -glm::dot(l.axis, d);  // both × |d|
        if (cosX <= 0 || cosL <= 0) continue;
        const double length = std::sqrt(d2);
        // (m + 1)/2 · cos^m θ_l, exactly cos θ_l for m = 1 (the positive lights).
        const double lobe = l.exponent == 1 ? cosL / length
                                            : 0.5 * (l.exponent + 1) * std::pow(cosL / length, l.exponent);
        e += l.flux * (cosX * lobe / (length * kPi * (d2 + l.area / kPi)));
    }
    return e;
}

// --- The lights ------------------------------------------------------------------------------

VirtualPointLights::VirtualPointLights(const Scene& scene, const VirtualPointLightSettings& settings)
    : scene_(scene),
      settings_(validated(settings)),
      rays_(std::make_unique<EmbreeScene>(scene)),
      closed_(closedMeshesOf(scene)) {
    std::vector<double> areas;
    for (size_t m = 0; m < scene.meshes.size(); ++m)
        for (size_t t = 0; t < scene.meshes[m].triangles.size(); ++t) {
            const double a = scene.meshes[m].area(t);
            if (!(a > 0)) continue;
            for (const bool back : {false, true}) {
                if (back && closed_[m]) continue;
                sides_.push_back({uint32_t(m), uint32_t(t), back});
                areas.push_back(a);
                sideArea_ += a;
            }
        }
    sideCdf_ = cumulative(areas);
}

VirtualPointLights::~VirtualPointLights() = default;

std::string VirtualPointLights::name() const { return "vpl"; }

std::vector<VirtualLight> VirtualPointLights::placePositive(const std::vector<IrradianceMeshCopy>& irradiance,
                                                            int count, Rgb& power) {
    // Every cache triangle's reflected power, Kd · area · mean E, with Kd
    // the albedo of the scene triangle a short ray finds beneath its centre.
    struct Patch {
        const IrradianceMeshCopy* mesh;
        size_t triangle;
        Vec3 normal;
        Rgb kd;
    };
    std::vector<Patch> patches;
    std::vector<double> weights;
    power = Rgb(0.0);
    const double hair = 1e-5 * std::max(scene_.bounds.diagonal(), 1e-30);
    for (const IrradianceMeshCopy& m : irradiance)
        for (size_t t = 0; t < m.triangles.size(); ++t) {
            const glm::uvec3 c = m.triangles[t];
            const Vec3 p0 = m.positions[c.x], p1 = m.positions[c.y], p2 = m.positions[c.z];
            Vec3 normal = glm::cross(p1 - p0, p2 - p0);
            const double twiceArea = glm::length(normal);
            if (!(twiceArea > 0)) continue;
            normal /= twiceArea;
            if (glm::dot(normal, m.normals[c.x] + m.normals[c.y] + m.normals[c.z]) < 0) normal = -normal;
            const Rgb meanE = (m.irradiance[c.x] + m.irradiance[c.y] + m.irradiance[c.z]) / 3.0;
            if (!(luminance(meanE) > 0)) continue;
            const Vec3 centre = (p0 + p1 + p2) / 3.0;
            RayHit hit;
            if (!rays_->intersect(centre + hair * normal, -normal, 0.0, 2 * hair, hit)) {
                ++unplaced_;
                continue;
            }
            const Rgb kd = scene_.albedo(hit.mesh, hit.triangle);
            const Rgb phi = kd * (0.5 * twiceArea) * meanE;
            if (!(luminance(phi) > 0)) continue;
            patches.push_back({&m, t, normal, kd});
            weights.push_back(luminance(phi));
            power += phi;
        }
    const std::vector<double> cdf = cumulative(weights);
    std::vector<VirtualLight> lights;
    if (cdf.empty()) return lights;
    const double total = luminance(power);
    for (int i = 1; i <= count; ++i) {
        const HaltonPoint h{uint64_t(i)};
        double pick = 0;
        const Patch& patch = patches[pickFrom(cdf, h.u2, pick)];
        const IrradianceMeshCopy& m = *patch.mesh;
        const glm::uvec3 c = m.triangles[patch.triangle];
        const Rgb e[3] = {patch.kd * m.irradiance[c.x], patch.kd * m.irradiance[c.y], patch.kd * m.irradiance[c.z]};
        const Vec3 b = sampleLinearDensity(Vec3(luminance(e[0]), luminance(e[1]), luminance(e[2])), pick, h.u3, h.u5);
        const Rgb reflected = b.x * e[0] + b.y * e[1] + b.z * e[2];  // Kd·E(y) = π·Lo(y)
        const double density = luminance(reflected) / total;          // per m², of the power's distribution
        if (!(density > 0)) continue;
        VirtualLight l;
        l.position = b.x * m.positions[c.x] + b.y * m.positions[c.y] + b.z * m.positions[c.z];
        l.axis = patch.normal;
        l.area = 1.0 / (count * density);
        l.flux = reflected * l.area;
        lights.push_back(l);
    }
    return lights;
}

bool VirtualPointLights::reachesASurface(const Vec3& origin, const Vec3& direction) const {
    Vec3 from = origin;
    for (int crossing = 0; crossing < 64; ++crossing) {
        RayHit hit;
        if (!rays_->intersect(from, direction, 0.0, kInf, hit)) return false;
        const SurfacePoint y = rays_->surface(hit);
        const bool inside = glm::dot(y.geometricNormal, direction) > 0 && closed_[hit.mesh];
        if (!inside) return true;
        from = rays_->spawnPoint(y.position, y.geometricNormal, direction);
    }
    return false;
}

std::vector<VirtualLight> VirtualPointLights::placeNegative(const std::vector<VirtualLight>& positive, int sites,
                                                            int count) const {
    std::vector<VirtualLight> lights;
    if (positive.empty() || sideCdf_.empty() || count < 1) return lights;
    // The candidates: points over every side, uniformly by area, each with
    // the light arriving there first and the mean direction it travels.
    struct Candidate {
        Vec3 position, direction;
        Rgb irradiance;
        double exponent;
    };
    std::vector<Candidate> candidates;
    std::vector<double> weights;
    for (int i = 1; i <= sites; ++i) {
        const HaltonPoint h{uint64_t(i)};
        double rest = 0;
        const Side& side = sides_[pickFrom(sideCdf_, h.u2, rest)];
        const Triangle3 tri = scene_.meshes[side.mesh].triangle(side.triangle);
        const double r = std::sqrt(h.u3);  // uniform over the triangle
        const Vec3 p = (1 - r) * tri[0] + r * (1 - h.u5) * tri[1] + r * h.u5 * tri[2];
        Vec3 n = glm::normalize(scene_.meshes[side.mesh].areaNormal(side.triangle));
        if (side.back) n = -n;
        const Vec3 origin = rays_->spawnPoint(p, n, n);
        Rgb e(0.0);
        Vec3 flow(0.0);
        double weight = 0;
        for (const VirtualLight& l : positive) {
            const Vec3 d = l.position - p;
            const double d2 = glm::dot(d, d);
            if (!(d2 > 0)) continue;
            const double cosP = glm::dot(n, d), cosL = -glm::dot(l.axis, d);
            if (cosP <= 0 || cosL <= 0) continue;
            // A ray to the light, lifted off the light's own surface too.
            const Vec3 target = rays_->spawnPoint(l.position, l.axis, l.axis);
            if (rays_->occluded(origin, target - origin, 0.0, 1.0)) continue;
            const Rgb arriving = l.flux * (cosP * cosL / (d2 * kPi * (d2 + l.area / kPi)));
            e += arriving;
            flow -= luminance(arriving) * (d / std::sqrt(d2));
            weight += luminance(arriving);
        }
        const double length = glm::length(flow);
        if (!(luminance(e) > 0) || !(length > 0)) continue;
        const Vec3 direction = flow / length;
        if (!reachesASurface(rays_->spawnPoint(p, n, -n), direction)) continue;
        // The lobe whose mean cosine is the light's resultant length ρ.
        double exponent = 1;
        if (settings_.matchSpread) {
            const double rho = std::min(length / weight, 1.0);
            exponent = rho >= 64.0 / 65.0 ? 64.0 : std::clamp((2 * rho - 1) / (1 - rho), 0.0, 64.0);
        }
        candidates.push_back({p, direction, e, exponent});
        weights.push_back(luminance(e));
    }
    const std::vector<double> cdf = cumulative(weights);
    if (cdf.empty()) return lights;
    // Each candidate stands for sideArea/sites of surface: the power the
    // kept ones pass on, which the negative lights share equally.
    double total = 0;
    for (double w : weights) total += w * sideArea_ / sites;
    for (int i = 1; i <= count; ++i) {
        double rest = 0;
        const Candidate& c = candidates[pickFrom(cdf, radicalInverse(2, uint64_t(i)), rest)];
        const double density = luminance(c.irradiance) / total;  // per m²
        VirtualLight l;
        l.position = c.position;
        l.axis = c.direction;
        l.area = 1.0 / (count * density);
        l.flux = c.irradiance * l.area;
        l.exponent = c.exponent;
        lights.push_back(l);
    }
    return lights;
}

void VirtualPointLights::setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance) {
    const auto start = std::chrono::steady_clock::now();
    if (slot >= sources_.size()) sources_.resize(slot + 1);
    auto source = std::make_unique<Source>();
    const double share = std::clamp(importance, 0.0, 1.0);
    const int count = std::max(std::min(settings_.lights, 32), int(std::lround(settings_.lights * share)));
    source->positive = placePositive(irradiance, count, source->power);
    source->placed = count;
    if (settings_.nearRays > 0) {
        // Lookup cells of 1/64 of the scene, as the ray gather's.
        const double diagonal = scene_.bounds.diagonal() > 0 ? scene_.bounds.diagonal() : 1.0;
        source->meshes = irradiance;
        for (const IrradianceMeshCopy& m : source->meshes)
            source->lookups.push_back(std::make_unique<MeshIrradianceLookup>(m, diagonal / 64, 1e-5 * diagonal));
    }
    if (settings_.visibility) {
        const int negatives = int(std::lround(settings_.negativeShare * count));
        source->negative = placeNegative(source->positive, settings_.sitesPerLight * count, negatives);
    }
    stats_.source = concat(source->positive.size(), " virtual point lights, ", source->negative.size(),
                           " negative ones", settings_.visibility ? "" : " (no visibility)");
    sources_[slot] = std::move(source);
    size_t held = 0;
    for (const auto& s : sources_)
        if (s) held += (s->positive.size() + s->negative.size()) * sizeof(VirtualLight);
    stats_.sourceBytes = held;
    stats_.buildSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void VirtualPointLights::releaseSource(size_t slot) {
    if (slot < sources_.size()) sources_[slot].reset();
}

const VirtualPointLights::Source& VirtualPointLights::source(size_t slot) const {
    ML_ASSERT(slot < sources_.size() && sources_[slot], "virtual point lights: source ", slot, " is not built");
    return *sources_[slot];
}

const std::vector<VirtualLight>& VirtualPointLights::positive(size_t slot) const { return source(slot).positive; }
const std::vector<VirtualLight>& VirtualPointLights::negative(size_t slot) const { return source(slot).negative; }
Rgb VirtualPointLights::reflectedPower(size_t slot) const { return source(slot).power; }

Rgb VirtualPointLights::irradianceAt(const Source& s, const Vec3& x, const Vec3& nIn, uint32_t seed) const {
    const Vec3 n = glm::normalize(nIn);
    Rgb e = glm::max(virtualLightIrradiance(s.positive, x, n) - virtualLightIrradiance(s.negative, x, n), Rgb(0.0));
    if (!s.lookups.empty()) e += nearCompensation(s, x, n, seed);
    return e;
}

Rgb VirtualPointLights::estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) {
    const Source& s = source(slot);
    const auto start = std::chrono::steady_clock::now();
    const Rgb e = irradianceAt(s, x, n, seed);
    stats_.estimates++;
    stats_.estimateSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return e;
}

void VirtualPointLights::estimateBatch(size_t slot, const std::vector<SampleRequest>& requests,
                                       std::vector<VertexSample>& results) {
    if (settings_.threads <= 1) return IndirectEstimator::estimateBatch(slot, requests, results);
    const Source& s = source(slot);
    const auto start = std::chrono::steady_clock::now();
    results.assign(requests.size(), VertexSample{});
    // Blocks of requests, each point's sum on its own; a failure is
    // reported for the first request that failed, as on one thread.
    constexpr size_t kBlock = 64;
    const size_t blocks = (requests.size() + kBlock - 1) / kBlock;
    std::vector<std::exception_ptr> failed(requests.size());
    parallelFor(blocks, settings_.threads, [&](size_t b) {
        for (size_t i = b * kBlock; i < std::min(requests.size(), (b + 1) * kBlock); ++i) {
            const SampleRequest& r = requests[i];
            try {
                results[i].irradiance = irradianceAt(s, r.x, r.n, r.seed);
            } catch (...) {
                failed[i] = std::current_exception();
                return;
            }
        }
    });
    for (size_t i = 0; i < failed.size(); ++i)
        if (failed[i]) asBatchRequest(i, [&] { std::rethrow_exception(failed[i]); });
    stats_.estimates += requests.size();
    stats_.estimateSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Rgb VirtualPointLights::nearCompensation(const Source& source, const Vec3& x, const Vec3& n, uint32_t seed) const {
    const double power = luminance(source.power);
    if (!(power > 0) || source.placed < 1) return Rgb(0.0);
    Vec3 t, b;
    orthonormalBasis(n, t, b);
    const Vec3 origin = rays_->spawnPoint(x, n, n);
    const int strata = std::max(1, int(std::lround(std::sqrt(double(settings_.nearRays)))));
    uint32_t state = hash32(seed ^ 0x6a09e667u);
    const auto next = [&state] {
        state = hash32(state + 0x9e3779b9u);
        return (state >> 8) * (1.0 / 16777216.0);
    };
    Rgb sum(0.0);
    for (int i = 0; i < strata; ++i)
        for (int j = 0; j < strata; ++j) {
            // Cosine-weighted (Malley) over a jittered stratum: E = π/M Σ L·w.
            const double u1 = (i + next()) / strata, u2 = (j + next()) / strata;
            const Vec3 w = cosineDirection(n, t, b, u1, u2);
            RayHit hit;
            if (!rays_->intersect(origin, w, 0.0, kInf, hit)) continue;
            const SurfacePoint y = rays_->surface(hit);
            Vec3 side = y.geometricNormal;
            if (glm::dot(side, w) > 0) {
                if (closed_[hit.mesh]) continue;  // a closed object's inside is black
                side = -side;
            }
            // Kd as the lights were placed with it: the triangle's albedo.
            const Rgb kd = scene_.albedo(hit.mesh, hit.triangle);
            const double d2 = glm::dot(y.position - x, y.position - x);
            // Each mesh's lights stand for areas of their own (a light's a is
            // from its mesh's power at y alone).
            for (const auto& lookup : source.lookups) {
                const Rgb reflected = kd * lookup->at(y.position, side);  // π Lo
                const double lum = luminance(reflected);
                if (!(lum > 0)) continue;
                const double disc = power / (source.placed * lum) / kPi;  // a(y)/π
                sum += reflected * (disc / (d2 + disc));
            }
        }
    return sum / double(strata * strata);
}

IndirectStats VirtualPointLights::stats() const { return stats_; }

}  // namespace ml
