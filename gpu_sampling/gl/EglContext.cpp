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
    // Tries each candidate display in turn (GPU devices first, then Mesa's
    // surfaceless platform, then the default display) until one gives a
    // current 4.5 core context: which one works depends on the driver and on
    // whether an X display is around. Throws with every reason when none does.
    explicit EglContext(bool requireHardware) {
        std::string reasons;
        for (const Candidate& c : candidates(requireHardware)) {
            try {
                create(c.display, requireHardware);
                return;
            } catch (const std::exception& e) {
                release();
                reasons += std::string(reasons.empty() ? "" : "; ") + c.name + ": " + e.what();
            }
        }
        throw std::runtime_error("no EGL display gives an OpenGL 4.5 core context (" +
                                 (reasons.empty() ? std::string("no display") : reasons) + ")");
    }
    ~EglContext() override { release(); }

    void makeCurrent() override {
        if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
            throw std::runtime_error("eglMakeCurrent (surfaceless) failed");
    }
    GlBackend backend() const override { return GlBackend::Egl; }

private:
    struct Candidate {
        std::string name;
        EGLDisplay display;
    };

    static std::vector<Candidate> candidates(bool requireHardware) {
        std::vector<Candidate> out;
        auto getPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
            eglGetProcAddress("eglGetPlatformDisplayEXT"));
        if (getPlatformDisplay && hasClientExtension("EGL_EXT_platform_device")) {
            auto queryDevices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
            EGLDeviceEXT devices[16];
            EGLint n = 0;
            if (queryDevices && queryDevices(16, devices, &n))
                for (EGLint i = 0; i < n; ++i) {
                    EGLDisplay d = getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
                    if (d != EGL_NO_DISPLAY) out.push_back({"device " + std::to_string(i), d});
                }
        }
        if (requireHardware) return out;
        if (getPlatformDisplay && hasClientExtension("EGL_MESA_platform_surfaceless")) {
            EGLDisplay d = getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
            if (d != EGL_NO_DISPLAY) out.push_back({"surfaceless", d});
        }
        EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
        if (d != EGL_NO_DISPLAY) out.push_back({"default display", d});
        return out;
    }

    void create(EGLDisplay display, bool requireHardware) {
        display_ = display;
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
            throw std::runtime_error("cannot create an OpenGL 4.5 core context");
        makeCurrent();
        gl_.load([](const char* name) { return reinterpret_cast<void*>(eglGetProcAddress(name)); });
        if (requireHardware && gl_.renderer.find("llvmpipe") != std::string::npos)
            throw std::runtime_error("a software renderer (" + gl_.renderer + ")");
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

    EGLDisplay display_ = EGL_NO_DISPLAY;
    EGLContext context_ = EGL_NO_CONTEXT;
    bool initialized_ = false;
};

}  // namespace

std::unique_ptr<GlContext> createEglContext(bool requireHardware) {
    return std::make_unique<EglContext>(requireHardware);
}

}  // namespace ml
