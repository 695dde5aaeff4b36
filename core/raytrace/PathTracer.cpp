#include "PathTracer.h"

#include "PunctualShadow.h"

#include "PhongBsdf.h"
#include "SmoothSpecularBsdf.h"
#include "core/Error.h"
#include "core/Random.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

namespace ml {

void PathTracerSettings::validate() const {
    if (maxDepth < 1 || maxDepth > 1024) throw InputError(concat("maximum depth ", maxDepth, " is not in [1, 1024]"));
    if (rouletteDepth < 1) throw InputError(concat("Russian roulette depth ", rouletteDepth, " is not >= 1"));
    if (threads < 0 || threads > 1024) throw InputError(concat("thread count ", threads, " is not in [0, 1024]"));
}

// --- Random numbers ------------------------------------------------------------

// PCG32 (O'Neill 2014): one stream per pixel sample, its 64-bit state from
// two differently salted hashes of (seed, a, b, c), so that the tens of
// millions of streams of a large reference do not collide.
struct PathTracer::Stream {
    uint64_t state = 0;

    Stream(uint32_t seed, uint32_t a, uint32_t b, uint32_t c) {
        const uint64_t hi = seedFor(seed, a, b, c);
        const uint64_t lo = seedFor(seed ^ 0xa511e9b3u, a, b, c ^ 0x63d83595u);
        next();
        state += (hi << 32) | lo;
        next();
    }
    uint32_t next() {
        const uint64_t old = state;
        state = old * 6364136223846793005ull + 1442695040888963407ull;
        const uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
        const uint32_t rot = uint32_t(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
    }
    // Uniform in [0, 1).
    double uniform() { return double(next()) * (1.0 / 4294967296.0); }
};

// --- Path vertices --------------------------------------------------------------

// A scattering point, normals turned to the side the path arrives from.
struct PathTracer::Vertex {
    Vec3 position{0.0};
    Vec3 ng{0.0};  // geometric normal, unit, on wo's side
    Vec3 ns{0.0};  // shading normal, unit, on the same side as ng
    Vec3 wo{0.0};  // towards where the path came from, unit
    const Material* material = nullptr;
    Rgb kd{0.0};   // the material's Kd here: its texture's at the hit, else Material::kd
    bool front = true;  // wo is on the triangle's front side (outside a closed glass object)
};

namespace {

double maxComponent(const Rgb& c) { return std::max(c.r, std::max(c.g, c.b)); }

double powerHeuristic(double a, double b) {
    const double a2 = a * a, b2 = b * b;
    return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.0;
}

// A cosine-weighted direction around unit n (pdf cosθ/π).
Vec3 cosineDirection(const Vec3& n, double u1, double u2) {
    Vec3 t, b;
    orthonormalBasis(n, t, b);
    const double r = std::sqrt(u1), phi = 2.0 * kPi * u2;
    return glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0, 1.0 - u1)) * n);
}

size_t pick(const std::vector<double>& cdf, double u) {
    const size_t i = size_t(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin());
    return std::min(i, cdf.size() - 1);
}

// The BSDF at a path vertex: Phong, or the smooth layer over Kd for a mirror
// or glass. eval() and pdf() are what next-event estimation and MIS see:
// for the layer, its diffuse lobe only (a delta lobe has no value to
// evaluate towards a light).
class VertexBsdf {
public:
    VertexBsdf(const Material& m, const Vec3& ns, const Vec3& ng, const Vec3& wo, bool front, const Rgb& kd) {
        if (m.specular()) smooth_.emplace(m, ns, ng, wo, front, kd);
        else phong_.emplace(m, ns, kd);
    }
    bool black() const { return phong_ ? phong_->black() : smooth_->black(); }
    Rgb eval(const Vec3& wo, const Vec3& wi) const { return phong_ ? phong_->eval(wo, wi) : smooth_->evalDiffuse(wi); }
    double pdf(const Vec3& wo, const Vec3& wi) const { return phong_ ? phong_->pdf(wo, wi) : smooth_->pdfDiffuse(wi); }
    const PhongBsdf* phong() const { return phong_ ? &*phong_ : nullptr; }
    const SmoothSpecularBsdf* smooth() const { return smooth_ ? &*smooth_ : nullptr; }

private:
    std::optional<PhongBsdf> phong_;
    std::optional<SmoothSpecularBsdf> smooth_;
};

