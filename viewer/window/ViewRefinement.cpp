#include "ViewRefinement.h"

#include "gpu_sampling/SamplerFactory.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cstdio>
#include <utility>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;

// How long the camera must rest between two views sent to the worker: a
// new view restarts its scoring, so sending one every frame would waste it.
constexpr double kViewInterval = 0.1;
// The share of a frame spent copying a newer snapshot to the GPU.
constexpr double kUploadBudget = 0.004;

bool sameCamera(const Camera& a, const Camera& b) {
    return a.position == b.position && a.target == b.target && a.up == b.up && a.fovYDegrees == b.fovYDegrees;
}

}  // namespace

void ViewRefinement::lowerWorkerPriority(ProgressiveSession& session) {
    session.setThreadSetup([] { ::setpriority(PRIO_PROCESS, pid_t(::syscall(SYS_gettid)), kWorkerNice); });
}

std::unique_ptr<ProgressiveSession> ViewRefinement::makeSession(const Scene& scene, const ViewSettings& settings) {
    SessionSettings ss;
    ss.cache = settings.cache;
    ss.worker = settings.worker;
    if (settings.indirect.active()) ss.indirect = settings.indirect.solver;
    ss.cachePath = settings.cachePath;
    // The stand-in shows indirect light meanwhile: it is gathered once
    // direct light's first pass is complete, not from an incomplete one.
    ss.worker.indirectStandIn = settings.indirect.active() && settings.realtime.realtime != "off";
    StopRule budget;
    budget.samples = settings.worker.maxSamples;
    auto session = std::make_unique<ProgressiveSession>(scene, ss, samplerFactory(scene, settings.direct, settings.indirect),
                                                        budget);
    // Each sampling thread lowers its own priority before its samplers (and
    // their GL threads) exist. Frames then take the processor when they need
    // it and refinement the rest: the frame rate does not depend on
    // refinement even where the two share too few cores (llvmpipe renders
    // both on the CPU).
    lowerWorkerPriority(*session);
    if (session->resumed())
        std::printf("cache: resumed from %s: %zu vertices, %llu samples\n", settings.cachePath.c_str(),
                    session->cache().totalVertices(), static_cast<unsigned long long>(session->cache().totalSamples()));
    return session;
}

ViewRefinement::ViewRefinement(std::unique_ptr<ProgressiveSession> session, const Scene& scene,
                               const ViewSettings& settings, CacheMeshUploader& uploader)
    : settings_(settings), uploader_(uploader), session_(std::move(session)),
      realtimeChoice_(settings.realtime) {
    if (session_->indirect()) {
        realtime_ = std::make_unique<RealtimeIndirect>(
            session_->indirect()->settings(), realtimeEstimatorFactory(settings.indirect),
            realtimeChoice_.settings(settings.worker.seed), kRealtimeNice);
        sceneCopy_ = std::make_shared<const Scene>(scene);
    }
}

ViewRefinement::~ViewRefinement() {
    // The worker may still be saving (its helper stops it): finish that first.
    if (save_ && save_->thread.joinable()) save_->thread.join();
    if (change_ && change_->thread.joinable()) change_->thread.join();
    stopWorker();
}

double ViewRefinement::now() const { return std::chrono::duration<double>(Clock::now() - t0_).count(); }

void ViewRefinement::start(const Camera& camera, int width, int height) {
    ++generation_;
    sentSerial_ = session_->start(RefinementCamera{camera, width, height}, paused_);
    noteSent(camera, width, height);
    reader_ = session_->reader();
    offered_ = 0;  // a new worker numbers its snapshots from 1
    started_ = true;
}

void ViewRefinement::setRealtime(const RealtimeChoice& choice) {
    choice.validate();
    realtimeChoice_ = choice;
    if (!realtime_) return;
    realtime_->configure(choice.settings(settings_.worker.seed));
    offered_ = 0;  // offer the snapshot shown again, and show what it blends to
    estimateConsidered_ = ~uint64_t(0);
}

