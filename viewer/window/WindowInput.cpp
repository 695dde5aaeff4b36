#define GLFW_INCLUDE_NONE
#include "WindowInput.h"

#include "GlfwWindow.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <glm/glm.hpp>

namespace ml {

namespace {
WindowInput* inputOf(GLFWwindow* win) { return static_cast<WindowInput*>(glfwGetWindowUserPointer(win)); }
}  // namespace

WindowInput::WindowInput(GlfwWindow& window) : window_(window) {
    GLFWwindow* w = window.handle();
    glfwSetWindowUserPointer(w, this);
    // Installed before ImGui's, which chain to them. Lambdas without
    // captures: GLFW takes plain function pointers.
    struct Count {
        static void key(GLFWwindow* win, int key, int, int action, int) {
            WindowInput* self = inputOf(win);
            ++self->events_;
            if (action == GLFW_PRESS) self->keysPressed_.push_back(key);
        }
        static void scroll(GLFWwindow* win, double, double dy) {
            WindowInput* self = inputOf(win);
            ++self->events_;
            self->scroll_ += dy;
        }
        static void any(GLFWwindow* win) { ++inputOf(win)->events_; }
    };
    glfwSetKeyCallback(w, Count::key);
    glfwSetScrollCallback(w, Count::scroll);
    glfwSetCursorPosCallback(w, [](GLFWwindow* win, double, double) { Count::any(win); });
    glfwSetMouseButtonCallback(w, [](GLFWwindow* win, int, int, int) { Count::any(win); });
    glfwSetFramebufferSizeCallback(w, [](GLFWwindow* win, int, int) { Count::any(win); });
    glfwSetWindowRefreshCallback(w, [](GLFWwindow* win) { Count::any(win); });
}

WindowInput::~WindowInput() { glfwSetWindowUserPointer(window_.handle(), nullptr); }

WindowInput::Frame WindowInput::take(bool keyboard, bool mouse, double fovYDegrees, int fbWidth, int fbHeight) {
    GLFWwindow* w = window_.handle();
    Frame f;
    if (keyboard) f.keysPressed = keysPressed_;
    keysPressed_.clear();
    if (mouse) f.scroll = scroll_;
    scroll_ = 0;
    if (keyboard) {
        auto down = [&](int k) { return glfwGetKey(w, k) == GLFW_PRESS ? 1.0 : 0.0; };
        f.walk.forward = down(GLFW_KEY_W) + down(GLFW_KEY_UP) - down(GLFW_KEY_S) - down(GLFW_KEY_DOWN);
        f.walk.right = down(GLFW_KEY_D) + down(GLFW_KEY_RIGHT) - down(GLFW_KEY_A) - down(GLFW_KEY_LEFT);
        f.walk.up = down(GLFW_KEY_E) + down(GLFW_KEY_PAGE_UP) - down(GLFW_KEY_Q) - down(GLFW_KEY_PAGE_DOWN);
        if (down(GLFW_KEY_LEFT_SHIFT) || down(GLFW_KEY_RIGHT_SHIFT)) f.walk.speedFactor = 4;
        if (down(GLFW_KEY_LEFT_CONTROL) || down(GLFW_KEY_RIGHT_CONTROL)) f.walk.speedFactor = 0.25;
    }
    const bool pressed = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS ||
                         glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
    double x, y;
    glfwGetCursorPos(w, &x, &y);
    if (pressed && (dragging_ || mouse)) {
        if (dragging_) {
            f.walk.lookRight = x - dragX_;
            f.walk.lookDown = y - dragY_;
        }
        dragging_ = true;
        dragX_ = x, dragY_ = y;
    } else {
        dragging_ = false;
    }
    int winWidth, winHeight;
    glfwGetWindowSize(w, &winWidth, &winHeight);
    f.radiansPerPixel = glm::radians(fovYDegrees) / std::max(winHeight, 1);
    // Framebuffer pixels can differ from window units.
    if (mouse && x >= 0 && y >= 0 && x < winWidth && y < winHeight && glfwGetWindowAttrib(w, GLFW_HOVERED))
        f.cursorPixel = {int(x * fbWidth / std::max(winWidth, 1)), int(y * fbHeight / std::max(winHeight, 1))};
    return f;
}

bool WindowInput::active() const {
    if (events_ != eventsDrawn_ || dragging_) return true;
    GLFWwindow* w = window_.handle();
    if (!glfwGetWindowAttrib(w, GLFW_FOCUSED)) return false;
    for (int k : {GLFW_KEY_W, GLFW_KEY_A, GLFW_KEY_S, GLFW_KEY_D, GLFW_KEY_Q, GLFW_KEY_E, GLFW_KEY_UP, GLFW_KEY_DOWN,
                  GLFW_KEY_LEFT, GLFW_KEY_RIGHT, GLFW_KEY_PAGE_UP, GLFW_KEY_PAGE_DOWN})
        if (glfwGetKey(w, k) == GLFW_PRESS) return true;
    return false;
}

}  // namespace ml
