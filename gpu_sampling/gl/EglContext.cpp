// EGL back end: headless OpenGL on a GPU (EGL device platform) or, failing
// that, Mesa's surfaceless platform.
#include "GlContext.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace ml {

namespace {

bool hasClientExtension(const char* name) {
    const char* ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    return ext && std::strstr(ext, name) != nullptr;
}

class EglContext final : public GlContext {
public:
    explicit EglContext(bool requireHardware) {
        try {
            create(requireHardware);
        } catch (...) {
            release();
            throw;
        }
    }
    ~EglContext() override { release(); }

    void makeCurrent() override {
        if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
            throw std::runtime_error("eglMakeCurrent (surfaceless) failed");
    }
    GlBackend backend() const override { return GlBackend::Egl; }

private:
    void create(bool requireHardware) {
        display_ = openDisplay(requireHardware);
        EGLint major = 0, minor = 0;
        if (!eglInitialize(display_, &major, &minor)) throw std::runtime_error("eglInitialize failed");
        initialized_ = true;
        if (!eglBindAPI(EGL_OPENGL_API)) throw std::runtime_error("EGL cannot bind the OpenGL API");
        const EGLint configAttribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                        EGL_OPENGL_BIT, EGL_NONE};
        EGLConfig config = nullptr;
        EGLint count = 0;
        // Surfaceless contexts need no config, but some drivers still want one.
        eglChooseConfig(display_, configAttribs, &config, 1, &count);
        const EGLint ctxAttribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                     EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                     EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
        context_ = eglCreateContext(display_, count > 0 ? config : EGL_NO_CONFIG_KHR,
                                    EGL_NO_CONTEXT, ctxAttribs);
        if (context_ == EGL_NO_CONTEXT)
            throw std::runtime_error("EGL could not create an OpenGL 4.5 core context");
        makeCurrent();
        gl_.load([](const char* name) { return reinterpret_cast<void*>(eglGetProcAddress(name)); });
        if (requireHardware && gl_.renderer.find("llvmpipe") != std::string::npos)
            throw std::runtime_error("EGL gave a software renderer (" + gl_.renderer + ")");
    }
    void release() {
        if (context_ != EGL_NO_CONTEXT) {
            eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
            eglDestroyContext(display_, context_);
            context_ = EGL_NO_CONTEXT;
        }
        if (initialized_) eglTerminate(display_);
        initialized_ = false;
    }

    static EGLDisplay openDisplay(bool requireHardware) {
        auto getPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
            eglGetProcAddress("eglGetPlatformDisplayEXT"));
        if (getPlatformDisplay && hasClientExtension("EGL_EXT_platform_device")) {
            auto queryDevices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(
                eglGetProcAddress("eglQueryDevicesEXT"));
            EGLDeviceEXT devices[16];
            EGLint n = 0;
            if (queryDevices && queryDevices(16, devices, &n) && n > 0) {
                for (EGLint i = 0; i < n; ++i) {
                    EGLDisplay d = getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
                    if (d != EGL_NO_DISPLAY) return d;
                }
            }
        }
        if (requireHardware) throw std::runtime_error("no EGL device found");
        if (getPlatformDisplay && hasClientExtension("EGL_MESA_platform_surfaceless")) {
            EGLDisplay d = getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
            if (d != EGL_NO_DISPLAY) return d;
        }
        EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
        if (d == EGL_NO_DISPLAY) throw std::runtime_error("no EGL display");
        return d;
    }

    EGLDisplay display_ = EGL_NO_DISPLAY;
    EGLContext context_ = EGL_NO_CONTEXT;
    bool initialized_ = false;
};

}  // namespace

std::unique_ptr<GlContext> createEglContext(bool requireHardware) {
    return std::make_unique<EglContext>(requireHardware);
}

}  // namespace ml
