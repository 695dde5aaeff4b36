// The viewer's side of refinement: the progressive session (cache, solver,
// worker) it drives, the camera it sends the worker, the snapshots it
// copies to the GPU a slice per frame, pausing, failures, and saving the
// cache on a helper thread while frames go on. The frame loop (ViewSession)
// asks it each frame what to show; it draws nothing itself.
#pragma once

#include "ViewSession.h"
#include "cache/ProgressiveSession.h"
#include "cache/RealtimeIndirect.h"
#include "viewer/compositor/GpuCacheMeshes.h"

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>

namespace ml {

class ViewRefinement {
public:
    // What the frame shows of a snapshot, kept after the snapshot itself is gone.
    struct Shown {
        bool any = false;
        uint64_t generation = 0, version = 0;
        double seconds = 0;
        size_t vertices = 0, triangles = 0, indirectMeshes = 0;
        uint64_t samples = 0, rounds = 0, cameraSerial = 0;
        double estimatedError = 1;
        bool converged = false;
        // What its indirect light is (RealtimeIndirect: the cache, the
        // real-time stand-in, or a blend) and the stand-in's share of it.
        std::string indirectSource = "cache";
        double realtimeShare = 0;
        std::string standInChoice;  // IndirectShown::choice
    };
    // How a save ended, once it has (finishSave).
    struct SaveOutcome {
        std::string path;
        std::string error;  // empty: saved
        size_t vertices = 0;
        // The worker's failure before the save stopped it, seen here first
        // (as newFailure() would have said it): the caller reports it.
        std::optional<std::string> failure;
    };

    // Niceness of the cache's sampling threads and of the real-time
    // stand-in's thread (RealtimeIndirect): the frames and the estimate the
    // next frames show (0) come first, then refinement; a frame never waits
    // for a round. The estimate at 5 was no better (viewer/README.md,
    // "Measured: bench dynamic"). A failure to set it (not permitted) leaves it as it was.
    static constexpr int kWorkerNice = 10;
    static constexpr int kRealtimeNice = 0;
    // The least time between two snapshots of the viewer's worker (view
    // --publish; render keeps 0.25 s). Each frame shows the newest, so after
    // a light or an object moves the image follows the cache's catch-up
    // gather by gather. Whatever this is, snapshots take at most a tenth of
    // the worker's time (CacheWorker's kPublishShare): a large cache's come
    // less often. bench dynamic (the Cornell box, the short block moved):
    // back within 2% of the converged image 0.3 s after the motion at
    // 0.25 s, 0.2 s at 0.1 s (a cold start: 0.5-0.65 s).
    static constexpr double kPublishSeconds = 0.1;
    // From its next start(), `session`'s sampling threads run at kWorkerNice.
    static void lowerWorkerPriority(ProgressiveSession& session);

    // The session for these settings, resuming settings.cachePath if it
    // exists (a cache that cannot be resumed throws InputError). Made before
    // the window opens, so that such an error comes first.
    static std::unique_ptr<ProgressiveSession> makeSession(const Scene& scene, const ViewSettings& settings);
    // Drives `session` of `scene` (the session's own scene, which changes
    // with beginChange); the worker starts with start(). `uploader` copies
    // snapshots to the GPU, with the indirect light settings.realtime says
    // (RealtimeIndirect, on a thread of its own).
    ViewRefinement(std::unique_ptr<ProgressiveSession> session, const Scene& scene, const ViewSettings& settings,
                   CacheMeshUploader& uploader);
    ~ViewRefinement();  // finishes a save in progress, then stops the worker

    const ProgressiveSession& session() const { return *session_; }
    bool started() const { return started_; }
    // The worker, serving this camera first.
    void start(const Camera& camera, int width, int height);
    // The camera the user sees is the one refined first: sent when it
    // changed, at most every `kViewInterval`, never during a save.
    void follow(const Camera& camera, int width, int height);
    // The worker's failure, the first time it is seen; then error() keeps it.
    std::optional<std::string> newFailure();
    const std::string& error() const { return error_; }
    // Takes the latest snapshot and copies it to the GPU, a slice per frame
    // (all of the first). True when a newer snapshot became the one shown.
    bool pump(double& uploadMs);
    const Shown& shown() const { return shown_; }
    // Called with each snapshot as it becomes the one shown, with the
    // indirect meshes shown with it (the compositor's specular pass reads
    // the cache on the CPU).
    using ShownCallback = std::function<void(const CacheSnapshot&, const std::vector<IrradianceMeshCopy>& indirect)>;
    void onShown(ShownCallback f) { onShown_ = std::move(f); }

