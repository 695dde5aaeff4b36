#include "RealtimeIndirect.h"

#include "core/Error.h"
#include "core/Random.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;

// The share of the direct meshes' vertices that have a sample.
double sampledShare(const std::vector<IrradianceMeshCopy>& direct) {
    size_t sampled = 0, all = 0;
    for (const IrradianceMeshCopy& m : direct) {
        for (uint32_t n : m.samples) sampled += n > 0;
        all += m.samples.size();
    }
    return all ? double(sampled) / double(all) : 1.0;
}

// The two meshes have the same vertices, in the same order (the cache's
// bounce still on its base mesh, which the estimate was made on).
bool sameVertices(const IrradianceMeshCopy& a, const IrradianceMeshCopy& b) {
    return a.positions == b.positions && a.triangles.size() == b.triangles.size() &&
           a.samples.size() == a.positions.size() && a.irradiance.size() == b.irradiance.size();
}

double luminanceSum(const IrradianceMeshCopy& m) {
    double sum = 0;
    for (const Rgb& e : m.irradiance) sum += luminance(e);
    return sum;
}

std::string percent(double share) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%.0f%%", 100 * share);
    return buf;
}

}  // namespace

RealtimeMesh::RealtimeMesh(const Scene& scene, const IndirectSettings& settings) {
    const IrradianceCache cache(scene, bounceCacheSettings(settings, 1), bounceCacheLayout());
    geometry = cache.copyMesh(0);
    const size_t n = geometry.positions.size();
    geometry.irradiance.assign(n, Rgb(0.0));
    geometry.samples.assign(n, 0);
    geometry.standardError.assign(n, Rgb(0.0));
    // The cache's shading points (borders a hair inside their faces); the
    // vertices of grid-cached objects, after the mesh's own, where they are.
    const size_t own = cache.vertexCount(0);
    points.resize(n);
    for (size_t v = 0; v < n; ++v) {
        points[v].x = v < own ? cache.position(0, v) : geometry.positions[v];
        points[v].n = v < own ? cache.normal(0, v) : geometry.normals[v];
    }
}

std::optional<std::vector<IrradianceMeshCopy>> estimateBounces(const RealtimeMesh& mesh, IndirectEstimator& estimator,
                                                               const IndirectSettings& settings, int methodBounces,
                                                               const std::vector<IrradianceMeshCopy>& source,
                                                               uint32_t seed, const std::function<bool()>& cancelled) {
    std::vector<IrradianceMeshCopy> bounces;
    if (settings.bounces <= 0) return bounces;
    const int estimated = methodBounces <= 0 ? settings.bounces : std::min(methodBounces, settings.bounces);
    std::vector<SampleRequest> requests = mesh.points;
    std::vector<VertexSample> values;
    for (int b = 1; b <= settings.bounces; ++b) {
        if (cancelled && cancelled()) return std::nullopt;
        IrradianceMeshCopy m = mesh.geometry;
        if (b <= estimated) {
            // Bounce b gathers from source b − 1, as in the solver: the
            // direct meshes, then the bounce before with its share of light.
            const size_t slot = size_t(b - 1);
            if (b == 1) {
                estimator.setSource(0, source);
            } else {
                estimator.setSource(slot, {bounces.back()}, std::pow(std::max(settings.albedo, 1e-3), b - 1));
                estimator.releaseSource(slot - 1);
            }
            for (size_t v = 0; v < requests.size(); ++v)
                requests[v].seed = seedFor(seed, 0x7ea17u, uint32_t(b), uint32_t(v));
            estimator.estimateBatch(slot, requests, values);
            m.irradiance.resize(values.size());
            for (size_t v = 0; v < values.size(); ++v) m.irradiance[v] = values[v].irradiance;
            fillHiddenVertices(m);
        } else {
            // The tail, as IndirectSolver::displayMeshes makes it.
            const double r = std::clamp(settings.tailAlbedo, 0.0, 0.999);
            m.irradiance = bounces.back().irradiance;
            shapeAsLaterBounces(m, b - 1);
            for (Rgb& e : m.irradiance) e *= r;
        }
        bounces.push_back(std::move(m));
    }
    estimator.releaseSource(size_t(estimated - 1));
    return bounces;
}

