// GLFW back end: a window with a 4.5 core context, for the viewer.
#define GLFW_INCLUDE_NONE
#include "GlContext.h"

#include <GLFW/glfw3.h>

#include <mutex>
#include <stdexcept>
#include <string>

namespace ml {

namespace {

std::string glfwLastError() {
    const char* msg = nullptr;
    glfwGetError(&msg);
    return msg ? msg : "unknown GLFW error";
}

class GlfwContext final : public GlContext {
public:
    explicit GlfwContext(const WindowOptions& o) {
        if (!glfwInit()) throw std::runtime_error("GLFW could not start: " + glfwLastError());
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
        glfwWindowHint(GLFW_VISIBLE, o.visible ? GLFW_TRUE : GLFW_FALSE);
        window_ = glfwCreateWindow(o.width, o.height, o.title.c_str(), nullptr, nullptr);
        if (!window_) {
            const std::string why = glfwLastError();
            glfwTerminate();
            throw std::runtime_error("GLFW could not open a 4.5 core window: " + why);
        }
        makeCurrent();
        gl_.load([](const char* name) { return reinterpret_cast<void*>(glfwGetProcAddress(name)); });
    }
    ~GlfwContext() override {
        glfwDestroyWindow(window_);
        glfwTerminate();
    }
    void makeCurrent() override { glfwMakeContextCurrent(window_); }
    GlBackend backend() const override { return GlBackend::Glfw; }
    GLFWwindow* window() const override { return window_; }

private:
    GLFWwindow* window_ = nullptr;
};

}  // namespace

std::unique_ptr<GlContext> createWindowContext(const WindowOptions& options) {
    return std::make_unique<GlfwContext>(options);
}

}  // namespace ml
