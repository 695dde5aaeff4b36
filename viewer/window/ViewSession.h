// The progressive walkthrough viewer: a window (GLFW, OpenGL 4.5 core) in
// which people walk through a scene while the cache refines on the worker
// thread, with the controls of Ui.h and, optionally, a script (ViewScript.h).
//
// Threads. The worker owns the cache and samples it with a headless GL
// context of its own; this thread owns the window's context and only ever
// acquires the latest snapshot (no lock) and copies it to the GPU in slices
// of bounded time (CacheMeshUploader). So a frame costs the same whatever
// the worker does: compositing the meshes shown, a few full-screen passes
// and the controls. The camera is handed to the worker (setView, when it
// changed, at most every 0.1 s), so what it sees is refined first and no
// finer than its pixels.
//
// Ending. Closing the window, `quit` in a script or Ctrl-C (SIGINT or
// SIGTERM sets a flag the frame loop checks; another one a quarter second
// or more later ends the process at once: core/io/InterruptGuard.h)
// stop the worker, which finishes its round, and join it. A worker that
// fails leaves its message in the window and on stderr; the window goes on
// showing the last snapshot (a script ends with exit status 1).
#pragma once

#include "DisplayState.h"
#include "ViewScript.h"
#include "cache/CacheWorker.h"
#include "cache/IrradianceCache.h"
#include "core/Camera.h"
#include "core/image/Illuminance.h"
#include "core/image/Photometry.h"
#include "gpu_sampling/SamplerFactory.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ml {

struct ViewSettings {
    int width = 1280;       // window, pixels
    int height = 720;
    int supersample = 1;    // sub-pixels per pixel side while interactive (1..4)
    Camera camera;          // the start camera (R goes back to it)
    DirectChoice direct;    // the worker's sampler
    IndirectChoice indirect;  // decided (IndirectChoice::decide); enabled = false: direct light only
    // What the image shows of indirect light: the cache with a real-time
    // method standing in while it catches up, or a method live
    // (--realtime, --indirect-display; the panel changes it).
    RealtimeChoice realtime;
    CacheSettings cache;
    WorkerSettings worker;  // maxSamples: the --samples budget
    std::string cachePath;  // resumed from if it exists; saved at the end and by "save cache"
    LengthUnit unit = LengthUnit::Metre;
    Photometry photometry;  // lux, lumens: --photometry, --efficacy
    DisplayState display;
    std::optional<ViewScript> script;    // resolved against the scene
    double scriptStep = 0;  // > 0: script time advances this much per frame instead of with the clock
    double maxFps = 60;     // frames are not drawn faster (0: no limit, for the bench)
    // The compositor's specular pass (mirrors, glass, Phong highlights) where
    // the scene has one; false shows their diffuse Kd alone (bench view's
    // measure of what the pass costs).
    bool specular = true;
    std::string screenshotPath = "meshlight-view.png";  // the panel's default
    bool printProgress = true;  // a status line on stderr now and then
};

// One drawn frame, for the bench.
struct FrameRecord {
    double start = 0;       // seconds since the session started
    double seconds = 0;     // the whole frame, events to swap
    double composeMs = 0;   // compositing and display
    double uploadMs = 0;    // copying snapshot slices to the GPU
    uint64_t samples = 0;   // the shown snapshot's
    size_t triangles = 0;   // cache triangles of the snapshot shown
    size_t drawnTriangles = 0;  // of those, drawn (the rest out of view)
    bool snapshot = false;  // a snapshot was shown
    double specularMs = 0;  // tracing the specular pass (0: none, or the last one still held)
};

class ViewSession {
public:
    // Opens the window (needs a display) and makes the cache; the worker
    // starts with run(). `scene` must outlive the session.
    ViewSession(const Scene& scene, const ViewSettings& settings);
    ~ViewSession();
    ViewSession(const ViewSession&) = delete;
    ViewSession& operator=(const ViewSession&) = delete;

    // The frame loop, until the window closes, the script quits or SIGINT.
    // Returns the exit status: 0; 1 when refinement failed or a screenshot
    // could not be written in a script; 2 for a script that turned out
    // invalid while playing (an inherited camera up along the view).
    int run();

    // --- Measurements (bench) ---
    const std::vector<FrameRecord>& frames() const;
    // Seconds from the session's construction to the first frame on
    // screen, and to the first one showing a cache snapshot (−1: none yet).
    double firstFrameSeconds() const;
    double firstSnapshotFrameSeconds() const;
    // Per light change: seconds from the change to the end of the frame
    // that shows it (swapped and finished).
    const std::vector<double>& lightChangeLatencies() const;
    std::string glDescription() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ml
