#include "RealtimeIndirect.h"

#include "core/Error.h"
#include "core/Random.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <unordered_map>

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

// A quarter or more of a bounce's vertices are gathered (have a sample).
bool quarterGathered(const std::vector<uint32_t>& samples) {
    const size_t gathered = samples.size() - size_t(std::count(samples.begin(), samples.end(), 0u));
    return !samples.empty() && 4 * gathered >= samples.size();
}

double luminanceSum(const IrradianceMeshCopy& m) {
    double sum = 0;
    for (const Rgb& e : m.irradiance) sum += luminance(e);
    return sum;
}

// A vertex by its position and normal, bit for bit (−0 read as 0): the
// same surface point of two layouts of one scene's unmoved geometry.
struct VertexKey {
    std::array<uint64_t, 6> bits;
    bool operator==(const VertexKey& o) const { return bits == o.bits; }
};

struct VertexKeyHash {
    size_t operator()(const VertexKey& k) const {
        uint64_t h = 0x9e3779b97f4a7c15ull;
        for (uint64_t b : k.bits) h = (h ^ b) * 0x100000001b3ull, h ^= h >> 29;
        return size_t(h);
    }
};

VertexKey keyOf(const Vec3& p, const Vec3& n) {
    VertexKey k;
    const double x[6] = {p.x + 0.0, p.y + 0.0, p.z + 0.0, n.x + 0.0, n.y + 0.0, n.z + 0.0};
    std::memcpy(k.bits.data(), x, sizeof x);
    return k;
}

using VertexIndex = std::unordered_map<VertexKey, uint32_t, VertexKeyHash>;

VertexIndex indexOf(const IrradianceMeshCopy& m) {
    VertexIndex index;
    index.reserve(m.positions.size());
    for (size_t v = 0; v < m.positions.size(); ++v) index.emplace(keyOf(m.positions[v], m.normals[v]), uint32_t(v));
    return index;
}

bool hasNormals(const IrradianceMeshCopy& m) {
    return m.normals.size() == m.positions.size() && m.irradiance.size() == m.positions.size();
}

std::string percent(double share) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%.0f%%", 100 * share);
    return buf;
}

}  // namespace

RealtimeMesh::RealtimeMesh(const Scene& scene, const IndirectSettings& settings, const CacheLayout& layout_)
    : layout(layout_) {
    const IrradianceCache cache(scene, bounceCacheSettings(settings, 1), layout);
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
    return chainBounces(mesh, estimator, settings, methodBounces, {}, source, seed, cancelled);
}

