#include "ProgressiveSession.h"

#include "SharedLightSampler.h"
#include "core/Error.h"

#include <algorithm>
#include <filesystem>
#include <thread>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Lights gathered by bounce 1 (GatheredLights.h): only when there is a
// bounce to gather them.
std::vector<char> gatheredLightsOf(const SessionSettings& settings) {
    if (!settings.indirect || settings.indirect->bounces <= 0) return {};
    return settings.indirect->gatheredLights;
}

CacheLayout layoutFor(const std::shared_ptr<const LightCoverage>& coverage) {
    CacheLayout layout;
    layout.coverage = coverage;
    return layout;
}

}  // namespace

std::string StopRule::describe() const {
    std::string s;
    auto add = [&](const std::string& part) { s += (s.empty() ? "" : ", or ") + part; };
    if (seconds) add(concat(*seconds, " s"));
    if (error) add(concat("an estimated error of ", *error));
    if (samples) add(concat(samples, " samples"));
    add("convergence");
    return s;
}

std::string describeProgress(const CacheSnapshot& s) {
    const std::string bounces =
        s.bounces ? concat(", bounces ", s.bouncesFinished, "/", s.bounces, " (", s.indirectSamples, " gathers)") : "";
    const std::string caustics = s.causticMeshes ? concat(", ", s.causticPhotons, " caustic photons") : "";
    char error[32];
    std::snprintf(error, sizeof error, "%.3g%%", 100 * s.estimatedError);
    return concat(s.vertices, " vertices, ", s.samples, " samples", bounces, caustics, ", estimated error ", error);
}

ProgressiveSession::ProgressiveSession(const Scene& scene, const SessionSettings& settings, SamplerFactory factory,
                                       const StopRule& stop)
    : scene_(scene),
      settings_(settings),
      coverage_(std::make_shared<LightCoverage>(scene, settings.cache.lightShare, gatheredLightsOf(settings))),
      factory_(std::move(factory)),
      cache_(scene, settings.cache, layoutFor(coverage_)) {
    // Lights that share a mesh: each sampling thread's direct sampler is
    // wrapped to fill the lights' own meshes by weight and the shared one by
    // drawing lights (SharedLightSampler).
    // A gathered light's mesh has no faces, but grid caches sample every
    // light: the wrapper answers its zero weight with zero there too.
    if (cache_.hasSharedMesh() || !gatheredLightsOf(settings).empty())
        factory_ = [&scene, coverage = coverage_, inner = factory_, rays = settings.cache.sharedRays] {
            WorkerSamplers s = inner();
            s.direct = std::make_unique<SharedLightSampler>(scene, coverage, std::move(s.direct),
                                                            SharedLightSampler::kDraws,
                                                            SharedLightSampler::kFirstDraws, rays);
            return s;
        };
    settings_.worker.maxSamples = stop.samples;
    settings_.worker.validate();
    if (!settings_.cachePath.empty() && std::filesystem::exists(settings_.cachePath)) {
        cache_.load(settings_.cachePath);  // refuses a truncated, corrupt or mismatched file
        resumed_ = true;
    }
    if (settings_.indirect && settings_.indirect->bounces > 0) {
        solver_ = std::make_unique<IndirectSolver>(scene_, *settings_.indirect);
        traceCaustics();
    }
}

void ProgressiveSession::traceCaustics() {
    // Caustics are indirect light: only with it, and only where a light
    // sees a specular object (no BVH is built for a scene without one).
    auto caustics = std::make_unique<CausticCache>(scene_, settings_.caustics);
    caustics_ = caustics->active() ? std::move(caustics) : nullptr;
}

ProgressiveSession::~ProgressiveSession() {
    stop();
    release();
}

void ProgressiveSession::release() {
    std::unique_ptr<CacheWorker> w = std::move(worker_);
    if (w) std::thread([&w] { w.reset(); }).join();
}

bool ProgressiveSession::running() const { return worker_ && !worker_->finished(); }