IndirectShown blendIndirect(const CacheSnapshot& s, uint64_t sceneVersion, const RealtimeEstimate* estimate,
                            bool live) {
    IndirectShown out;
    const size_t caustics = std::min(s.causticMeshes, s.indirect.size());
    const bool forScene = estimate && estimate->sceneVersion == sceneVersion;
    if (!estimate || (s.indirectComplete && !live)) {
        out.meshes = s.indirect;
        out.source = "cache";
        return out;
    }
    out.estimateSerial = estimate->serial;
    double fromEstimate = 0, total = 0;
    if (live || !forScene) {
        // The estimate alone: the viewer's live display, or the one of the
        // scene before while this scene's is made.
        out.meshes = estimate->bounces;
        out.realtimeShare = 1;
        out.source = estimate->method + (live ? " (live)" : " (real-time, the pose before)");
    } else {
        for (size_t b = 0; b < estimate->bounces.size(); ++b) {
            const IrradianceMeshCopy& r = estimate->bounces[b];
            if (b >= s.bounceMeshes.size()) {  // not started by the cache
                const double sum = luminanceSum(r);
                fromEstimate += sum, total += sum;
                out.meshes.push_back(r);
                continue;
            }
            const IrradianceMeshCopy& c = s.bounceMeshes[b];
            if (!sameVertices(c, r)) {  // refined: its first pass is complete
                total += luminanceSum(c);
                out.meshes.push_back(c);
                continue;
            }
            // In its first pass: per vertex, gathered since the change or not.
            IrradianceMeshCopy m = c;
            for (size_t v = 0; v < m.irradiance.size(); ++v) {
                if (c.samples[v] == 0) {
                    m.irradiance[v] = r.irradiance[v];
                    fromEstimate += luminance(r.irradiance[v]);
                }
                total += luminance(m.irradiance[v]);
            }
            out.meshes.push_back(std::move(m));
        }
        out.realtimeShare = total > 0 ? fromEstimate / total : 1.0;
        if (out.realtimeShare >= 1)
            out.source = estimate->method + " (real-time)";
        else if (out.realtimeShare <= 0)
            out.source = "cache";
        else
            out.source = "cache " + percent(1 - out.realtimeShare) + " + " + estimate->method + " " +
                         percent(out.realtimeShare) + " (catching up)";
    }
    out.meshes.insert(out.meshes.end(), s.indirect.end() - std::ptrdiff_t(caustics), s.indirect.end());
    return out;
}

void RealtimeSettings::validate() const {
    if (methodBounces < 0 || methodBounces > 256)
        throw InputError(concat("real-time bounces ", methodBounces, " is not in 0..256"));
    if (live && method == "off") throw InputError("a live indirect display needs a real-time method, not off");
}

RealtimeIndirect::RealtimeIndirect(const IndirectSettings& indirect, EstimatorFactory factory,
                                   const RealtimeSettings& settings, int nice)
    : indirect_(indirect), factory_(std::move(factory)), settings_(settings) {
    settings_.validate();
    ML_ASSERT(factory_, "the real-time estimate needs an estimator factory");
    thread_ = std::thread([this, nice] { run(nice); });
}

RealtimeIndirect::~RealtimeIndirect() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stopping_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
}

void RealtimeIndirect::configure(const RealtimeSettings& settings) {
    settings.validate();
    settings_ = settings;
    asked_.any = false;  // the next offer asks, with these settings
    asked_.directSampled = 0, asked_.directError = 1;
}