// Delta bounces a path may take in all (a light trapped between two mirrors
// facing each other, or by total internal reflection): Russian roulette ends
// such paths in expectation, this bounds them.
constexpr int kMaxDeltaBounces = 256;

}  // namespace

// --- Construction ---------------------------------------------------------------

PathTracer::PathTracer(const EmbreeScene& rays, const PathTracerSettings& settings)
    : rays_(rays), scene_(rays.scene()), settings_(settings), emitters_(EmitterTexture::forLights(scene_)) {
    settings_.validate();
    double total = 0;
    for (const Light& l : scene_.lights) {
        lightProbability_.push_back(luminance(l.power()));
        total += lightProbability_.back();
        std::vector<double> cdf;
        double sum = 0;
        for (const Triangle3& t : l.geometry) {
            sum += 0.5 * glm::length(glm::cross(t[1] - t[0], t[2] - t[0]));
            cdf.push_back(sum);
        }
        for (double& c : cdf) c /= sum;
        triangleCdf_.push_back(std::move(cdf));
    }
    if (total > 0) {
        double sum = 0;
        for (double& p : lightProbability_) {
            p /= total;
            sum += p;
            lightCdf_.push_back(sum);
        }
        lightCdf_.back() = 1.0;
    } else {
        lightProbability_.assign(scene_.lights.size(), 0.0);
    }
}

int PathTracer::threadCount() const {
    if (settings_.threads > 0) return settings_.threads;
    return std::max(1, int(std::thread::hardware_concurrency()));
}

// A uniform point of light `light` (triangle by area, then uniform in it)
// and that triangle's unit front normal.
bool PathTracer::lightPoint(size_t light, double u0, double u1, double u2, Vec3& y, Vec3& normal,
                            Rgb& radiance) const {
    const Light& l = scene_.lights[light];
    const size_t k = pick(triangleCdf_[light], u0);
    const Triangle3& t = l.geometry[k];
    const double r = std::sqrt(u1);
    y = t[0] + r * (1.0 - u2) * (t[1] - t[0]) + r * u2 * (t[2] - t[0]);
    radiance = l.radiance * emitters_[light].weight(k, r * (1.0 - u2), r * u2);
    const Vec3 an = glm::cross(t[1] - t[0], t[2] - t[0]);
    const double len = glm::length(an);
    if (!(len > 0)) return false;
    normal = an / len;
    return true;
}

// --- The estimator --------------------------------------------------------------

// The vertex at a surface hit, seen along direction `incoming` (unit).
PathTracer::Vertex PathTracer::vertexAt(const SurfacePoint& s, const Vec3& incoming, const Scene& scene) {
    Vertex v;
    v.position = s.position;
    v.wo = -incoming;
    v.ng = s.geometricNormal;
    v.ns = s.shadingNormal;
    if (glm::dot(v.ng, v.wo) < 0) {  // seen from the back: reflect on that side
        v.front = false;
        v.ng = -v.ng;
        v.ns = -v.ns;
    }
    v.material = &scene.materials[s.material];
    v.kd = s.kd(scene);
    return v;
}

// Next-event estimation at v: one light by power, one point by area; the
// light-sampling half of MIS.
Rgb PathTracer::sampleLight(const Vertex& v, Stream& rng) const {
    const double uLight = rng.uniform(), u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
    if (lightCdf_.empty()) return Rgb(0.0);
    const size_t l = pick(lightCdf_, uLight);
    if (scene_.lights[l].punctual()) {
        // A delta light: only this strategy can reach it (no MIS).
        const PunctualSample p = punctualIrradiance(rays_, l, v.position, v.ns, v.ng);
        if (!p.visible) return Rgb(0.0);
        const VertexBsdf bsdf(*v.material, v.ns, v.ng, v.wo, v.front, v.kd);
        return bsdf.eval(v.wo, p.toLight) * p.irradiance / lightProbability_[l];
    }
    Vec3 y, nl;
    Rgb emitted;
    if (!lightPoint(l, u0, u1, u2, y, nl, emitted)) return Rgb(0.0);
    const Vec3 d = y - v.position;
    const double d2 = glm::dot(d, d);
    if (!(d2 > 0)) return Rgb(0.0);
    const Vec3 wi = d / std::sqrt(d2);
    const double cosLight = -glm::dot(nl, wi);
    if (cosLight <= 0 || glm::dot(wi, v.ng) <= 0) return Rgb(0.0);  // light's back, or behind the surface
    const VertexBsdf bsdf(*v.material, v.ns, v.ng, v.wo, v.front, v.kd);
    const Rgb f = bsdf.eval(v.wo, wi);
    if (maxComponent(f) <= 0) return Rgb(0.0);
    const Light& light = scene_.lights[l];
    const double pLight = lightProbability_[l] * d2 / (cosLight * light.area);
    const Vec3 from = rays_.spawnPoint(v.position, v.ng, wi);
    const Vec3 to = rays_.spawnPoint(y, nl, -wi);
    if (rays_.occluded(from, to - from, 0.0, 1.0)) return Rgb(0.0);
    const double w = powerHeuristic(pLight, bsdf.pdf(v.wo, wi));
    return f * emitted * (glm::dot(wi, v.ns) * w / pLight);
}

