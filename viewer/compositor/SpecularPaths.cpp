#include "SpecularPaths.h"

#include "core/Error.h"
#include "gpu_sampling/indirect/RadianceProxy.h"
#include "gpu_sampling/indirect/RayGather.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <thread>

namespace ml {

namespace {

bool specularOrGlossy(const Material& m) { return m.specular() || m.glossy(); }

// A rectangle of sub-pixels, continuous coordinates, x right, y down.
struct Rect {
    double x0, y0, x1, y1;
    bool contains(double x, double y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
};

}  // namespace

struct SpecularPaths::Impl {
    const Scene& scene;
    SpecularSplitSettings settings;
    EmbreeScene rays;
    std::vector<char> closed;
    // The bounds of each mesh's glossy and specular triangles (empty boxes
    // for meshes with none): what the screen rectangles are made from.
    std::vector<Bounds3> boxes;
    // The cache read, replaced whole by setCache while a trace on another
    // thread may still read the one before.
    struct CacheState {
        std::vector<IrradianceMeshCopy> direct, indirect;
        std::vector<std::unique_ptr<MeshIrradianceLookup>> directLookups, indirectLookups;
    };
    mutable std::mutex cacheMutex;
    std::shared_ptr<const CacheState> cache;

    std::shared_ptr<const CacheState> currentCache() const {
        std::lock_guard<std::mutex> lock(cacheMutex);
        return cache;
    }

    Impl(const Scene& s, const SpecularSplitSettings& st) : scene(s), settings(st), rays(s), closed(closedMeshesOf(s)) {
        settings.validate();
        for (const Mesh& m : scene.meshes) {
            Bounds3 b;
            for (size_t t = 0; t < m.triangles.size(); ++t)
                if (specularOrGlossy(scene.materials[m.materials[t]]))
                    for (const Vec3& p : m.triangle(t)) b.extend(p);
            if (!b.empty()) boxes.push_back(b);
        }
    }

    CachedRadiance radiance(const CacheState& state, const LightWeights& weights) const {
        CachedRadiance c{scene, rays, closed, {}, {}, true, settings};
        const size_t lights = scene.lights.size();
        for (size_t m = 0; m < state.direct.size(); ++m)
            c.meshes.push_back({state.directLookups[m].get(), m < lights ? weights.light[m] : weights.shared,
                                m < lights ? int(m) : -1});
        for (size_t m = 0; m < state.indirect.size(); ++m)
            c.meshes.push_back({state.indirectLookups[m].get(), weights.indirect, -1});
        c.emission = weights.emission.empty() ? weights.light : weights.emission;
        return c;
    }