std::optional<std::vector<IrradianceMeshCopy>> chainBounces(const RealtimeMesh& mesh, IndirectEstimator& estimator,
                                                            const IndirectSettings& settings, int methodBounces,
                                                            std::vector<IrradianceMeshCopy> known,
                                                            const std::vector<IrradianceMeshCopy>& source,
                                                            uint32_t seed, const std::function<bool()>& cancelled) {
    std::vector<IrradianceMeshCopy> bounces = std::move(known);
    if (settings.bounces <= 0) return std::vector<IrradianceMeshCopy>{};
    bounces.resize(std::min(bounces.size(), size_t(settings.bounces)));
    const int first = int(bounces.size()) + 1;
    const int estimated = methodBounces <= 0 ? settings.bounces : std::min(methodBounces, settings.bounces);
    std::vector<SampleRequest> requests = mesh.points;
    std::vector<VertexSample> values;
    for (int b = first; b <= settings.bounces; ++b) {
        if (cancelled && cancelled()) return std::nullopt;
        IrradianceMeshCopy m = mesh.geometry;
        if (b <= estimated) {
            // Bounce b gathers from source b − 1, as in the solver: the
            // direct meshes, then the bounce before with its share of light
            // (the cache's own for the first one chained onto it).
            const size_t slot = size_t(b - 1);
            if (b == 1) {
                estimator.setSource(0, source);
            } else {
                const double share = std::pow(std::max(settings.albedo, 1e-3), b - 1);
                estimator.setSource(slot, b == first ? source : std::vector<IrradianceMeshCopy>{bounces.back()}, share);
                if (b > first) estimator.releaseSource(slot - 1);
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
    if (estimated >= first) estimator.releaseSource(size_t(estimated - 1));
    return bounces;
}

// The power of correctByChange's trust (RealtimeIndirect.h): measured at 1,
// 3 and 6 (bench dynamic --quick, three moves of the Cornell box, each
// method): 6 beats the method alone in all nine cases, 1 and 3 lose where a
// light moved far (volume 2.07% and 1.85% against 1.70%). With every
// bounce estimated (the full bench) volume still loses there (1.93% against
// 1.74%): its later bounces change more than the first's trust allows for.
constexpr double kTrustPower = 6;

// Estimates in a row a later scene's request may end (run()): two, so that
// while a motion's poses come faster than estimates every third is shown.
constexpr int kObsoleteInARow = 2;

double correctByChange(std::vector<IrradianceMeshCopy>& estimate, const std::vector<IrradianceMeshCopy>& baseline,
                       const std::vector<IrradianceMeshCopy>& before) {
    size_t changed = 0, all = 0;
    for (size_t b = 0; b < estimate.size(); ++b) {
        IrradianceMeshCopy& e = estimate[b];
        all += e.positions.size();
        if (b >= baseline.size() || b >= before.size() || !hasNormals(e) || !hasNormals(baseline[b]) ||
            !hasNormals(before[b]))
            continue;
        const VertexIndex baseAt = indexOf(baseline[b]), oldAt = indexOf(before[b]);
        for (size_t v = 0; v < e.positions.size(); ++v) {
            const VertexKey k = keyOf(e.positions[v], e.normals[v]);
            const auto i = baseAt.find(k), j = oldAt.find(k);
            if (i == baseAt.end() || j == oldAt.end()) continue;
            const Rgb& base = baseline[b].irradiance[i->second];
            const Rgb& old = before[b].irradiance[j->second];
            // The trust in the method's old error: 1 where the method's
            // light did not change, falling fast as it changes against the
            // light it had (kTrustPower), 1 where both are dark (the method
            // misses that light in both poses).
            const double lb = luminance(base), moved = std::abs(luminance(e.irradiance[v]) - lb);
            const double w = lb + moved > 0 ? std::pow(lb / (lb + moved), kTrustPower) : 1.0;
            e.irradiance[v] = glm::max(e.irradiance[v] + w * (old - base), Rgb(0.0));
            ++changed;
        }
    }
    return all ? double(changed) / double(all) : 0.0;
}

double standInError(const std::vector<IrradianceMeshCopy>& estimate, const std::vector<IrradianceMeshCopy>& cache) {
    const double none = std::numeric_limits<double>::infinity();
    if (estimate.empty() || cache.empty() || !hasNormals(estimate.front())) return none;
    const size_t bounces = std::min(estimate.size(), cache.size());
    std::vector<VertexIndex> at;
    for (size_t b = 0; b < bounces; ++b) {
        if (!hasNormals(cache[b]) || !hasNormals(estimate[b]) ||
            estimate[b].positions.size() != estimate.front().positions.size())
            return none;
        at.push_back(indexOf(cache[b]));
    }
    double off = 0, light = 0;
    const IrradianceMeshCopy& mesh = estimate.front();
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        const VertexKey k = keyOf(mesh.positions[v], mesh.normals[v]);
        double e = 0, c = 0;
        bool everywhere = true;
        for (size_t b = 0; b < bounces && everywhere; ++b) {
            const auto i = at[b].find(k);
            everywhere = i != at[b].end();
            if (everywhere) e += luminance(estimate[b].irradiance[v]), c += luminance(cache[b].irradiance[i->second]);
        }
        if (!everywhere) continue;
        off += std::abs(e - c);
        light += c;
    }
    return light > 0 && std::isfinite(off) ? off / light : none;
}

int chooseStandIn(const std::vector<StandInTrial>& trials) {
    if (trials.empty()) return -1;
    double fastest = std::numeric_limits<double>::infinity();
    for (const StandInTrial& t : trials) fastest = std::min(fastest, t.seconds);
    const double slowest = std::max(kStandInSlowFactor * fastest, kStandInSlowSeconds);
    int best = -1;
    for (size_t i = 0; i < trials.size(); ++i) {
        if (trials[i].seconds > slowest) continue;
        // Ties, and methods none of whose vertices compare, go to the
        // faster (infinity never beats a finite error).
        if (best < 0 || trials[i].error < trials[size_t(best)].error ||
            (!(trials[i].error > trials[size_t(best)].error) && trials[i].seconds < trials[size_t(best)].seconds))
            best = int(i);
    }
    return best;
}

std::string describeTrials(const std::vector<StandInTrial>& trials, int chosen) {
    std::string out;
    for (size_t i = 0; i < trials.size(); ++i) {
        const StandInTrial& t = trials[i];
        char error[32] = "not comparable,", buf[160];
        if (std::isfinite(t.error)) std::snprintf(error, sizeof error, "%.2g%% in", 100 * t.error);
        std::snprintf(buf, sizeof buf, "%s%s %s %.2g s%s", i ? "; " : "", t.method.c_str(), error, t.seconds,
                      int(i) == chosen ? " (chosen)" : "");
        out += buf;
    }
    return out;
}

int gatheredBounces(const CacheSnapshot& s) {
    if (s.indirectComplete) return 0;
    int k = 0;
    for (const IrradianceMeshCopy& m : s.bounceMeshes) {
        if (m.samples.empty() || std::find(m.samples.begin(), m.samples.end(), 0u) != m.samples.end()) break;
        ++k;
    }
    return k;
}

namespace {

// How far the cache's bounces are gathered, for chaining: 2k with bounces
// 1..k gathered, 2k + 1 when bounce k + 1 also has a quarter of its
// vertices gathered (its copy fills the rest from gathered neighbours).
int chainLevel(const CacheSnapshot& s) {
    const int k = gatheredBounces(s);
    if (k == 0 && s.indirectComplete) return 0;
    if (size_t(k) >= s.bounceMeshes.size()) return 2 * k;
    return 2 * k + (quarterGathered(s.bounceMeshes[size_t(k)].samples) ? 1 : 0);
}

}  // namespace

IndirectShown blendIndirect(const CacheSnapshot& s, uint64_t sceneVersion, const RealtimeEstimate* estimate,
                            bool live) {
    IndirectShown out;
    const size_t caustics = std::min(s.causticMeshes, s.indirect.size());
    const bool forScene = estimate && estimate->sceneVersion == sceneVersion;
    if (!estimate || ((s.indirectComplete || s.oldIndirectKept) && !live)) {
        out.meshes = s.indirect;
        out.source = s.oldIndirectKept ? "cache (the pose before, until gathered again)" : "cache";
        return out;
    }
    out.estimateSerial = estimate->serial;
    double fromEstimate = 0, total = 0;
    const std::string method = estimate->method + (estimate->onOldLight > 0 ? " on the old light" : "");
    if (live || !forScene) {
        // The estimate alone: the viewer's live display, or the one of the
        // scene before while this scene's is made.
        out.meshes = estimate->bounces;
        out.realtimeShare = 1;
        out.source = method + (live ? " (live)" : " (real-time, the pose before)");
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
            // In its first pass, a quarter or more gathered: the cache's
            // copy, which fills the rest from gathered neighbours (what the
            // stand-in's later bounces are chained onto then; the cache's
            // own display shows bounce 1 from a sixteenth). Measured by
            // bench dynamic, the light moved, while bounce 1 was gathered:
            // per vertex (the stand-in's value where not gathered) 2.6-3.7%
            // from the converged image in two runs, the copy from a quarter
            // on 2.5-2.8% in one.
            if (quarterGathered(c.samples)) {
                total += luminanceSum(c);
                out.meshes.push_back(c);
                continue;
            }
            // Under a quarter: per vertex, gathered since the change or not.
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
            out.source = method + " (real-time)";
        else if (out.realtimeShare <= 0)
            out.source = "cache";
        else
            out.source = "cache " + percent(1 - out.realtimeShare) + " + " + method + " " +
                         percent(out.realtimeShare) + " (catching up)";
    }
    out.meshes.insert(out.meshes.end(), s.indirect.end() - std::ptrdiff_t(caustics), s.indirect.end());
    return out;
}

void RealtimeSettings::validate() const {
    if (methodBounces != kBouncesFromScene && (methodBounces < 0 || methodBounces > 256))
        throw InputError(concat("real-time bounces ", methodBounces, " is not in 0..256"));
    if (live && (method == "off" || method == "auto"))
        throw InputError(concat("a live indirect display needs a real-time method, not ", method));
    if (method == "auto" && candidates.empty())
        throw InputError("the real-time stand-in 'auto' needs methods to choose from");
}

std::string RealtimeIndirect::methodFor(const RealtimeSettings& settings) const {
    if (settings.method != "auto") return settings.method;
    std::lock_guard<std::mutex> lock(mutex_);
    return chosen_ < 0 ? settings.candidates.front() : trials_[size_t(chosen_)].method;
}

std::string RealtimeIndirect::choice() const {
    if (settings_.method != "auto") return "";
    std::lock_guard<std::mutex> lock(mutex_);
    if (chosen_ < 0)
        return concat(settings_.candidates.front(), " until the methods are measured on the first complete cache");
    return concat(trials_[size_t(chosen_)].method, ", chosen by its error on this scene's complete cache: ",
                  describeTrials(trials_, chosen_));
}

std::vector<StandInTrial> RealtimeIndirect::trials() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return trials_;
}

bool RealtimeIndirect::waitBaseline(double timeoutSeconds) const {
    std::unique_lock<std::mutex> lock(mutex_);
    return wake_.wait_for(lock, std::chrono::duration<double>(timeoutSeconds),
                          [&] { return failure_ || (!baselineWanted_ && !baselining_); }) &&
           !failure_;
}

int standInBounces(const IndirectSettings& indirect) {
    const double r = std::clamp(indirect.tailAlbedo, 0.0, 0.999);
    int k = 1;
    while (k < indirect.bounces && std::pow(r, k) > kStandInTailShare) ++k;
    return std::max(0, std::min(k, indirect.bounces));
}

RealtimeSettings RealtimeIndirect::resolved(RealtimeSettings settings) const {
    settings.validate();
    // Live, the method itself is shown: every bounce of it.
    if (settings.methodBounces == RealtimeSettings::kBouncesFromScene)
        settings.methodBounces = settings.live ? 0 : standInBounces(indirect_);
    return settings;
}

RealtimeIndirect::RealtimeIndirect(const IndirectSettings& indirect, EstimatorFactory factory,
                                   const RealtimeSettings& settings, int nice)
    : indirect_(indirect), factory_(std::move(factory)), settings_(resolved(settings)) {
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
    settings_ = resolved(settings);
    asked_.any = false;  // the next offer asks, with these settings
    asked_.directSampled = 0, asked_.directError = 1;
}

void RealtimeIndirect::offer(const CacheSnapshot& s, uint64_t sceneVersion, const std::shared_ptr<const Scene>& scene) {
    if (scene) offeredScene_ = scene, offeredVersion_ = sceneVersion;
    if (settings_.method == "off") return;
    if (s.indirectComplete && !s.oldIndirectKept && !settings_.live) {
        keepBefore(s, sceneVersion);
        return;
    }
    if (s.oldIndirectKept && !settings_.live) return;
    const double sampled = sampledShare(s.direct);
    const bool newScene = !asked_.any || sceneVersion != asked_.sceneVersion || !asked_.scene;
    const int level = settings_.live ? 0 : chainLevel(s);
    // A bounce gathered again (IndirectSolver::restart) is chained onto
    // again as it fills in.
    if (!newScene) asked_.chained = std::min(asked_.chained, level);
    const bool chain = level > 0 && (newScene || level > asked_.chained);
    const bool filledIn = sampled >= asked_.directSampled + 0.1 || (sampled >= 1 && asked_.directSampled < 1);
    const bool refined = s.directError <= 0.5 * asked_.directError;
    if (!newScene && !chain && (level > 0 || (!filledIn && !refined))) return;
    ML_ASSERT(scene || !newScene, "the first offer of a scene version hands over its scene");
    if (scene) asked_.scene = scene;
    asked_ = {sceneVersion, asked_.scene, sampled, s.directError, true, level};
    Request r;
    r.scene = asked_.scene;
    r.sceneVersion = sceneVersion;
    r.snapshotVersion = s.version;
    r.directSampled = sampled;
    r.settings = settings_;
    r.settings.method = methodFor(settings_);
    // What bounce 1 reflects: direct light and the caustics (CacheWorker).
    r.source = s.direct;
    const size_t caustics = std::min(s.causticMeshes, s.indirect.size());
    r.source.insert(r.source.end(), s.indirect.end() - std::ptrdiff_t(caustics), s.indirect.end());
    r.known.assign(s.bounceMeshes.begin(), s.bounceMeshes.begin() + (level + 1) / 2);
    r.level = level;
    r.layout = s.bounceLayout;
    if (level == 0 && !settings_.live && before_ && before_->sceneVersion != sceneVersion) r.before = before_;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        pending_ = std::move(r);
    }
    wake_.notify_all();
}