// Radiance scattered at `first` towards first.wo by up to `depth`
// scattering vertices (direct light at each, as in the header).
Rgb PathTracer::scattered(const Vertex& first, Stream& rng, int depth) const {
    Rgb result(0.0), beta(1.0);
    Vertex v = first;
    // k: the depth level of v (the header's D), which delta bounces do not
    // raise; n: the vertices so far, for Russian roulette. A level beyond
    // `depth` is reached only at a mirror or glass, whose delta lobes may
    // still carry the emission that the previous level's scattering sees
    // (direct light through glass, which no shadow ray finds); nothing else
    // is gathered there.
    int deltaBounces = 0;
    for (int k = 1, n = 1;; ++n) {
        const bool beyond = k > depth;
        if (beyond && !v.material->specular()) break;
        const VertexBsdf bsdf(*v.material, v.ns, v.ng, v.wo, v.front, v.kd);
        if (bsdf.black()) break;
        if (!beyond) result += beta * sampleLight(v, rng);

        const double uLobe = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        Vec3 wi;
        double pdf = 0;
        bool delta = false;
        if (const SmoothSpecularBsdf* smooth = bsdf.smooth()) {
            SmoothSpecularBsdf::Sample sample;
            if (!smooth->sample(uLobe, u1, u2, sample)) break;
            wi = sample.wi;
            pdf = sample.pdf;
            delta = sample.delta;
            if (beyond && !delta) break;
            if (!delta && glm::dot(wi, v.ng) <= 0) break;  // below the true surface, as for Phong
            beta *= sample.weight;
        } else {
            const PhongBsdf& phong = *bsdf.phong();
            if (!phong.sample(v.wo, uLobe, u1, u2, wi)) break;
            if (glm::dot(wi, v.ng) <= 0) break;  // below the true surface (shading normal): blocked
            pdf = phong.pdf(v.wo, wi);
            if (!(pdf > 0)) break;
            beta *= phong.eval(v.wo, wi) * (glm::dot(wi, v.ns) / pdf);
        }

        RayHit hit;
        if (!rays_.intersect(rays_.spawnPoint(v.position, v.ng, wi), wi, 0.0, kInf, hit)) break;
        const SurfacePoint s = rays_.surface(hit);
        const Material& m = scene_.materials[s.material];
        const double cosLight = -glm::dot(s.geometricNormal, wi);
        if (m.emissive() && cosLight > 0) {
            // The BSDF-sampling half of MIS: weigh against the light
            // strategy's density for the same point.
            const int l = rays_.lightOf(hit.mesh, hit.triangle);
            // After a delta bounce only this strategy can reach the
            // emitter (no MIS): it counts fully.
            double w = 1.0;
            if (l >= 0 && !delta) {
                const Vec3 d = s.position - v.position;
                const double pLight = lightProbability_[size_t(l)] * glm::dot(d, d) / (cosLight * scene_.lights[size_t(l)].area);
                w = powerHeuristic(pdf, pLight);
            }
            result += beta * s.ke(scene_) * w;
        }
        if (delta) {
            if (++deltaBounces > kMaxDeltaBounces) break;
        } else {
            if (k >= depth && !m.specular()) break;
            ++k;
        }
        if (n >= settings_.rouletteDepth) {
            const double q = std::min(0.95, maxComponent(beta));
            if (!(rng.uniform() < q)) break;
            beta /= q;
        }
        v = vertexAt(s, wi, scene_);
    }
    return result;
}