void RealtimeIndirect::offer(const CacheSnapshot& s, uint64_t sceneVersion, const std::shared_ptr<const Scene>& scene) {
    if (settings_.method == "off" || (s.indirectComplete && !settings_.live)) return;
    const double sampled = sampledShare(s.direct);
    const bool newScene = !asked_.any || sceneVersion != asked_.sceneVersion || !asked_.scene;
    const bool filledIn = sampled >= asked_.directSampled + 0.1 || (sampled >= 1 && asked_.directSampled < 1);
    const bool refined = s.directError <= 0.5 * asked_.directError;
    if (!newScene && !filledIn && !refined) return;
    ML_ASSERT(scene || !newScene, "the first offer of a scene version hands over its scene");
    if (scene) asked_.scene = scene;
    asked_ = {sceneVersion, asked_.scene, sampled, s.directError, true};
    Request r;
    r.scene = asked_.scene;
    r.sceneVersion = sceneVersion;
    r.snapshotVersion = s.version;
    r.directSampled = sampled;
    r.settings = settings_;
    // What bounce 1 reflects: direct light and the caustics (CacheWorker).
    r.source = s.direct;
    const size_t caustics = std::min(s.causticMeshes, s.indirect.size());
    r.source.insert(r.source.end(), s.indirect.end() - std::ptrdiff_t(caustics), s.indirect.end());
    {
        std::lock_guard<std::mutex> lock(mutex_);
        pending_ = std::move(r);
    }
    wake_.notify_all();
}

std::shared_ptr<const RealtimeEstimate> RealtimeIndirect::latest() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return latest_;
}

IndirectShown RealtimeIndirect::display(const CacheSnapshot& s, uint64_t sceneVersion) const {
    const std::shared_ptr<const RealtimeEstimate> e = settings_.method == "off" ? nullptr : latest();
    return blendIndirect(s, sceneVersion, e.get(), settings_.live);
}

bool RealtimeIndirect::busy() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return working_ || pending_.has_value();
}

void RealtimeIndirect::rethrowIfFailed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (failure_) std::rethrow_exception(failure_);
}

bool RealtimeIndirect::waitIdle(uint64_t sceneVersion, double timeoutSeconds) const {
    std::unique_lock<std::mutex> lock(mutex_);
    return wake_.wait_for(lock, std::chrono::duration<double>(timeoutSeconds), [&] {
        return failure_ || (!working_ && !pending_ && latest_ && latest_->sceneVersion == sceneVersion);
    }) && !failure_;
}

void RealtimeIndirect::run(int nice) {
    if (nice > 0) ::setpriority(PRIO_PROCESS, pid_t(::syscall(SYS_gettid)), nice);
    // Declared in this order so the estimator (which reads the scene) goes first.
    std::shared_ptr<const Scene> scene;
    std::optional<RealtimeMesh> mesh;
    std::unique_ptr<IndirectEstimator> estimator;
    uint64_t version = 0;
    std::string method;
    try {
        for (;;) {
            Request r;
            {
                std::unique_lock<std::mutex> lock(mutex_);
                wake_.wait(lock, [&] { return stopping_ || pending_.has_value(); });
                if (stopping_) break;
                r = std::move(*pending_);
                pending_.reset();
                working_ = true;
            }
            const auto start = Clock::now();
            if (!estimator || r.sceneVersion != version || r.scene != scene || r.settings.method != method) {
                estimator.reset();
                if (r.scene != scene || !mesh) mesh.emplace(*r.scene, indirect_);
                scene = r.scene;
                estimator = factory_(*scene, r.settings.method);
                version = r.sceneVersion;
                method = r.settings.method;
            }
            const auto cancelled = [this] {
                std::lock_guard<std::mutex> lock(mutex_);
                return stopping_;
            };
            std::optional<std::vector<IrradianceMeshCopy>> bounces = estimateBounces(
                *mesh, *estimator, indirect_, r.settings.methodBounces, r.source, r.settings.seed, cancelled);
            if (!bounces) break;
            auto e = std::make_shared<RealtimeEstimate>();
            e->method = r.settings.method;
            e->sceneVersion = r.sceneVersion;
            e->snapshotVersion = r.snapshotVersion;
            e->directSampled = r.directSampled;
            e->bounces = std::move(*bounces);
            e->seconds = std::chrono::duration<double>(Clock::now() - start).count();
            {
                std::lock_guard<std::mutex> lock(mutex_);
                e->serial = ++serial_;
                latest_ = std::move(e);
                working_ = false;
            }
            wake_.notify_all();
        }
    } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        failure_ = std::current_exception();
    }
    {
        std::lock_guard<std::mutex> lock(mutex_);
        working_ = false;
    }
    wake_.notify_all();
}

}  // namespace ml
