#include "ViewSession.h"

#include "FrameMeter.h"
#include "FrameStatistics.h"
#include "GlfwWindow.h"
#include "Screenshot.h"
#include "Ui.h"
#include "ViewLights.h"
#include "ViewRefinement.h"
#include "WalkCamera.h"
#include "WindowInput.h"
#include "WireframeColours.h"
#include "core/Error.h"
#include "core/image/ToneMap.h"
#include "core/io/InterruptGuard.h"
#include "viewer/compositor/Compositor.h"
#include "viewer/compositor/GpuCacheMeshes.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;

double secondsBetween(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// Frames drawn after the last activity, so ImGui settles (hover, fades).
constexpr int kSettleFrames = 3;

// The specular pass while the view changes: one ray per block of sub-pixels,
// the block's side doubled (up to 16) when a trace takes over twice this,
// halved (down to 2) under a third of it, so that frames do not wait for
// it; the full image follows on a thread of its own once the view is still.
constexpr double kSpecularFrameMs = 15;
constexpr int kSpecularMinBlock = 2, kSpecularMaxBlock = 16;

// What the user set LP_NUM_THREADS to, read before anything in this
// process can set it (OsMesaContext does).
const std::optional<std::string> kUserLlvmpipeThreads = [] {
    const char* v = std::getenv("LP_NUM_THREADS");
    return v ? std::optional<std::string>(v) : std::nullopt;
}();

// llvmpipe reads LP_NUM_THREADS when a screen starts (for GLX: when GLFW
// starts). The window's image is large and wants every core, but
// OsMesaContext sets 0 for the whole process (one sampling image is one
// tile): a window opened after a worker (the bench opens several) would
// render on one thread. So the window gets llvmpipe's default, one thread
// per core, unless the user chose, and the variable is put back after.
std::unique_ptr<GlfwWindow> openWindow(const WindowOptions& options) {
    const char* before = std::getenv("LP_NUM_THREADS");
    const std::optional<std::string> saved = before ? std::optional<std::string>(before) : std::nullopt;
    if (!kUserLlvmpipeThreads)
        ::setenv("LP_NUM_THREADS", std::to_string(std::max(1u, std::thread::hardware_concurrency())).c_str(), 1);
    std::unique_ptr<GlfwWindow> window;
    try {
        window = std::make_unique<GlfwWindow>(options);
    } catch (...) {
        saved ? ::setenv("LP_NUM_THREADS", saved->c_str(), 1) : ::unsetenv("LP_NUM_THREADS");
        throw;
    }
    saved ? ::setenv("LP_NUM_THREADS", saved->c_str(), 1) : ::unsetenv("LP_NUM_THREADS");
    return window;
}

}  // namespace

struct ViewSession::Impl : ScriptHost {

    // What is drawn, and the session's own copy, which a light or an object
    // moving changes on a helper thread (ViewRefinement::beginChange); it
    // becomes the one drawn once the change is applied.
    Scene scene;
    Scene refined;
    ViewSettings settings;
    Clock::time_point t0 = Clock::now();

    std::vector<LightControl> lightControls;
    std::vector<Rgb> lightPowers;  // W per channel, as the scene emits (every kind: ViewLights.h)
    std::vector<ViewLight> lightInfo;
    std::vector<LightGroup> groups;
    DisplayState state;

    std::unique_ptr<GlfwWindow> window;
    std::unique_ptr<WindowInput> input;  // destroyed before the window
    std::unique_ptr<Compositor> compositor;
    std::unique_ptr<CacheMeshUploader> uploader;
    // The cache, its solver and worker, the snapshots shown, saves.
    std::unique_ptr<ViewRefinement> refinement;
    std::unique_ptr<Ui> ui;
    WalkCamera walk;
    std::optional<ScriptPlayer> player;
    std::optional<Clock::time_point> scriptStart;
    uint64_t frameIndex = 0;

    std::vector<IrradianceMeshCopy> emptyMeshes;

