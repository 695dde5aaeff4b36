// The viewer's controls (Dear ImGui, Debian's libimgui-dev with its GLFW and
// OpenGL 3 back ends): display mode, exposure and tone mapping, each light,
// refinement, walking, screenshots and the cache; the lux legend; and a
// banner when refinement failed.
//
// ImGui's OpenGL back end loads its own GL entry points (through libGL's
// glXGetProcAddress, for the current GLX context): it draws in the window's
// context only, never in a worker's, and saves and restores the GL state it
// touches; the compositor sets everything it relies on at each frame.
#pragma once

#include "DisplayState.h"
#include "ViewLights.h"
#include "core/image/Illuminance.h"
#include "core/SceneChange.h"
#include "core/image/Photometry.h"
#include "gpu_sampling/SamplerFactory.h"

#include <optional>
#include <string>
#include <vector>

struct GLFWwindow;

namespace ml {

struct UiStats {
    double elapsed = 0;        // seconds since the viewer started
    bool snapshot = false;     // a snapshot is shown
    double workerSeconds = 0;  // the shown snapshot's age in worker time
    size_t vertices = 0, triangles = 0, indirectMeshes = 0;
    size_t drawnTriangles = 0;  // of `triangles`, in view in the last frame
    uint64_t samples = 0, rounds = 0;
    double estimatedError = 1;
    bool converged = false, finished = false, paused = false, saving = false;
    double uploadProgress = 1;  // < 1 while a newer snapshot is being copied to the GPU
    double fps = 0, frameMs = 0, composeMs = 0;
    // What the image's indirect light is (IndirectShown::source: "cache",
    // "volume (real-time)", a blend while catching up); empty: none.
    std::string indirectSource;
    double realtimeShare = 0;
    // With the stand-in "auto": the method chosen and why (IndirectShown::choice).
    std::string standInChoice;
};

// What a frame of controls reads and changes.
struct UiModel {
    DisplayState* display = nullptr;
    std::vector<LightControl>* lights = nullptr;
    std::vector<ViewLight> lightInfo;  // per scene light
    std::vector<LightGroup> groups;     // the panel lists the lights by group
    Rgb indirectWeight{1.0};
    // Where lights share a cache mesh (LightCoverage): one line saying where
    // changing a light is exact and where approximate; empty: every light
    // has its own mesh everywhere.
    std::string sharedLights;
    UiStats stats;
    Camera camera;
    double speed = 1;  // scene units per second
    LengthUnit unit = LengthUnit::Metre;
    Photometry photometry;  // lux and lumens
    int supersample = 1;
    RealtimeChoice realtime;  // what is shown of indirect light, and what stands in for it
    std::vector<std::pair<std::string, Rgb>> meshColours;  // wireframe legend
    std::optional<double> cursorLux;                      // under the mouse, lux mode
    std::string error;    // refinement failed: shown in red whatever the panel
    std::string message;  // the last save, for a few seconds
    // What the "Move" section moves: each light's place (a punctual light's
    // position, an area light's centroid) and the scene's named objects, in
    // the scene as drawn; `changing` while a move is being applied.
    std::vector<Vec3> lightPlaces;
    std::vector<std::string> objects;
    bool changing = false;
};

// What the user asked for in this frame.
struct UiRequests {
    bool resetCamera = false;
    bool meterExposure = false;
    bool meterLux = false;
    bool lightsChanged = false;
    std::optional<bool> pause;  // true: pause, false: resume
    std::optional<std::string> screenshot, saveCache;
    double speedFactor = 1;     // multiply the walking speed
    int supersample = 0;        // > 0: new supersampling
    std::optional<RealtimeChoice> realtime;  // another indirect display or stand-in
    std::optional<SceneChange> sceneChange;  // a light or an object moved from the panel
};

class Ui {
public:
    // Sets up ImGui on the window's current context; its GLFW callbacks
    // chain to the ones already installed.
    Ui(GLFWwindow* window, const std::string& screenshotPath, const std::string& cachePath);
    ~Ui();
    Ui(const Ui&) = delete;
    Ui& operator=(const Ui&) = delete;

    // Starts a frame and lays out every window; call before compositing, so
    // what the user changes shows in this very frame.
    UiRequests build(UiModel& model);
    // Draws the windows into the current framebuffer (after the image).
    void render();
    bool wantsMouse() const;
    bool wantsKeyboard() const;
    // The image path in the panel (F12 saves there too).
    std::string screenshotPath() const { return screenshotPath_; }

private:
    // The "Move" section: nudges the chosen light or object along an axis.
    void moveControls(const UiModel& m, UiRequests& r);

    char screenshotPath_[512];
    char cachePath_[512];
    int moveTarget_ = 0;       // lights first, then objects
    float moveStep_ = 0.25f;   // metres
};

}  // namespace ml