// Radiance arriving at `origin` from `direction` (unit): emission seen
// directly plus what the surface there scatters.
Rgb PathTracer::radiance(const Vec3& origin, const Vec3& direction, Stream& rng) const {
    RayHit hit;
    if (!rays_.intersect(origin, direction, 0.0, kInf, hit)) return Rgb(0.0);
    const SurfacePoint s = rays_.surface(hit);
    Rgb result(0.0);
    const Material& m = scene_.materials[s.material];
    // Emission shows its texture, seen directly as the compositor does,
    // and met later as the light sampler weighs it (EmitterTexture.h).
    if (m.emissive() && glm::dot(s.geometricNormal, direction) < 0) result += s.ke(scene_);
    return result + scattered(vertexAt(s, direction, scene_), rng, settings_.maxDepth);
}

// --- Images ---------------------------------------------------------------------

namespace {

// Runs work(item) for items [0, count) on `threads` threads, items handed
// out in order by an atomic counter; calls progress() on this thread about
// ten times a second. The first exception of a worker stops the others and
// is rethrown here; `stop` ends the work early.
template <typename Work>
void parallelFor(size_t count, int threads, const Work& work, const std::function<void()>& progress,
                 const std::atomic<bool>* stop) {
    std::atomic<size_t> next{0};
    std::atomic<bool> abort{false};
    std::mutex mutex;
    std::condition_variable finished;
    int running = threads;
    std::exception_ptr error;
    auto worker = [&] {
        try {
            for (;;) {
                if (abort.load() || (stop && stop->load())) break;
                const size_t item = next++;
                if (item >= count) break;
                work(item);
            }
        } catch (...) {
            std::lock_guard<std::mutex> lock(mutex);
            if (!error) error = std::current_exception();
            abort = true;
        }
        std::lock_guard<std::mutex> lock(mutex);
        --running;
        finished.notify_one();
    };
    std::vector<std::thread> pool;
    pool.reserve(size_t(threads));
    for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
    {
        std::unique_lock<std::mutex> lock(mutex);
        while (running > 0) {
            finished.wait_for(lock, std::chrono::milliseconds(100));
            if (progress) {
                lock.unlock();
                progress();
                lock.lock();
            }
        }
    }
    for (std::thread& t : pool) t.join();
    if (error) std::rethrow_exception(error);
}

}  // namespace