    // Requests for the frame being made.
    bool quitRequested = false;
    FrameMeter meter;  // auto exposure and lux range
    bool meteredOnce = false;
    std::vector<std::string> screenshots;
    std::optional<Clock::time_point> lightChangedAt;
    std::string message;
    double messageUntil = 0;
    int exitCode = 0;

    // Between frames (the GLFW callbacks and the drag are WindowInput's).
    int settleFrames = kSettleFrames;
    Clock::time_point lastFrame = Clock::now();
    std::optional<std::pair<int, int>> cursorPixel;  // lux mode: the pixel under the mouse
    std::optional<double> cursorLux;                 // and its illuminance, read by the last frame
    size_t drawnTriangles = 0;  // by the last frame
    std::optional<Camera> lastCamera;  // the last frame's
    double specularMs = 0;             // this frame's specular trace (0: none)
    int specularBlock = 4;             // sub-pixels a side per ray of the reduced trace
    DisplayMode shownMode = DisplayMode::Final;  // the last frame's

    // Measurements.
    FrameStatistics stats;

    Impl(const Scene& s, const ViewSettings& vs)
        : scene(s), refined(s), settings(vs), state(vs.display),
          walk(vs.camera, std::max(s.bounds.diagonal(), 1e-30) / 8.0) {
        for (const Light& l : scene.lights) {
            lightControls.emplace_back();
            lightInfo.push_back(viewLight(l, scene, metresPerUnit(settings.unit), settings.photometry));
            lightPowers.push_back(lightInfo.back().powerW);
        }
        groups = lightGroups(scene.lights);
        if (settings.printProgress) printLights();
        // Before the window: a cache that cannot be resumed is refused first.
        std::unique_ptr<ProgressiveSession> session = ViewRefinement::makeSession(refined, settings);
        if (settings.script) player.emplace(*settings.script);

        WindowOptions wo;
        wo.width = settings.width;
        wo.height = settings.height;
        wo.title = "Meshlight - " + scene.name;
        window = openWindow(wo);
        GLFWwindow* w = window->handle();
        glfwSwapInterval(0);  // frames are paced by maxFps, not by the display
        input = std::make_unique<WindowInput>(*window);
        makeCompositor();
        uploader = std::make_unique<CacheMeshUploader>(window->gl(), scene.bounds.center());
        // Until the first snapshot, every light has an empty mesh: the
        // frames show the emitters and the controls, nothing lit yet.
        emptyMeshes.resize(scene.lights.size());
        uploader->start(emptyMeshes, {});
        uploader->step(1e9);
        refinement = std::make_unique<ViewRefinement>(std::move(session), refined, settings, *uploader);
        refinement->onShown([this](const CacheSnapshot& s, const std::vector<IrradianceMeshCopy>& indirect) {
            if (compositor->hasSpecularPass()) compositor->setSpecularCache(s.direct, indirect);
        });
        ui = std::make_unique<Ui>(w, settings.screenshotPath,
                                  settings.cachePath.empty() ? "meshlight-view.cache" : settings.cachePath);
    }

    ~Impl() override {
        refinement.reset();  // finishes a save, stops the worker
    }

    double now() const { return secondsBetween(t0, Clock::now()); }

    // --- The worker ---------------------------------------------------------------

    void checkWorker() { reportFailure(refinement->newFailure()); }

    // A worker's failure, the first time it is seen: on stderr (the panel
    // shows refinement->error()); a script ends with status 1.
    void reportFailure(const std::optional<std::string>& failure) {
        if (!failure) return;
        std::fprintf(stderr, "\nmeshlight: refinement failed: %s\n", failure->c_str());
        if (player) {
            exitCode = 1;
            quitRequested = true;
        }
    }

    void makeCompositor() { compositor = std::make_unique<Compositor>(*window, scene); }

