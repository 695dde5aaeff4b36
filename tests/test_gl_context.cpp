// The OpenGL contexts the samplers run on: version and renderer, the integer
// render target with logic operations that the jittered sampler relies on
// (§4.2.2 of Fournier & Péroche: light drawn with an OR of the inverted
// bits, occluders ANDed in), checked Filament-style by rendering a 16×16
// image headless and reading every pixel back against values computed here.
#include "core/Error.h"
#include "gpu_sampling/gl/GlContext.h"
#include "viewer/window/GlfwWindow.h"
#include "gpu_sampling/gl/GlObjects.h"

#include "GlTestContext.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <thread>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

using namespace ml;

namespace {

// One OSMesa context for the whole binary: creating one costs tens of
// milliseconds, and a context belongs to the thread that made it (gtest runs
// every test on the main thread).
bool atLeast45(const GlApi& gl) { return gl.majorVersion > 4 || (gl.majorVersion == 4 && gl.minorVersion >= 5); }

constexpr int kSize = 16;

// The value every pixel is cleared to, and the two values a pass writes, as
// functions of the pixel so that a misplaced or swapped pixel shows. The
// shader computes the same expressions from gl_FragCoord.
uint32_t clearValue() { return 0x0f0f00f0u; }
uint32_t firstPassSource(uint32_t x, uint32_t y) { return 0x12340000u ^ (x | (y << 4)) ^ (x * y << 8); }
uint32_t secondPassSource(uint32_t x, uint32_t y) { return 0xffff00ffu ^ (x << 8) ^ (y << 12) ^ (x << 20); }

const char* kVertex = R"(
uniform vec4 uRect;  // x0, y0, x1, y1 in NDC
void main() {
    // Two triangles from gl_VertexID alone: no vertex buffer needed.
    const ivec2 corner[6] = ivec2[6](ivec2(0, 0), ivec2(1, 0), ivec2(1, 1), ivec2(0, 0), ivec2(1, 1), ivec2(0, 1));
    ivec2 c = corner[gl_VertexID];
    gl_Position = vec4(c.x == 0 ? uRect.x : uRect.z, c.y == 0 ? uRect.y : uRect.w, 0.0, 1.0);
}
)";

const char* kFragment = R"(
uniform int uPass;
layout(location = 0) out uint outBits;
void main() {
    uint x = uint(gl_FragCoord.x), y = uint(gl_FragCoord.y);
    if (uPass == 0) outBits = 0x12340000u ^ (x | (y << 4)) ^ (x * y << 8);
    else outBits = 0xffff00ffu ^ (x << 8) ^ (y << 12) ^ (x << 20);
}
)";

// Clears a 16×16 R32UI target, draws the left half with GL_OR_INVERTED
// (dst = dst | ~src) and the bottom half with GL_AND (dst = dst & src), and
// reads the image back. The rectangles' edges fall on pixel boundaries
// (NDC 0 is between pixels 7 and 8), never on a pixel centre, so which pixels
// each pass covers is unambiguous.
std::vector<uint32_t> renderLogicOpImage(const GlApi& gl) {
    GlTexture target = makeTexture2D(gl, GL_R32UI, kSize, kSize);
    GLuint f = 0;
    gl.CreateFramebuffers(1, &f);
    GlFramebuffer fbo(gl, f);
    gl.NamedFramebufferTexture(f, GL_COLOR_ATTACHMENT0, target.id(), 0);
    const GLenum buffers[1] = {GL_COLOR_ATTACHMENT0};
    gl.NamedFramebufferDrawBuffers(f, 1, buffers);
    EXPECT_EQ(gl.CheckNamedFramebufferStatus(f, GL_FRAMEBUFFER), GLenum(GL_FRAMEBUFFER_COMPLETE));

    GlProgram program(gl, {{GL_VERTEX_SHADER, "logic_op.vert", glslSource({kVertex})},
                           {GL_FRAGMENT_SHADER, "logic_op.frag", glslSource({kFragment})}});
    GlVertexArray vao = makeVertexArray(gl);

    gl.BindFramebuffer(GL_FRAMEBUFFER, f);
    gl.Viewport(0, 0, kSize, kSize);
    gl.Disable(GL_DEPTH_TEST);
    gl.Disable(GL_CULL_FACE);
    gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    const GLuint clear[4] = {clearValue(), 0, 0, 0};
    gl.ClearBufferuiv(GL_COLOR, 0, clear);

    program.use();
    gl.BindVertexArray(vao.id());
    gl.Enable(GL_COLOR_LOGIC_OP);
    gl.LogicOp(GL_OR_INVERTED);
    gl.Uniform1i(program.uniform("uPass"), 0);
    gl.Uniform4f(program.uniform("uRect"), -1.0f, -1.0f, 0.0f, 1.0f);  // left half
    gl.DrawArrays(GL_TRIANGLES, 0, 6);
    gl.LogicOp(GL_AND);
    gl.Uniform1i(program.uniform("uPass"), 1);
    gl.Uniform4f(program.uniform("uRect"), -1.0f, -1.0f, 1.0f, 0.0f);  // bottom half
    gl.DrawArrays(GL_TRIANGLES, 0, 6);
    gl.Disable(GL_COLOR_LOGIC_OP);

    std::vector<uint32_t> pixels(kSize * kSize, 0xdeadbeefu);
    gl.NamedFramebufferReadBuffer(f, GL_COLOR_ATTACHMENT0);
    gl.PixelStorei(GL_PACK_ALIGNMENT, 4);
    gl.ReadPixels(0, 0, kSize, kSize, GL_RED_INTEGER, GL_UNSIGNED_INT, pixels.data());
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
    checkGl(gl, "logic-op test render");
    return pixels;
}