void RealtimeIndirect::keepBefore(const CacheSnapshot& s, uint64_t sceneVersion) {
    const double now = std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
    const size_t caustics = std::min(s.causticMeshes, s.indirect.size());
    if (!offeredScene_ || offeredVersion_ != sceneVersion || s.indirect.size() == caustics) return;
    const bool first = !before_ || before_->sceneVersion != sceneVersion;
    if (!first && (before_->snapshotVersion == s.version || now - beforeTakenAt_ < kBeforeSeconds)) return;
    auto b = std::make_shared<Before>();
    b->scene = offeredScene_;
    b->sceneVersion = sceneVersion;
    b->snapshotVersion = s.version;
    if (first) {
        auto source = std::make_shared<std::vector<IrradianceMeshCopy>>(s.direct);
        source->insert(source->end(), s.indirect.end() - std::ptrdiff_t(caustics), s.indirect.end());
        b->source = std::move(source);
    } else {
        b->source = before_->source;
    }
    // Of the bounces, only what correctByChange reads: this copy is made on
    // the frame thread, once a second while the cache is complete.
    for (auto m = s.indirect.begin(); m != s.indirect.end() - std::ptrdiff_t(caustics); ++m) {
        IrradianceMeshCopy& c = b->bounces.emplace_back();
        c.positions = m->positions;
        c.normals = m->normals;
        c.irradiance = m->irradiance;
    }
    b->layout = s.bounceLayout;
    before_ = b;
    beforeTakenAt_ = now;
    if (first) {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            baselineWanted_.emplace(std::move(b), settings_);
        }
        wake_.notify_all();
    }
}