// Ends the worker (joining it); the next start frees it.
void ViewRefinement::stopWorker() {
    reader_ = CacheWorker::Reader();
    uploading_ = nullptr;
    session_->stop();
    started_ = false;
}

void ViewRefinement::noteSent(const Camera& camera, int width, int height) {
    sentCamera_ = camera;
    sentWidth_ = width;
    sentHeight_ = height;
    sentAt_ = now();
    viewDirty_ = false;
}

void ViewRefinement::follow(const Camera& camera, int width, int height) {
    if (!started_) return;
    if (!sameCamera(camera, sentCamera_) || width != sentWidth_ || height != sentHeight_) viewDirty_ = true;
    if (viewDirty_ && !save_ && !change_ && now() - sentAt_ >= kViewInterval) {
        sentSerial_ = session_->setCamera(RefinementCamera{camera, width, height});
        noteSent(camera, width, height);
    }
}

std::optional<std::string> ViewRefinement::newFailure() {
    if (!started_ || !error_.empty()) return std::nullopt;
    try {
        session_->rethrowIfFailed();
        if (realtime_) realtime_->rethrowIfFailed();
    } catch (const std::exception& e) {
        error_ = e.what();
        return error_;
    }
    return std::nullopt;
}

bool ViewRefinement::pump(double& uploadMs) {
    uploadMs = 0;
    if (!started_) return false;
    const auto start = Clock::now();
    if (!uploader_.busy()) {
        const CacheSnapshot* s = reader_.acquire();
        // The stand-in is offered every snapshot (it decides whether to
        // estimate again); a newer estimate is shown as a newer snapshot is.
        if (s && realtime_ && s->version != offered_) {
            realtime_->offer(*s, sceneVersion_, sceneCopy_);
            offered_ = s->version;
        }
        const std::shared_ptr<const RealtimeEstimate> estimate = realtime_ ? realtime_->latest() : nullptr;
        const uint64_t newest = estimate ? estimate->serial : 0;
        if (s && (!shown_.any || shown_.generation != generation_ || s->version != shown_.version ||
                  newest != estimateConsidered_)) {
            uploading_ = s;
            estimateConsidered_ = newest;
            if (realtime_) {
                uploadingIndirect_ = realtime_->display(*s, sceneVersion_);
            } else {
                uploadingIndirect_ = IndirectShown{};
                uploadingIndirect_.source = "cache";
            }
            uploader_.start(s->direct, realtime_ ? uploadingIndirect_.meshes : s->indirect);
        }
    }
    bool swapped = false;
    if (uploader_.busy()) {
        // The first snapshot is copied whole: there is nothing to show before it.
        swapped = uploader_.step(shown_.any ? kUploadBudget : 1e9);
        if (swapped) {
            const CacheSnapshot& s = *uploading_;
            shown_.any = true;
            shown_.generation = generation_;
            shown_.version = s.version;
            shown_.seconds = s.seconds;
            shown_.vertices = s.vertices;
            shown_.triangles = uploader_.front().triangleCount();
            shown_.indirectMeshes = s.indirect.size();
            shown_.samples = s.samples;
            shown_.rounds = s.rounds;
            shown_.cameraSerial = s.cameraSerial;
            shown_.estimatedError = s.estimatedError;
            shown_.converged = s.converged;
            shown_.indirectSource = uploadingIndirect_.source;
            shown_.realtimeShare = uploadingIndirect_.realtimeShare;
            shown_.standInChoice = uploadingIndirect_.choice;
            if (onShown_) onShown_(s, realtime_ ? uploadingIndirect_.meshes : s.indirect);
            uploading_ = nullptr;
        }
    }
    uploadMs = 1e3 * std::chrono::duration<double>(Clock::now() - start).count();
    return swapped;
}

void ViewRefinement::setPaused(bool paused) {
    paused_ = paused;
    if (started_) paused ? session_->pause() : session_->resume();
}