    // The sub-pixel rectangles the glossy and specular triangles cover (a
    // sub-pixel of margin); one covering the whole view where a box reaches
    // behind the camera.
    std::vector<Rect> screenRects(const Camera& camera, const CompositorSettings& s, const Vec3& forward,
                                  const Vec3& right, const Vec3& up, double tanHalf, double aspect) const {
        const double w = double(s.width) * s.supersample, h = double(s.height) * s.supersample;
        const double nearest = 1e-9 * std::max(scene.bounds.diagonal(), 1e-300);
        std::vector<Rect> rects;
        for (const Bounds3& b : boxes) {
            double x0 = kInf, y0 = kInf, x1 = -kInf, y1 = -kInf;
            bool behind = false;
            for (int k = 0; k < 8 && !behind; ++k) {
                const Vec3 p((k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z);
                const Vec3 d = p - camera.position;
                const double z = glm::dot(d, forward);
                if (z <= nearest) {
                    behind = true;
                    break;
                }
                const double nx = glm::dot(d, right) / (z * aspect * tanHalf) + 2 * s.shiftX / s.width;
                const double ny = glm::dot(d, up) / (z * tanHalf) + 2 * s.shiftY / s.height;
                const double x = (nx + 1) * 0.5 * w, y = (1 - ny) * 0.5 * h;
                x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
            }
            if (behind) return {{-kInf, -kInf, kInf, kInf}};
            if (x1 < -1 || y1 < -1 || x0 > w + 1 || y0 > h + 1) continue;
            rects.push_back({x0 - 1, y0 - 1, x1 + 1, y1 + 1});
        }
        return rects;
    }
};

SpecularPaths::SpecularPaths(const Scene& scene, const SpecularSplitSettings& settings)
    : impl_(std::make_unique<Impl>(scene, settings)) {}
SpecularPaths::~SpecularPaths() = default;

bool SpecularPaths::needed(const Scene& scene) {
    // Materials some face uses: a library's unused mirror costs nothing.
    for (const Mesh& m : scene.meshes)
        for (uint32_t material : m.materials)
            if (specularOrGlossy(scene.materials[material])) return true;
    return false;
}

void SpecularPaths::setCache(const std::vector<IrradianceMeshCopy>& direct,
                             const std::vector<IrradianceMeshCopy>& indirect) {
    Impl& d = *impl_;
    const size_t lights = d.scene.lights.size();
    ML_ASSERT(direct.size() == lights || direct.size() == lights + 1, direct.size(), " meshes for ", lights, " lights");
    auto state = std::make_shared<Impl::CacheState>();
    state->direct = direct;
    state->indirect = indirect;
    // Cells and tolerance of RayGather's lookups: the same reading of the
    // same meshes as the indirect gather's.
    const double diagonal = d.scene.bounds.diagonal() > 0 ? d.scene.bounds.diagonal() : 1.0;
    for (const IrradianceMeshCopy& m : state->direct)
        state->directLookups.push_back(std::make_unique<MeshIrradianceLookup>(m, diagonal / 64, 1e-5 * diagonal));
    for (const IrradianceMeshCopy& m : state->indirect)
        state->indirectLookups.push_back(std::make_unique<MeshIrradianceLookup>(m, diagonal / 64, 1e-5 * diagonal));
    std::lock_guard<std::mutex> lock(d.cacheMutex);
    d.cache = std::move(state);
}

bool SpecularPaths::hasCache() const { return impl_->currentCache() != nullptr; }

ImageRgb SpecularPaths::trace(const Camera& camera, const CompositorSettings& s, const LightWeights& weights,
                              int reduction, const std::atomic<bool>* cancel) const {
    const Impl& d = *impl_;
    const std::shared_ptr<const Impl::CacheState> state = d.currentCache();
    ML_ASSERT(state, "specular paths traced before setCache");
    ML_ASSERT(reduction >= 1, "reduction ", reduction);
    ML_ASSERT(weights.light.size() == d.scene.lights.size(), weights.light.size(), " weights for ",
              d.scene.lights.size(), " lights");
    s.validate();
    camera.validate();
    const int sw = s.width * s.supersample, sh = s.height * s.supersample;
    const int bw = (sw + reduction - 1) / reduction, bh = (sh + reduction - 1) / reduction;
    ImageRgb out(bw, bh);
    Vec3 forward, right, up;
    camera.basis(forward, right, up);
    // The compositor's projection (Compositor's clipFromLocal), shifted:
    // a sub-pixel at NDC c sees what the unshifted view has at c − shift.
    const double tanHalf = std::tan(glm::radians(camera.fovYDegrees) * 0.5);
    const double aspect = double(s.width) / double(s.height);
    const double shiftX = 2 * s.shiftX / s.width, shiftY = 2 * s.shiftY / s.height;
    const std::vector<Rect> rects = d.screenRects(camera, s, forward, right, up, tanHalf, aspect);
    if (rects.empty()) return out;
    const CachedRadiance cache = d.radiance(*state, weights);

    auto row = [&](int by) {
        // Block centres in sub-pixels from the top left (a last, partial
        // block's centre is that of the sub-pixels it has).
        const double y = 0.5 * (by * reduction + std::min((by + 1) * reduction, sh));
        for (int bx = 0; bx < bw; ++bx) {
            const double x = 0.5 * (bx * reduction + std::min((bx + 1) * reduction, sw));
            if (std::none_of(rects.begin(), rects.end(), [&](const Rect& r) { return r.contains(x, y); })) continue;
            const double nx = 2 * x / sw - 1 - shiftX, ny = 1 - 2 * y / sh - shiftY;
            const Vec3 dir = glm::normalize(forward + (nx * aspect * tanHalf) * right + (ny * tanHalf) * up);
            RayHit hit;
            if (!d.rays.intersect(camera.position, dir, 0.0, kInf, hit)) continue;
            const SurfacePoint p = d.rays.surface(hit);
            if (!specularOrGlossy(d.scene.materials[p.material])) continue;
            const Rgb l = specularRadiance(cache, p, -dir);
            ML_ASSERT(isFinite(l), "non-finite specular radiance at sub-pixel ", bx * reduction, ",", by * reduction);
            out.set(bx, by, l);
        }
    };
    // Rows handed out one at a time: the specular surfaces cover some rows
    // only, so a fixed split would leave a thread idle.
    const int threads = std::max(1, std::min(int(std::thread::hardware_concurrency()), bh));
    std::atomic<int> next{0};
    std::mutex mutex;
    std::exception_ptr error;
    auto worker = [&] {
        try {
            for (int by = next++; by < bh && !(cancel && cancel->load()); by = next++) row(by);
        } catch (...) {
            std::lock_guard<std::mutex> lock(mutex);
            if (!error) error = std::current_exception();
            next = bh;
        }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
    if (error) std::rethrow_exception(error);
    return out;
}

}  // namespace ml