    // What the image shows of indirect light (--realtime, --indirect-display):
    // the next snapshot or estimate shown follows it. Ignored with direct
    // light only.
    void setRealtime(const RealtimeChoice& choice);
    const RealtimeChoice& realtime() const { return realtimeChoice_; }

    void setPaused(bool paused);
    bool paused() const { return paused_; }
    // A script's wait-done: the snapshot shown is the worker's last for the
    // view sent (or the worker has ended, failed or is paused).
    bool done() const;
    // Worker ended (out of samples, failed or stopped) and no save is running.
    bool finished() const { return started_ && session_->finished() && !save_ && !change_; }

    // Stops the worker and writes the cache on a helper thread; false when
    // a save runs already or no worker was started.
    bool beginSave(const std::string& path);
    bool saving() const { return save_ != nullptr; }
    // Once the file is written and no snapshot of the old worker is being
    // copied: ends the save and, unless the old worker failed, starts a new
    // one on the same cache (a resumed cache refines exactly as if never
    // saved) at this camera.
    std::optional<SaveOutcome> finishSave(const Camera& camera, int width, int height);

    // --- Lights and objects that move (issue 17) ---
    // How a change ended, once it has (finishChange).
    struct ChangeOutcome {
        std::string what;    // SceneChange::describe()
        std::string error;   // empty: the cache follows the change
        InvalidationReport report;
        double seconds = 0;  // the helper's time: stopping the worker and the cache's invalidation
    };
    // Stops the worker and applies `change` to `scene` (the session's own
    // scene, which nothing else may read until finishChange) with the cache
    // following it (ProgressiveSession::applyChange), on a helper thread:
    // frames go on showing the last snapshot meanwhile. False while a save
    // or another change runs, or before the worker started.
    bool beginChange(Scene& scene, const SceneChange& change);
    bool changing() const { return change_ != nullptr; }
    // Once the change is applied and no snapshot of the old worker is being
    // copied: starts a new worker at this camera on the changed cache
    // (also after an InputError, on the cache as it was).
    std::optional<ChangeOutcome> finishChange(const Camera& camera, int width, int height);

    // At the end of the frame loop: joins a save and stops the worker (then
    // look at newFailure()).
    void stop();
    // Saves settings.cachePath, if given, when a worker ran and nothing
    // failed; returns the vertices saved (none: nothing saved).
    std::optional<size_t> saveAtExit();

private:
    // A cache being saved: the worker is stopped and the file written on
    // this helper thread, so frames go on meanwhile.
    struct SaveJob {
        std::string path;
        std::thread thread;
        std::atomic<bool> done{false};
        std::string error;
    };
    // A change being applied on this helper thread (beginChange).
    struct ChangeJob {
        ChangeOutcome outcome;
        std::shared_ptr<const Scene> changed;  // the scene after it, for the stand-in (copied here, not by a frame)
        std::thread thread;
        std::atomic<bool> done{false};
    };
    double now() const;
    void stopWorker();
    void noteSent(const Camera& camera, int width, int height);

    const ViewSettings& settings_;
    CacheMeshUploader& uploader_;
    std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
    // The cache, its indirect solver and the worker refining them; a
    // worker made again after a save continues the same cache and solver.
    std::unique_ptr<ProgressiveSession> session_;
    bool started_ = false;
    mutable CacheWorker::Reader reader_;
    const CacheSnapshot* uploading_ = nullptr;  // pinned by reader_ while it is copied
    uint64_t generation_ = 0;                   // workers started so far
    Shown shown_;
    ShownCallback onShown_;

    // The real-time stand-in for indirect light (null with direct light
    // only), the scene version it is told (one more after each change
    // applied) and that scene's copy, which it keeps while it estimates.
    RealtimeChoice realtimeChoice_;
    std::unique_ptr<RealtimeIndirect> realtime_;
    uint64_t sceneVersion_ = 1;
    std::shared_ptr<const Scene> sceneCopy_;
    uint64_t offered_ = 0;            // the snapshot version offered last (this worker's)
    uint64_t estimateConsidered_ = 0;  // the newest estimate when the last copy to the GPU began
    IndirectShown uploadingIndirect_;  // the indirect meshes being copied, kept until swapped in
    bool paused_ = false;
    std::string error_;
    std::unique_ptr<SaveJob> save_;
    std::unique_ptr<ChangeJob> change_;

    // The view the worker serves.
    Camera sentCamera_;
    int sentWidth_ = 0, sentHeight_ = 0;
    uint64_t sentSerial_ = 0;
    double sentAt_ = -1e30;
    bool viewDirty_ = false;
};

}  // namespace ml