bool ViewRefinement::done() const {
    if (!started_ || save_ || change_ || !shown_.any || shown_.generation != generation_ || uploader_.busy()) return false;
    if (!error_.empty() || paused_) return true;
    // Nothing newer published since the snapshot shown (safe to acquire: no
    // copy is in progress).
    const CacheSnapshot* latest = reader_.acquire();
    // The stand-in too: no estimate under way, the newest one shown.
    if (realtime_ && (realtime_->busy() || (realtime_->latest() ? realtime_->latest()->serial : 0) != estimateConsidered_))
        return false;
    const bool newest = latest && latest->version == shown_.version;
    if (session_->finished()) return newest;
    return newest && shown_.converged && shown_.cameraSerial >= sentSerial_ && !viewDirty_;
}

bool ViewRefinement::beginSave(const std::string& path) {
    if (save_ || change_ || !started_) return false;
    save_ = std::make_unique<SaveJob>();
    save_->path = path;
    SaveJob* job = save_.get();
    ProgressiveSession* refining = session_.get();
    job->thread = std::thread([job, refining] {
        try {
            refining->stop();  // the round in progress ends first; the cache is ours after the join
            refining->save(job->path);
        } catch (const std::exception& e) {
            job->error = e.what();
        }
        job->done.store(true);
    });
    return true;
}

std::optional<ViewRefinement::SaveOutcome> ViewRefinement::finishSave(const Camera& camera, int width, int height) {
    if (!save_ || !save_->done.load() || uploader_.busy()) return std::nullopt;
    save_->thread.join();
    SaveOutcome outcome{save_->path, save_->error, session_->cache().totalVertices(), std::nullopt};
    save_.reset();
    outcome.failure = newFailure();  // a failure before the stop is still reported
    stopWorker();
    if (error_.empty()) start(camera, width, height);
    return outcome;
}

bool ViewRefinement::beginChange(Scene& scene, const SceneChange& change) {
    if (save_ || change_ || !started_) return false;
    change_ = std::make_unique<ChangeJob>();
    change_->outcome.what = change.describe();
    ChangeJob* job = change_.get();
    ProgressiveSession* refining = session_.get();
    const bool copy = realtime_ != nullptr;
    job->thread = std::thread([job, refining, &scene, change, copy] {
        const auto start = Clock::now();
        try {
            job->outcome.report = refining->applyChange(scene, change);  // stops the worker first
            if (copy) job->changed = std::make_shared<const Scene>(scene);
        } catch (const std::exception& e) {
            job->outcome.error = e.what();
        }
        job->outcome.seconds = std::chrono::duration<double>(Clock::now() - start).count();
        job->done.store(true);
    });
    return true;
}

std::optional<ViewRefinement::ChangeOutcome> ViewRefinement::finishChange(const Camera& camera, int width, int height) {
    if (!change_ || !change_->done.load() || uploader_.busy()) return std::nullopt;
    change_->thread.join();
    ChangeOutcome outcome = std::move(change_->outcome);
    // A new scene for the stand-in: the next snapshots are of it.
    if (outcome.error.empty() && change_->changed) {
        ++sceneVersion_;
        sceneCopy_ = std::move(change_->changed);
    }
    change_.reset();
    stopWorker();
    if (error_.empty()) start(camera, width, height);
    return outcome;
}

void ViewRefinement::stop() {
    if (save_ && save_->thread.joinable()) save_->thread.join();
    save_.reset();
    if (change_ && change_->thread.joinable()) change_->thread.join();
    change_.reset();
    reader_ = CacheWorker::Reader();
    uploading_ = nullptr;
    if (started_) session_->stop();
}

std::optional<size_t> ViewRefinement::saveAtExit() {
    if (settings_.cachePath.empty() || !started_ || !error_.empty()) return std::nullopt;
    session_->save(settings_.cachePath);
    return session_->cache().totalVertices();
}

}  // namespace ml