uint64_t ProgressiveSession::start(const std::optional<RefinementCamera>& view, bool paused) {
    ML_ASSERT(!running(), "the session's worker is running already");
    release();
    SamplerFactory factory = factory_;
    if (threadSetup_) factory = [setup = threadSetup_, inner = factory_] {
        setup();
        return inner();
    };
    if (solver_) solver_->sourcesLost();  // the new worker's estimator starts empty
    worker_ = std::make_unique<CacheWorker>(cache_, std::move(factory), settings_.worker, solver_.get(), caustics_.get());
    const uint64_t serial = worker_->setCamera(view);
    startTime_ = Clock::now();
    nextTick_ = -1;
    if (paused) worker_->pause();
    worker_->start();
    return serial;
}

void ProgressiveSession::stop() {
    if (worker_) worker_->stop();
}

void ProgressiveSession::pause() {
    if (worker_) worker_->pause();
}

void ProgressiveSession::resume() {
    if (worker_) worker_->resume();
}

bool ProgressiveSession::finished() const { return !worker_ || worker_->finished(); }

uint64_t ProgressiveSession::setCamera(const std::optional<RefinementCamera>& view) {
    ML_ASSERT(worker_, "setView needs a started session");
    return worker_->setCamera(view);
}

CacheWorker::Reader ProgressiveSession::reader() {
    ML_ASSERT(worker_, "a reader needs a started session");
    return worker_->reader();
}

void ProgressiveSession::rethrowIfFailed() const {
    if (worker_) worker_->rethrowIfFailed();
}

bool ProgressiveSession::waitForVersion(uint64_t version, double timeoutSeconds) {
    return worker_ ? worker_->waitForVersion(version, timeoutSeconds) : true;
}

double ProgressiveSession::seconds() const { return secondsSince(startTime_); }

const CacheSnapshot* ProgressiveSession::refineUntil(CacheWorker::Reader& reader, const StopRule& stop,
                                                     uint64_t serial, double every,
                                                     const std::function<void(const CacheSnapshot&)>& tick) {
    ML_ASSERT(worker_, "refineUntil needs a started session");
    if (nextTick_ < 0) nextTick_ = every;
    const auto imageStart = Clock::now();
    for (;;) {
        worker_->rethrowIfFailed();
        const CacheSnapshot* s = reader.acquire();
        const bool fresh = s && s->cameraSerial >= serial;
        if (worker_->finished()) break;
        if (fresh && s->converged) break;
        if (fresh && stop.error && s->estimatedError <= *stop.error) break;
        if (stop.seconds && secondsSince(imageStart) >= *stop.seconds) break;
        if (s && tick && seconds() >= nextTick_) {
            tick(*s);
            nextTick_ = seconds() + every;
        }
        // Poll at 20 Hz, or sooner when a deadline is near.
        double wait = std::max(0.0, std::min(0.05, nextTick_ - seconds()));
        if (stop.seconds) wait = std::min(wait, std::max(0.0, *stop.seconds - secondsSince(imageStart)));
        worker_->waitForVersion((s ? s->version : 0) + 1, wait);
    }
    worker_->rethrowIfFailed();
    return reader.acquire();
}

InvalidationReport ProgressiveSession::applyChange(Scene& scene, const SceneChange& change) {
    ML_ASSERT(&scene == &scene_, "a change applies to the session's own scene");
    const AppliedChange applied = applySceneChange(scene, change);  // throws before anything changes
    stop();
    Scene before = std::move(scene);
    scene = applied.scene;
    try {
        const InvalidationReport report = invalidateCache(cache_, solver_.get(), coverage_.get(), before, applied);
        // Photons start over in the changed scene: a moved light or object
        // moves its caustics everywhere they fall.
        if (solver_) traceCaustics();
        return report;
    } catch (...) {
        scene = std::move(before);
        throw;
    }
}

void ProgressiveSession::save(const std::string& path) const {
    ML_ASSERT(!worker_ || worker_->finished(), "the cache is saved with its worker stopped");
    cache_.save(path);
}

}  // namespace ml
