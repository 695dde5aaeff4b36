// The window's keyboard and mouse between frames: GLFW callbacks count
// events and collect key presses and scrolling (installed before ImGui's,
// which chain to them), and each frame turns the held keys and the mouse
// drag into a walking step. The frame loop asks whether anything happened
// since the last frame drawn, so idle frames can be skipped.
#pragma once

#include "WalkCamera.h"

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

struct GLFWwindow;

namespace ml {

class GlfwWindow;

class WindowInput {
public:
    // Installs the callbacks on the window (which must outlive this).
    explicit WindowInput(GlfwWindow& window);
    ~WindowInput();  // removes them
    WindowInput(const WindowInput&) = delete;
    WindowInput& operator=(const WindowInput&) = delete;

    // What one frame reads. `keyboard`/`mouse`: the controls do not want them.
    struct Frame {
        std::vector<int> keysPressed;  // GLFW key codes pressed since the last frame
        double scroll = 0;             // wheel steps since the last frame
        WalkInput walk;                // held keys and the drag
        double radiansPerPixel = 0;    // of the window's height, for the drag
        // The framebuffer pixel under the mouse while it hovers the window.
        std::optional<std::pair<int, int>> cursorPixel;
    };
    Frame take(bool keyboard, bool mouse, double fovYDegrees, int fbWidth, int fbHeight);

    // Something happened since the frame marked drawn (events, a drag, a
    // held walking key while focused).
    bool active() const;
    void markDrawn() { eventsDrawn_ = events_; }

private:
    GlfwWindow& window_;
    uint64_t events_ = 0, eventsDrawn_ = ~uint64_t(0);
    double scroll_ = 0;
    std::vector<int> keysPressed_;
    bool dragging_ = false;
    double dragX_ = 0, dragY_ = 0;
};

}  // namespace ml