ReferenceImage PathTracer::render(const Camera& camera, int width, int height, int samplesPerPixel,
                                  const RenderControl& control) const {
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw InputError(concat("image size ", width, "x", height, " is not within 1..16384"));
    if (samplesPerPixel < 2)
        throw InputError(concat("samples per pixel ", samplesPerPixel,
                                " is below 2 (the even and odd samples estimate the noise)"));
    camera.validate();
    const auto start = std::chrono::steady_clock::now();
    Vec3 forward, right, up;
    camera.basis(forward, right, up);
    // The compositor's projection: x_ndc = f/aspect · x/(−z), y_ndc = f · y/(−z).
    const double tanHalf = std::tan(glm::radians(camera.fovYDegrees) * 0.5);
    const double aspect = double(width) / double(height);

    if (control.passSamples < 0 || control.passSamples % 2 != 0)
        throw InputError(concat("samples per pass ", control.passSamples, " is not even (passes keep the even and "
                                "odd halves the same size)"));
    const int pass = control.passSamples > 0 ? std::min(control.passSamples, samplesPerPixel) : samplesPerPixel;

    ReferenceImage out;
    out.radiance = ImageRgb(width, height);
    out.standardError = ImageRgb(width, height);

    constexpr int kTile = 16;
    const int tilesX = (width + kTile - 1) / kTile, tilesY = (height + kTile - 1) / kTile;
    const size_t pixels = size_t(width) * size_t(height);
    const uint64_t total = uint64_t(pixels) * uint64_t(samplesPerPixel);
    std::atomic<uint64_t> done{0};
    // Per pixel, the sums of the even and odd samples of the passes done
    // (`sums`), and of those plus the pass under way (`next`), swapped in
    // once the pass is whole. Each pixel adds its samples in order, so the
    // sums do not depend on the pass size or the threads.
    std::vector<std::array<Rgb, 2>> sums(pixels, {Rgb(0.0), Rgb(0.0)}), next(pixels);

    int spp = 0;
    while (spp < samplesPerPixel) {
        const int first = spp, last = std::min(samplesPerPixel, spp + pass);
        auto tile = [&](size_t index) {
            const int tx = int(index % size_t(tilesX)), ty = int(index / size_t(tilesX));
            const int x0 = tx * kTile, y0 = ty * kTile;
            const int x1 = std::min(width, x0 + kTile), y1 = std::min(height, y0 + kTile);
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    const uint32_t pixel = uint32_t(y) * uint32_t(width) + uint32_t(x);
                    std::array<Rgb, 2> sum = sums[pixel];
                    for (int s = first; s < last; ++s) {
                        Stream rng(settings_.seed, pixel, uint32_t(s), 0);
                        const double jx = rng.uniform(), jy = rng.uniform();
                        const double sx = 2.0 * (x + jx) / width - 1.0;   // NDC, right
                        const double sy = 1.0 - 2.0 * (y + jy) / height;  // NDC, up; row 0 at the top
                        const Vec3 dir =
                            glm::normalize(forward + (sx * aspect * tanHalf) * right + (sy * tanHalf) * up);
                        const Rgb l = radiance(camera.position, dir, rng);
                        ML_ASSERT(isFinite(l) && l.r >= 0 && l.g >= 0 && l.b >= 0, "radiance (", l.r, ", ", l.g,
                                  ", ", l.b, ") at pixel (", x, ", ", y, "), sample ", s, ", seed ", settings_.seed);
                        sum[s & 1] += l;
                    }
                    next[pixel] = sum;
                }
            done += uint64_t(x1 - x0) * uint64_t(y1 - y0) * uint64_t(last - first);
        };
        std::function<void()> progress;
        if (control.progress) progress = [&] { control.progress(done.load(), total); };
        parallelFor(size_t(tilesX) * size_t(tilesY), threadCount(), tile, progress, control.stop);
        if (done.load() < uint64_t(pixels) * uint64_t(last)) break;  // stopped: the pass is dropped
        sums.swap(next);
        spp = last;
    }
    out.samplesPerPixel = spp;
    out.cancelled = spp < samplesPerPixel;

    if (spp > 0) {
        const double nA = double((spp + 1) / 2), nB = double(spp / 2);  // even, odd sample indices
        const double halvesToError = std::sqrt(nA * nB) / double(spp);
        double sumRelative = 0;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const std::array<Rgb, 2>& sum = sums[size_t(y) * size_t(width) + size_t(x)];
                const Rgb a = sum[0] / nA, b = sum[1] / nB;
                const Rgb mean = (sum[0] + sum[1]) / double(spp);
                out.radiance.set(x, y, mean);
                out.standardError.set(x, y, glm::abs(a - b) * halvesToError);
                const double lum = luminance(mean);
                if (lum > 0) {
                    sumRelative += std::abs(luminance(a) - luminance(b)) * halvesToError / lum;
                    ++out.litPixels;
                }
            }
        out.meanRelativeError = out.litPixels ? sumRelative / double(out.litPixels) : 0.0;
    }
    out.paths = uint64_t(pixels) * uint64_t(spp);
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

// --- Irradiance at a point ------------------------------------------------------

