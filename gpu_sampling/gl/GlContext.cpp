#include "GlContext.h"

#include "core/Error.h"

#include <stdexcept>

namespace ml {

GlBackend parseGlBackend(const std::string& name) {
    if (name == "auto") return GlBackend::Auto;
    if (name == "osmesa") return GlBackend::OsMesa;
    if (name == "egl") return GlBackend::Egl;
    if (name == "glfw") return GlBackend::Glfw;
    throw InputError(concat("unknown OpenGL back end '", name, "' (use auto, osmesa, egl or glfw)"));
}

const char* glBackendName(GlBackend b) {
    switch (b) {
        case GlBackend::Auto: return "auto";
        case GlBackend::OsMesa: return "osmesa";
        case GlBackend::Egl: return "egl";
        case GlBackend::Glfw: return "glfw";
    }
    return "?";
}

namespace {
// The context this thread last made current through use() or
// createHeadlessContext(); null when unknown.
thread_local GlContext* tCurrent = nullptr;
}  // namespace

GlContext::~GlContext() {
    if (tCurrent == this) tCurrent = nullptr;
}

void GlContext::use() {
    if (tCurrent == this) return;
    makeCurrent();
    tCurrent = this;
}

std::string GlContext::describe() const {
    return concat(glBackendName(backend()), ": ", gl_.renderer, ", OpenGL ", gl_.majorVersion, ".",
                  gl_.minorVersion);
}

// Declared here rather than in a header: only createHeadlessContext picks among them.
namespace {
std::unique_ptr<GlContext> createHeadless(GlBackend backend);
}
std::unique_ptr<GlContext> createOsMesaContext();
std::unique_ptr<GlContext> createEglContext(bool requireHardware);

std::unique_ptr<GlContext> createHeadlessContext(GlBackend backend) {
    std::unique_ptr<GlContext> context = createHeadless(backend);
    tCurrent = context.get();  // made current by its constructor
    return context;
}

namespace {
std::unique_ptr<GlContext> createHeadless(GlBackend backend) {
    switch (backend) {
        case GlBackend::OsMesa: return createOsMesaContext();
        case GlBackend::Egl: return createEglContext(false);
        case GlBackend::Glfw: throw std::runtime_error("a GLFW context is a window: open a GlfwWindow (viewer/window)");
        case GlBackend::Auto:
            try {
                return createEglContext(true);
            } catch (const std::exception&) {
                return createOsMesaContext();  // no GPU: the software rasteriser
            }
    }
    throw std::logic_error("unhandled GL back end");
}
}  // namespace

}  // namespace ml