    // Ends a change once the cache follows it (ViewRefinement::finishChange):
    // the changed scene is drawn from this frame on (the compositor made
    // again for its geometry), and the new worker refines what was forgotten
    // first. A change refused (an unknown object...) ends a script with
    // status 2, as an invalid script does.
    void finishChange(int width, int height) {
        const std::optional<ViewRefinement::ChangeOutcome> changed =
            refinement->finishChange(walk.camera(), width, height);
        if (!changed) return;
        if (!changed->error.empty()) {
            showMessage("could not apply " + changed->what + ": " + changed->error);
            std::fprintf(stderr, "meshlight: could not apply %s: %s\n", changed->what.c_str(), changed->error.c_str());
            if (player) exitCode = 2, quitRequested = true;
            return;
        }
        compositor.reset();  // its specular thread reads the scene drawn
        scene = refined;
        makeCompositor();
        showMessage(concat(changed->what, ": ", changed->report.describe()));
        if (settings.printProgress)
            std::printf("%s: %s (%.0f ms on a helper thread)\n", changed->what.c_str(), changed->report.describe().c_str(),
                        1e3 * changed->seconds);
    }

    // Ends a save once its file is written (ViewRefinement::finishSave).
    void finishSave(int width, int height) {
        const std::optional<ViewRefinement::SaveOutcome> saved = refinement->finishSave(walk.camera(), width, height);
        if (!saved) return;
        if (saved->error.empty()) {
            showMessage(concat("saved the cache to ", saved->path, " (", saved->vertices, " vertices)"));
            std::printf("saved the cache to %s\n", saved->path.c_str());
        } else {
            showMessage("could not save the cache: " + saved->error);
            std::fprintf(stderr, "meshlight: could not save the cache: %s\n", saved->error.c_str());
            if (player) exitCode = 1, quitRequested = true;
        }
        reportFailure(saved->failure);  // a failure before the stop is still reported
    }

    // --- ScriptHost -----------------------------------------------------------------

    Camera camera() const override { return walk.camera(); }
    void setCamera(const Camera& c) override { walk.set(c); }
    DisplayState& display() override { return state; }
    std::vector<LightControl>& lights() override { return lightControls; }
    void lightsChanged() override {
        if (!lightChangedAt) lightChangedAt = Clock::now();
        if (state.mode == DisplayMode::Illuminance && state.luxAuto) meter.requestLuxRange();
    }
    void meterExposure() override { meter.requestExposure(); }
    void meterLuxRange() override { meter.requestLuxRange(); }
    void setPaused(bool p) override { refinement->setPaused(p); }
    uint64_t shownSamples() const override { return refinement->shown().any ? refinement->shown().samples : 0; }
    double shownError() const override {
        return refinement->shown().any ? refinement->shown().estimatedError : 1.0;
    }
    bool refinementDone() const override { return refinement->done(); }
    void screenshot(const std::string& path) override { screenshots.push_back(path); }
    void saveCache(const std::string& path) override {
        if (refinement->beginSave(path)) showMessage("saving the cache to " + path + "...");
    }
    bool busySaving() const override { return refinement->saving(); }
    void quit() override { quitRequested = true; }
    bool changeScene(const SceneChange& change) override {
        if (!refinement->started() || refinement->saving() || refinement->changing()) return false;
        return refinement->beginChange(refined, change);
    }
    void setIndirectDisplay(const std::string& display) override {
        RealtimeChoice c = refinement->realtime();
        c.display = display;
        setRealtime(c);
    }
    void setRealtime(const RealtimeChoice& c) {
        refinement->setRealtime(c);
        showMessage(c.describe());
    }

    void showMessage(const std::string& m) {
        message = m;
        messageUntil = now() + 6;
    }

    // --- One frame ------------------------------------------------------------------

    // Keys and the mouse, unless the controls have them.
    void handleInput(double dt, int fbWidth, int fbHeight) {
        const WindowInput::Frame in =
            input->take(!ui->wantsKeyboard(), !ui->wantsMouse(), walk.camera().fovYDegrees, fbWidth, fbHeight);
        for (int key : in.keysPressed) {
            if (key == GLFW_KEY_R || key == GLFW_KEY_HOME) walk.reset();
            if (key == GLFW_KEY_P) setPaused(!refinement->paused());
            if (key == GLFW_KEY_TAB) state.showUi = !state.showUi;
            if (key == GLFW_KEY_F12) screenshots.push_back(ui->screenshotPath());
        }
        if (in.scroll != 0) walk.setSpeed(walk.speed() * std::pow(1.25, in.scroll));
        walk.update(in.walk, dt, in.radiansPerPixel);
        // Illuminance under the mouse, in lux mode.
        cursorLux.reset();
        cursorPixel = state.mode == DisplayMode::Illuminance ? in.cursorPixel : std::nullopt;
    }

