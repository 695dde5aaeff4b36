// OSMesa back end: Mesa's software rasteriser (llvmpipe) inside this process.
#include "GlContext.h"

#include <GL/osmesa.h>

#include <cstdlib>
#include <stdexcept>
#include <vector>

namespace ml {

namespace {

class OsMesaContext final : public GlContext {
public:
    OsMesaContext() {
        // llvmpipe splits rendering into 64×64 tiles over worker threads. A
        // sampling image is a single tile, so the threads only add hand-offs:
        // rendering in the calling thread halves the cost of a direct-light
        // sample (270 -> 147 us on the bench, 2 cores). Large compositor
        // images lose their parallelism, a small price beside that. Read when
        // llvmpipe starts; a value the user set is kept.
        ::setenv("LP_NUM_THREADS", "0", /*overwrite=*/0);
        // 4.6 fails on Debian 12's Mesa; 4.5 core is the most it offers.
        const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0,
                               OSMESA_STENCIL_BITS, 0, OSMESA_ACCUM_BITS, 0,
                               OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                               OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
        ctx_ = OSMesaCreateContextAttribs(attribs, nullptr);
        if (!ctx_) throw std::runtime_error("OSMesa could not create an OpenGL 4.5 core context");
        makeCurrent();
        gl_.load([](const char* name) { return reinterpret_cast<void*>(OSMesaGetProcAddress(name)); });
    }
    ~OsMesaContext() override { OSMesaDestroyContext(ctx_); }

    void makeCurrent() override {
        // The default framebuffer is a 1×1 dummy: every pass renders to its own FBO.
        if (!OSMesaMakeCurrent(ctx_, dummy_.data(), GL_UNSIGNED_BYTE, 1, 1))
            throw std::runtime_error("OSMesaMakeCurrent failed");
    }
    GlBackend backend() const override { return GlBackend::OsMesa; }

private:
    OSMesaContext ctx_ = nullptr;
    std::vector<unsigned char> dummy_ = std::vector<unsigned char>(4, 0);
};

}  // namespace

std::unique_ptr<GlContext> createOsMesaContext() { return std::make_unique<OsMesaContext>(); }

}  // namespace ml
