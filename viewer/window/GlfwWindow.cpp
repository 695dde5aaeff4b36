#define GLFW_INCLUDE_NONE
#include "GlfwWindow.h"

#include <GLFW/glfw3.h>

#include <stdexcept>
#include <string>

namespace ml {

namespace {

std::string glfwLastError() {
    const char* msg = nullptr;
    glfwGetError(&msg);
    return msg ? msg : "unknown GLFW error";
}

}  // namespace

GlfwWindow::GlfwWindow(const WindowOptions& o) {
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

GlfwWindow::~GlfwWindow() {
    glfwDestroyWindow(window_);
    glfwTerminate();
}

void GlfwWindow::makeCurrent() { glfwMakeContextCurrent(window_); }

}  // namespace ml