    // Does this iteration need a frame? Idle frames are skipped, so the
    // worker has the processor while nothing on screen would change.
    bool wantsFrame(bool newSnapshot) {
        // A snapshot being copied needs no frame until it is whole (newSnapshot).
        const bool active = newSnapshot || input->active() || (player && !player->finished()) ||
                            !screenshots.empty() || meter.pending() || lightChangedAt || refinement->saving() ||
                            refinement->changing() || quitRequested || stats.firstFrame() < 0;
        if (active) settleFrames = kSettleFrames;
        return active || settleFrames > 0;
    }

    UiModel uiModel() {
        UiModel m;
        m.display = &state;
        m.lights = &lightControls;
        m.lightInfo = lightInfo;
        m.groups = groups;
        for (const Light& l : scene.lights) m.lightPlaces.push_back(l.punctual() ? l.emission.position : l.centroid);
        for (const Mesh& mesh : scene.meshes)
            if (!mesh.name.empty() && std::find(m.objects.begin(), m.objects.end(), mesh.name) == m.objects.end())
                m.objects.push_back(mesh.name);
        m.changing = refinement->changing();
        m.indirectWeight = indirectWeight(lightControls, lightPowers);
        UiStats& s = m.stats;
        const ViewRefinement::Shown& shown = refinement->shown();
        s.elapsed = now();
        s.snapshot = shown.any;
        s.workerSeconds = shown.seconds;
        s.vertices = shown.vertices;
        s.triangles = shown.triangles;
        s.drawnTriangles = drawnTriangles;
        s.indirectMeshes = shown.indirectMeshes;
        s.samples = shown.samples;
        s.rounds = shown.rounds;
        s.estimatedError = shown.estimatedError;
        s.converged = shown.converged;
        s.indirectSource = settings.indirect.active() ? shown.indirectSource : "";
        s.realtimeShare = shown.realtimeShare;
        s.standInChoice = settings.indirect.active() ? shown.standInChoice : "";
        s.finished = refinement->finished();
        s.paused = refinement->paused();
        s.saving = refinement->saving();
        s.uploadProgress = uploader->busy() ? uploader->progress() : 1.0;
        s.frameMs = stats.frameMsAverage();
        s.fps = stats.frameMsAverage() > 0 ? 1e3 / stats.frameMsAverage() : 0;
        s.composeMs = stats.composeMsAverage();
        m.camera = walk.camera();
        m.speed = walk.speed();
        m.unit = settings.unit;
        m.photometry = settings.photometry;
        m.supersample = settings.supersample;
        m.meshColours = meshLegend(scene, uploader->front());
        if (refinement->session().cache().hasSharedMesh())
            m.sharedLights = concat(
                "Direct light: ", refinement->session().coverage().describe(),
                ". Changing a light is exact where it has its own mesh; in the shared mesh the lights take their "
                "power-weighted mean, like indirect light, and 'light N' alone does not show what it gives there.");
        m.realtime = refinement->realtime();
        m.cursorLux = cursorLux;
        m.error = refinement->error();
        if (now() < messageUntil) m.message = message;
        return m;
    }

    void applyRequests(const UiRequests& r) {
        if (r.resetCamera) walk.reset();
        if (r.meterExposure) meter.requestExposure();
        if (r.meterLux) meter.requestLuxRange();
        if (r.lightsChanged) lightsChanged();
        if (r.pause) setPaused(*r.pause);
        if (r.screenshot) screenshots.push_back(*r.screenshot);
        if (r.saveCache) saveCache(*r.saveCache);
        if (r.speedFactor != 1) walk.setSpeed(walk.speed() * r.speedFactor);
        if (r.supersample > 0) settings.supersample = r.supersample;
        if (r.realtime) setRealtime(*r.realtime);
        if (r.sceneChange && !changeScene(*r.sceneChange)) showMessage("busy: the last move, a save or start-up");
    }

