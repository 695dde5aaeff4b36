// One abstraction for an OpenGL 4.5 core context with three back ends:
// OSMesa (headless, CPU: tests and CI), EGL (headless, GPU machines) and a
// GLFW window (the viewer's, in viewer/window/GlfwWindow.h: headless code
// never sees GLFW).
//
// A context is owned by one thread (Filament's driver-thread rule): create it,
// make it current and use it on that thread; other threads send it work.
#pragma once

#include "GlApi.h"

#include <memory>
#include <string>

namespace ml {

enum class GlBackend {
    Auto,    // EGL on a hardware GPU if one answers, otherwise OSMesa
    OsMesa,  // Mesa llvmpipe in this process, no display needed
    Egl,     // EGL device or surfaceless platform, no display needed
    Glfw,    // a window (needs a display; Xvfb works)
};

GlBackend parseGlBackend(const std::string& name);  // "auto", "osmesa", "egl", "glfw"
const char* glBackendName(GlBackend);

class GlContext {
public:
    virtual ~GlContext();
    GlContext(const GlContext&) = delete;
    GlContext& operator=(const GlContext&) = delete;

    // Makes this context current on the calling thread.
    virtual void makeCurrent() = 0;
    // The same, unless this thread's last context made current through
    // use() or createHeadlessContext() is this one: for samplers that share
    // a thread but not a context, switching only when they alternate.
    void use();
    virtual GlBackend backend() const = 0;

    const GlApi& gl() const { return gl_; }
    // "OSMesa: llvmpipe (LLVM 15.0.6, 256 bits), OpenGL 4.5"
    std::string describe() const;

protected:
    GlContext() = default;
    GlApi gl_;
};

// Creates a headless context (OSMesa or EGL; Auto picks) and makes it current.
// Throws std::runtime_error with the reason when none can be made.
std::unique_ptr<GlContext> createHeadlessContext(GlBackend backend = GlBackend::Auto);

}  // namespace ml