std::shared_ptr<const RealtimeEstimate> RealtimeIndirect::latest() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return latest_;
}

IndirectShown RealtimeIndirect::display(const CacheSnapshot& s, uint64_t sceneVersion) const {
    const std::shared_ptr<const RealtimeEstimate> e = settings_.method == "off" ? nullptr : latest();
    // An estimate of an earlier scene made before that scene's cache was
    // complete (estimates are made only while it is not) is older than the
    // cache's old light, which is exact for that pose: while this scene's
    // estimate is made, the old light shows (a single move after the cache
    // settled; a motion's intermediate poses have newer estimates).
    if (e && !settings_.live && e->sceneVersion != sceneVersion && s.indirectStale && before_ &&
        before_->sceneVersion >= e->sceneVersion && before_->sceneVersion != sceneVersion) {
        IndirectShown shown;
        shown.meshes = s.indirect;
        shown.source = "cache (the pose before, until the estimate comes)";
        shown.choice = choice();
        return shown;
    }
    IndirectShown shown = blendIndirect(s, sceneVersion, e.get(), settings_.live);
    shown.choice = choice();
    return shown;
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
    int obsoleteInARow = 0;  // estimates ended in a row by a later scene's request
    // The baseline: the method's bounces for the pose before's direct light
    // (Before::source, held so that its address names it), with the
    // settings it was made with.
    struct Baseline {
        std::shared_ptr<const std::vector<IrradianceMeshCopy>> source;
        RealtimeSettings settings;
        std::vector<IrradianceMeshCopy> bounces;
    } baseline;
    const auto haveBaseline = [&](const Before& b, const RealtimeSettings& rs) {
        return baseline.source == b.source && baseline.settings.method == rs.method &&
               baseline.settings.methodBounces == rs.methodBounces && baseline.settings.seed == rs.seed;
    };
    // `laid`: the pose before's mesh, if already laid (null: laid here).
    const auto makeBaseline = [&](const Before& b, const RealtimeSettings& rs, const std::function<bool()>& cancelled,
                                  const RealtimeMesh* laid = nullptr) {
        baseline = {};
        std::optional<RealtimeMesh> own;
        const RealtimeMesh& old = laid ? *laid : own.emplace(*b.scene, indirect_, b.layout);
        const std::unique_ptr<IndirectEstimator> e = factory_(*b.scene, rs.method);
        std::optional<std::vector<IrradianceMeshCopy>> made =
            estimateBounces(old, *e, indirect_, rs.methodBounces, *b.source, rs.seed, cancelled);
        if (made) baseline = {b.source, rs, std::move(*made)};
    };
    try {
        for (;;) {
            Request r;
            std::optional<std::pair<std::shared_ptr<const Before>, RealtimeSettings>> wanted;
            {
                std::unique_lock<std::mutex> lock(mutex_);
                wake_.wait(lock, [&] { return stopping_ || pending_.has_value() || baselineWanted_.has_value(); });
                if (stopping_) break;
                if (pending_) {
                    r = std::move(*pending_);
                    pending_.reset();
                    working_ = true;
                } else {
                    wanted = std::move(baselineWanted_);
                    baselineWanted_.reset();
                    baselining_ = true;
                }
            }
            if (wanted) {  // idle: the baseline of a complete cache, before any change asks for it
                const Before& b = *wanted->first;
                RealtimeSettings rs = wanted->second;
                std::string chosen;
                {
                    std::lock_guard<std::mutex> lock(mutex_);
                    if (chosen_ >= 0) chosen = trials_[size_t(chosen_)].method;
                }
                if (rs.method == "auto" && chosen.empty()) {
                    // Auto's measurement: every candidate's baseline, each
                    // against the complete cache's bounces; a request
                    // (a change) ends it, and the next complete cache
                    // measures again.
                    const auto interrupted = [this] {
                        std::lock_guard<std::mutex> lock(mutex_);
                        return stopping_ || pending_.has_value();
                    };
                    // The pose before's mesh is laid once; each method's
                    // time counts it, as each lays it after a change.
                    const auto laying = Clock::now();
                    const RealtimeMesh old(*b.scene, indirect_, b.layout);
                    const double laid = std::chrono::duration<double>(Clock::now() - laying).count();
                    std::vector<StandInTrial> trials;
                    std::vector<Baseline> made;
                    for (const std::string& m : rs.candidates) {
                        RealtimeSettings one = rs;
                        one.method = m;
                        const auto t = Clock::now();
                        makeBaseline(b, one, interrupted, &old);
                        if (baseline.bounces.empty()) break;
                        trials.push_back({m, standInError(baseline.bounces, b.bounces),
                                          laid + std::chrono::duration<double>(Clock::now() - t).count()});
                        made.push_back(std::move(baseline));
                        baseline = {};
                    }
                    const int best = trials.size() == rs.candidates.size() ? chooseStandIn(trials) : -1;
                    if (best >= 0) baseline = std::move(made[size_t(best)]);
                    std::lock_guard<std::mutex> lock(mutex_);
                    if (best >= 0) chosen_ = best, trials_ = std::move(trials);
                } else {
                    if (rs.method == "auto") rs.method = chosen;
                    if (!haveBaseline(b, rs))
                        makeBaseline(b, rs, [this] {
                            std::lock_guard<std::mutex> lock(mutex_);
                            return stopping_;
                        });
                }
                {
                    std::lock_guard<std::mutex> lock(mutex_);
                    baselining_ = false;
                }
                wake_.notify_all();
                continue;
            }
            const auto start = Clock::now();
            const bool relaid = mesh && (mesh->layout.borderInset != r.layout.borderInset ||
                                         mesh->layout.backFaces != r.layout.backFaces);
            if (!estimator || r.sceneVersion != version || r.scene != scene || r.settings.method != method ||
                relaid) {
                estimator.reset();
                if (r.scene != scene || !mesh || relaid) mesh.emplace(*r.scene, indirect_, r.layout);
                scene = r.scene;
                estimator = factory_(*scene, r.settings.method);
                version = r.sceneVersion;
                method = r.settings.method;
            }
            // Chained onto the cache's gathered bounces that are still on
            // the base mesh (a first pass; a refined one means the cache is
            // about to be complete): bounce k + 1 gathers from the cache's
            // bounce k, not from the method's own.
            size_t chained = 0;
            while (chained < r.known.size() && sameVertices(r.known[chained], mesh->geometry)) ++chained;
            r.known.resize(chained);
            const std::vector<IrradianceMeshCopy> source =
                chained > 0 ? std::vector<IrradianceMeshCopy>{r.known.back()} : std::move(r.source);
            // A request chained further (chainLevel) for the same scene
            // makes this one obsolete; so does one for a later scene (a
            // motion's next pose), unless kObsoleteInARow estimates in a
            // row ended so: a motion's last pose is then estimated at once,
            // not after the pose before it, and while poses keep coming an
            // estimate still comes every few.
            const bool mayEndForLater = obsoleteInARow < kObsoleteInARow && !r.settings.live;
            const auto laterScene = [this, &r] {
                return pending_ && pending_->sceneVersion != r.sceneVersion && !pending_->settings.live;
            };
            const auto cancelled = [this, &r, mayEndForLater, &laterScene] {
                std::lock_guard<std::mutex> lock(mutex_);
                return stopping_ ||
                       (pending_ && pending_->sceneVersion == r.sceneVersion &&
                        pending_->settings.method == r.settings.method && pending_->level > r.level) ||
                       (mayEndForLater && laterScene());
            };
            // The pose before's baseline (made while idle unless the change
            // came first).
            const bool onOld = chained == 0 && r.before;
            if (onOld && !haveBaseline(*r.before, r.settings)) makeBaseline(*r.before, r.settings, cancelled);
            std::optional<std::vector<IrradianceMeshCopy>> bounces =
                chainBounces(*mesh, *estimator, indirect_, r.settings.methodBounces, std::move(r.known), source,
                             r.settings.seed, cancelled);
            double onOldLight = 0;
            if (bounces && onOld && haveBaseline(*r.before, r.settings))
                onOldLight = correctByChange(*bounces, baseline.bounces, r.before->bounces);
            if (!bounces) {
                std::lock_guard<std::mutex> lock(mutex_);
                if (stopping_) break;
                if (mayEndForLater && laterScene()) ++obsoleteInARow;
                continue;  // the pending request follows
            }
            obsoleteInARow = 0;
            auto e = std::make_shared<RealtimeEstimate>();
            e->method = r.settings.method;
            e->sceneVersion = r.sceneVersion;
            e->snapshotVersion = r.snapshotVersion;
            e->directSampled = r.directSampled;
            e->chained = int(chained);
            e->bounces = std::move(*bounces);
            e->onOldLight = onOldLight;
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