    CompositorSettings compositeSettings(int fbWidth, int fbHeight, CompositeQuantity q) const {
        CompositorSettings cs;
        cs.width = fbWidth;
        cs.height = fbHeight;
        cs.supersample = settings.supersample;
        cs.quantity = q;
        cs.photometry = settings.photometry;
        return cs;
    }

    void writeScreenshots(int fbWidth, int fbHeight) {
        for (const std::string& path : screenshots) {
            try {
                writeScreenshot(path, *window, *compositor, fbWidth, fbHeight);
                std::printf("screenshot: wrote %s (%dx%d, %s, %llu samples)\n", path.c_str(), fbWidth, fbHeight,
                            displayModeName(state.mode), static_cast<unsigned long long>(shownSamples()));
                showMessage("wrote " + path);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "meshlight: screenshot %s: %s\n", path.c_str(), e.what());
                showMessage(concat("screenshot failed: ", e.what()));
                if (player) exitCode = 1, quitRequested = true;
            }
        }
        screenshots.clear();
    }

    void printStatus(bool now = false) {
        const ViewRefinement::Shown& shown = refinement->shown();
        if (settings.printProgress && shown.any)
            stats.printStatus(this->now(), shown.vertices, shown.samples, shown.estimatedError,
                              settings.indirect.active() ? "indirect: " + shown.indirectSource + "; " + lightsStatus()
                                                         : lightsStatus(),
                              now);
    }

    // Each luminaire's flux as the scene emits it, once, on stdout: the
    // first few lights, then each group's total.
    void printLights() const {
        constexpr size_t kListed = 8;
        std::printf("lights (%s):", settings.photometry.describe().c_str());
        for (size_t l = 0; l < lightInfo.size() && l < kListed; ++l)
            std::printf("%s '%s' %s %.4g lm", l ? "," : "", lightInfo[l].name.c_str(), lightInfo[l].kind.c_str(),
                        lightInfo[l].lumens);
        if (lightInfo.size() > kListed) std::printf(", and %zu more", lightInfo.size() - kListed);
        if (lightInfo.empty()) std::printf(" none");
        std::printf("\n");
        bool any = false;
        for (const LightGroup& g : groups) {
            if (g.lights.size() < 2) continue;
            double lumens = 0;
            for (size_t l : g.lights) lumens += lightInfo[l].lumens;
            std::printf("%s group '%s': %zu lights, %.4g lm", any ? "," : "light groups:", g.name.c_str(),
                        g.lights.size(), lumens);
            any = true;
        }
        if (any) std::printf("\n");
    }

    // The flux the lights give as they are set now, for the status line:
    // "925.6 lm, 2 of 3 lights on" and, if any is changed, which.
    std::string lightsStatus() const {
        double lumens = 0;
        size_t on = 0;
        for (size_t l = 0; l < lightControls.size(); ++l) {
            lumens += settings.photometry.luminous(lightInfo[l].powerW * lightControls[l].weight());
            on += lightControls[l].on ? 1 : 0;
        }
        char buf[96];
        std::snprintf(buf, sizeof buf, "%.4g lm, %zu of %zu lights on", lumens, on, lightControls.size());
        return buf;
    }

    // Mirrors, glass and highlights (the compositor's specular pass, on the
    // CPU): traced again only when the view, the lights or the cache
    // changed, at once at reduced resolution (kSpecularFrameMs), so that the
    // change shows in this frame; once the camera is still, in full on a
    // thread of its own, shown by the frame after it lands (iterate).
    void traceSpecular(const LightWeights& weights, const CompositorSettings& cs) {
        const Camera& c = walk.camera();
        const bool moving = lastCamera && (c.position != lastCamera->position || c.target != lastCamera->target ||
                                           c.up != lastCamera->up || c.fovYDegrees != lastCamera->fovYDegrees);
        lastCamera = c;
        if (!settings.specular || !compositor->hasSpecularPass() || cs.quantity != CompositeQuantity::Radiance)
            return;
        const auto start = Clock::now();
        // A screenshot shows the full image, whatever the camera does.
        if (!screenshots.empty()) {
            if (compositor->traceSpecular(c, weights, cs, 1)) specularMs = 1e3 * secondsBetween(start, Clock::now());
            return;
        }
        if (compositor->traceSpecular(c, weights, cs, specularBlock)) {
            specularMs = 1e3 * secondsBetween(start, Clock::now());
            if (specularMs > 2 * kSpecularFrameMs) specularBlock = std::min(2 * specularBlock, kSpecularMaxBlock);
            if (specularMs < kSpecularFrameMs / 3) specularBlock = std::max(specularBlock / 2, kSpecularMinBlock);
        }
        if (!moving) compositor->requestSpecular(c, weights, cs);
    }

    // The image in the window's back buffer: composited, metered when asked,
    // tone-mapped, the wireframe over it, the lux under the mouse read back.
    // Returns its milliseconds.
    double drawImage(int fbWidth, int fbHeight) {
        const auto composeStart = Clock::now();
        const LightWeights weights = compositeWeights(state, lightControls, lightPowers);
        const CompositeQuantity quantity = compositeQuantity(state.mode);
        traceSpecular(weights, compositeSettings(fbWidth, fbHeight, quantity));
        compositor->compose(walk.camera(), uploader->front(), weights,
                            compositeSettings(fbWidth, fbHeight, quantity));
        drawnTriangles = compositor->drawnTriangles();
        meter.meter(*compositor, uploader->front(), walk.camera(), state, lightControls, lightPowers, weights,
                    compositeSettings(fbWidth, fbHeight, quantity));
        DisplaySettings ds;
        ds.exposure = meter.exposureScale() * std::exp2(state.exposureEV);
        ds.op = state.op;
        ds.luxMin = state.luxMin;
        ds.luxMax = state.luxMax;
        ds.contours = state.contours;
        compositor->display(0, ds);
        if (state.wireframe) {
            const std::vector<Rgb> colours = meshColours(uploader->front());
            if (!colours.empty()) compositor->drawWireframe(0, uploader->front(), colours);
        }
        if (cursorPixel) cursorLux = compositor->readIlluminance(cursorPixel->first, cursorPixel->second);
        return 1e3 * secondsBetween(composeStart, Clock::now());
    }

    // One pass of the loop: checks the worker and snapshots, then draws a
    // frame when something could have changed.
    void iterate() {
        checkWorker();
        int fbWidth = 0, fbHeight = 0;
        glfwGetFramebufferSize(window->handle(), &fbWidth, &fbHeight);
        if (fbWidth <= 0 || fbHeight <= 0) return;  // minimised
        finishSave(fbWidth, fbHeight);
        finishChange(fbWidth, fbHeight);
        double uploadMs = 0;
        const bool newSnapshot = refinement->pump(uploadMs);
        const bool specularLanded = compositor->collectSpecular();  // a full specular image to show
        if (!wantsFrame(newSnapshot || specularLanded)) return;
        const auto frameStart = Clock::now();
        const double dt = std::min(secondsBetween(lastFrame, frameStart), 0.25);
        lastFrame = frameStart;
        input->markDrawn();
        --settleFrames;

        // Input, the script and the controls, in that order, before the
        // image: what any of them changes shows in this very frame (the
        // controls, laid out last, show the script's changes too).
        handleInput(dt, fbWidth, fbHeight);
        if (player && !player->finished()) {
            if (!scriptStart) scriptStart = frameStart;
            const double t = settings.scriptStep > 0 ? double(frameIndex) * settings.scriptStep
                                                     : secondsBetween(*scriptStart, frameStart);
            player->advance(t, *this);
        }
        UiModel model = uiModel();
        applyRequests(ui->build(model));
        // Entering lux mode with an automatic range: take it from this frame.
        if (state.mode == DisplayMode::Illuminance && shownMode != DisplayMode::Illuminance && state.luxAuto)
            meter.requestLuxRange();
        shownMode = state.mode;
        // The worker starts once the first frame's camera is known (a
        // script's first keyframe), so its first view is the one shown.
        if (!refinement->started() && !refinement->saving() && !refinement->changing())
            refinement->start(walk.camera(), fbWidth, fbHeight);
        else
            refinement->follow(walk.camera(), fbWidth, fbHeight);
        if (newSnapshot && !meteredOnce) {
            meteredOnce = true;
            meter.requestExposure();  // the first light seen sets the exposure
            if (state.luxAuto) meter.requestLuxRange();
        }

        specularMs = 0;
        const double composeMs = drawImage(fbWidth, fbHeight);
        ui->render();
        writeScreenshots(fbWidth, fbHeight);
        glfwSwapBuffers(window->handle());
        if (lightChangedAt) {
            window->gl().Finish();  // the frame showing the change is on screen
            stats.addLightLatency(secondsBetween(*lightChangedAt, Clock::now()));
            lightChangedAt.reset();
        }
        const auto frameEnd = Clock::now();
        const double frameSeconds = secondsBetween(frameStart, frameEnd);
        stats.add({secondsBetween(t0, frameStart), frameSeconds, composeMs, uploadMs, refinement->shown().samples,
                   refinement->shown().triangles, drawnTriangles, refinement->shown().any, specularMs},
                  secondsBetween(t0, frameEnd));
        ++frameIndex;
        printStatus();
        if (settings.maxFps > 0) {
            const double rest = 1.0 / settings.maxFps - secondsBetween(frameStart, Clock::now());
            if (rest > 0) std::this_thread::sleep_for(std::chrono::duration<double>(rest));
        }
    }

    int run() {
        InterruptGuard guard;
        bool interrupted = false;
        for (;;) {
            // Wait for events only when the last pass drew nothing (idle).
            if (settleFrames > 0 || uploader->busy() || (player && !player->finished()))
                glfwPollEvents();
            else
                glfwWaitEventsTimeout(0.05);
            if (guard.interrupted()) {
                interrupted = true;
                break;
            }
            if (glfwWindowShouldClose(window->handle()) || quitRequested) break;
            try {
                iterate();
            } catch (const InputError& e) {
                // A script line that only fails while playing (a keyframe's
                // inherited up along its view).
                std::fprintf(stderr, "\nmeshlight: error: %s\n", e.what());
                exitCode = 2;
                break;
            }
        }
        printStatus(true);
        if (interrupted) std::fprintf(stderr, "\nmeshlight: interrupted; stopping the worker\n");
        stats.printSummary();
        refinement->stop();
        checkWorker();
        if (const std::optional<size_t> saved = refinement->saveAtExit())
            std::printf("cache: saved to %s (%zu vertices)\n", settings.cachePath.c_str(), *saved);
        if (player && !player->finished() && exitCode == 0 && !interrupted)
            std::printf("script: the window was closed at %s\n", player->where().c_str());
        return interrupted && exitCode == 0 ? 130 : exitCode;
    }
};

ViewSession::ViewSession(const Scene& scene, const ViewSettings& settings)
    : impl_(std::make_unique<Impl>(scene, settings)) {}
ViewSession::~ViewSession() = default;

int ViewSession::run() { return impl_->run(); }
const std::vector<FrameRecord>& ViewSession::frames() const { return impl_->stats.frames(); }
double ViewSession::firstFrameSeconds() const { return impl_->stats.firstFrame(); }
double ViewSession::firstSnapshotFrameSeconds() const { return impl_->stats.firstLitFrame(); }
const std::vector<double>& ViewSession::lightChangeLatencies() const { return impl_->stats.lightLatencies(); }
std::string ViewSession::glDescription() const { return impl_->window->describe(); }

}  // namespace ml
