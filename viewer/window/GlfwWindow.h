// The viewer's window: a GLFW window with an OpenGL 4.5 core context, a
// GlContext like the headless ones. GLFW stays in the window code.
#pragma once

#include "gpu_sampling/gl/GlContext.h"

#include <memory>
#include <string>

struct GLFWwindow;

namespace ml {

struct WindowOptions {
    int width = 1280;     // pixels
    int height = 720;     // pixels
    std::string title = "Meshlight";
    bool visible = true;
};

class GlfwWindow final : public GlContext {
public:
    // Opens the window and makes its context current; std::runtime_error
    // with GLFW's reason when it cannot (no display, no 4.5 core context).
    explicit GlfwWindow(const WindowOptions& options);
    ~GlfwWindow() override;

    void makeCurrent() override;
    GlBackend backend() const override { return GlBackend::Glfw; }
    GLFWwindow* handle() const { return window_; }

private:
    GLFWwindow* window_ = nullptr;
};

}  // namespace ml