// Every pixel against the same operations done on the CPU.
void expectLogicOpImage(const GlApi& gl) {
    const std::vector<uint32_t> pixels = renderLogicOpImage(gl);
    int wrong = 0;
    for (uint32_t y = 0; y < kSize; ++y)
        for (uint32_t x = 0; x < kSize; ++x) {
            uint32_t expected = clearValue();
            if (x < kSize / 2) expected |= ~firstPassSource(x, y);
            if (y < kSize / 2) expected &= secondPassSource(x, y);
            const uint32_t got = pixels[y * kSize + x];
            if (got != expected && ++wrong <= 8)
                ADD_FAILURE() << "pixel (" << x << ", " << y << "): expected 0x" << std::hex << expected
                              << ", got 0x" << got;
        }
    EXPECT_EQ(wrong, 0) << "pixels differing from the CPU's logic operations";
}

TEST(GlContext, OsMesaIsCore45WithARenderer) {
    GlContext& context = test::glContext();
    const GlApi& gl = context.gl();
    EXPECT_EQ(context.backend(), GlBackend::OsMesa);
    EXPECT_TRUE(atLeast45(gl)) << "version " << gl.majorVersion << "." << gl.minorVersion;
    EXPECT_FALSE(gl.renderer.empty());
    // "osmesa: llvmpipe (...), OpenGL 4.5": the back end, the renderer, the version.
    const std::string d = context.describe();
    EXPECT_EQ(d.rfind("osmesa: ", 0), 0u) << d;
    EXPECT_NE(d.find(gl.renderer), std::string::npos) << d;
    EXPECT_NE(d.find("OpenGL 4."), std::string::npos) << d;
    // A core profile: GL_CONTEXT_PROFILE_MASK has the core bit.
    GLint profile = 0;
    gl.GetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    EXPECT_NE(profile & GL_CONTEXT_CORE_PROFILE_BIT, 0);
    checkGl(gl, "querying the context");
}

TEST(GlContext, IntegerTargetWithLogicOpsGivesExpectedBits) {
    expectLogicOpImage(test::glContext().gl());
}

TEST(GlContext, CheckGlReportsAnErrorByName) {
    const GlApi& gl = test::glContext().gl();
    gl.Enable(GL_TEXTURE_2D);  // not a core-profile capability: GL_INVALID_ENUM
    try {
        checkGl(gl, "enabling a fixed-function capability");
        FAIL() << "no error reported";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("GL_INVALID_ENUM"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("enabling a fixed-function capability"), std::string::npos) << e.what();
    }
    EXPECT_EQ(gl.GetError(), GLenum(GL_NO_ERROR));  // the error was consumed
}

TEST(GlContext, EglIsCore45WhereADisplayExists) {
    std::unique_ptr<GlContext> egl;
    try {
        egl = createHeadlessContext(GlBackend::Egl);
    } catch (const std::exception& e) {
        test::glContext();
        GTEST_SKIP() << "no EGL context on this machine: " << e.what();
    }
    EXPECT_EQ(egl->backend(), GlBackend::Egl);
    EXPECT_TRUE(atLeast45(egl->gl())) << egl->describe();
    EXPECT_FALSE(egl->gl().renderer.empty());
    // The same bits on this back end: the sampler must not depend on which one runs it.
    expectLogicOpImage(egl->gl());
    egl.reset();
    // The OSMesa context still works after another back end came and went.
    expectLogicOpImage(test::glContext().gl());
}

TEST(GlContext, BackendNamesParseAndUnknownOnesAreInputErrors) {
    for (GlBackend b : {GlBackend::Auto, GlBackend::OsMesa, GlBackend::Egl, GlBackend::Glfw})
        EXPECT_EQ(parseGlBackend(glBackendName(b)), b) << glBackendName(b);
    EXPECT_THROW(parseGlBackend("vulkan"), InputError);
    try {
        parseGlBackend("vulkan");
    } catch (const InputError& e) {
        // The message names the offending value and the accepted ones.
        EXPECT_NE(std::string(e.what()).find("'vulkan'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("osmesa"), std::string::npos) << e.what();
    }
    EXPECT_THROW(parseGlBackend("OSMesa"), InputError);  // names are lower case
    EXPECT_THROW(parseGlBackend(""), InputError);
}

TEST(GlContext, GlfwIsNotAHeadlessBackend) {
    EXPECT_THROW(createHeadlessContext(GlBackend::Glfw), std::runtime_error);
}

// A window on this thread and headless contexts on a worker beside it, the
// viewer's arrangement (one thread per context: glvnd will not make an EGL
// context current on a thread that holds a GLX one). Needs a display: ctest
// runs it under xvfb-run where that exists.
TEST(GlContext, WindowBesideHeadlessContextsOnAWorker) {
    if (!std::getenv("DISPLAY")) GTEST_SKIP() << "no DISPLAY (run under xvfb-run)";
    WindowOptions options;
    options.width = 32;
    options.height = 32;
    options.visible = false;
    auto window = std::make_unique<GlfwWindow>(options);
    EXPECT_EQ(window->backend(), GlBackend::Glfw);
    EXPECT_NE(window->handle(), nullptr);
    EXPECT_TRUE(atLeast45(window->gl()));
    std::string workerError;
    std::thread worker([&] {
        try {
            for (GlBackend b : {GlBackend::OsMesa, GlBackend::Egl}) {
                std::unique_ptr<GlContext> headless = createHeadlessContext(b);
                if (!atLeast45(headless->gl())) workerError += std::string(glBackendName(b)) + " is not 4.5; ";
            }
        } catch (const std::exception& e) {
            workerError = e.what();
        }
    });
    worker.join();
    EXPECT_EQ(workerError, "");
    window->makeCurrent();
    checkGl(window->gl(), "window context after the worker");
}

}  // namespace