IrradianceEstimate PathTracer::irradiance(const Vec3& x, const Vec3& nIn, int samples, uint32_t pointId) const {
    if (samples < 2) throw InputError(concat("samples ", samples, " is below 2 (the spread estimates the error)"));
    if (!isFinite(x) || !isFinite(nIn) || !(glm::length(nIn) > 0))
        throw InputError("irradiance: non-finite point or zero normal");
    const Vec3 n = glm::normalize(nIn);
    const size_t lights = scene_.lights.size();
    const Vec3 origin = rays_.spawnPoint(x, n, n);

    // Sums over a block of samples, combined in block order: the result does
    // not depend on which thread summed which block.
    constexpr int kBlock = 64;
    struct Sums {
        std::vector<Rgb> perLight;
        Rgb direct{0.0}, direct2{0.0}, indirect{0.0}, indirect2{0.0};
    };
    const size_t blocks = size_t((samples + kBlock - 1) / kBlock);
    std::vector<Sums> sums(blocks);

    auto block = [&](size_t b) {
        Sums& out = sums[b];
        out.perLight.assign(lights, Rgb(0.0));
        const int end = std::min(samples, int(b + 1) * kBlock);
        std::vector<Rgb> perLight(lights);
        for (int k = int(b) * kBlock; k < end; ++k) {
            Stream rng(settings_.seed, pointId, uint32_t(k), 1);
            std::fill(perLight.begin(), perLight.end(), Rgb(0.0));
            // One point of every light, weighed against cosine sampling.
            for (size_t l = 0; l < lights; ++l) {
                const double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
                if (scene_.lights[l].punctual()) {  // exact: one shadow ray, every sample alike
                    perLight[l] += punctualIrradiance(rays_, l, x, n).irradiance;
                    continue;
                }
                Vec3 y, nl;
                Rgb emitted;
                if (!lightPoint(l, u0, u1, u2, y, nl, emitted)) continue;
                const Vec3 d = y - x;
                const double d2 = glm::dot(d, d);
                if (!(d2 > 0)) continue;
                const Vec3 wi = d / std::sqrt(d2);
                const double cosLight = -glm::dot(nl, wi), cosX = glm::dot(n, wi);
                if (cosLight <= 0 || cosX <= 0) continue;
                const double pLight = d2 / (cosLight * scene_.lights[l].area);
                const Vec3 to = rays_.spawnPoint(y, nl, -wi);
                if (rays_.occluded(origin, to - origin, 0.0, 1.0)) continue;
                perLight[l] += emitted * (cosX / pLight * powerHeuristic(pLight, cosX / kPi));
            }
            // One cosine-weighted direction: the rest of direct light (MIS)
            // and, beyond the first surface, the indirect light.
            const double u1 = rng.uniform(), u2 = rng.uniform();
            const Vec3 wi = cosineDirection(n, u1, u2);
            Rgb indirect(0.0);
            RayHit hit;
            const double cosX = glm::dot(n, wi);
            if (cosX > 0 && rays_.intersect(origin, wi, 0.0, kInf, hit)) {
                const SurfacePoint s = rays_.surface(hit);
                const Material& m = scene_.materials[s.material];
                const double cosLight = -glm::dot(s.geometricNormal, wi);
                const int l = rays_.lightOf(hit.mesh, hit.triangle);
                if (m.emissive() && cosLight > 0 && l >= 0) {
                    const Vec3 d = s.position - x;
                    const double pLight = glm::dot(d, d) / (cosLight * scene_.lights[size_t(l)].area);
                    perLight[size_t(l)] += s.ke(scene_) * (kPi * powerHeuristic(cosX / kPi, pLight));
                }
                // Through a mirror or glass even at depth 1: light that
                // reaches x that way is found by this ray alone.
                if (settings_.maxDepth >= 2 || m.specular()) {
                    Vertex v;
                    v = vertexAt(s, wi, scene_);
                    indirect = kPi * scattered(v, rng, settings_.maxDepth - 1);
                }
            }
            Rgb direct(0.0);
            for (size_t l = 0; l < lights; ++l) {
                out.perLight[l] += perLight[l];
                direct += perLight[l];
            }
            ML_ASSERT(isFinite(direct) && isFinite(indirect), "irradiance sample ", k, " at point ", pointId,
                      " is not finite");
            out.direct += direct;
            out.direct2 += direct * direct;
            out.indirect += indirect;
            out.indirect2 += indirect * indirect;
        }
    };
    parallelFor(blocks, std::min(threadCount(), int(blocks)), block, {}, nullptr);

    IrradianceEstimate e;
    e.samples = uint64_t(samples);
    e.directPerLight.assign(lights, Rgb(0.0));
    Rgb direct2(0.0), indirect2(0.0);
    for (const Sums& s : sums) {
        for (size_t l = 0; l < lights; ++l) e.directPerLight[l] += s.perLight[l];
        e.direct += s.direct;
        direct2 += s.direct2;
        e.indirect += s.indirect;
        indirect2 += s.indirect2;
    }
    const double count = double(samples);
    auto standardError = [count](const Rgb& sum, const Rgb& sum2) {
        const Rgb variance = glm::max((sum2 - sum * sum / count) / (count - 1.0), Rgb(0.0));
        return glm::sqrt(variance / count);
    };
    e.directError = standardError(e.direct, direct2);
    e.indirectError = standardError(e.indirect, indirect2);
    for (Rgb& p : e.directPerLight) p /= count;
    e.direct /= count;
    e.indirect /= count;
    return e;
}

}  // namespace ml
