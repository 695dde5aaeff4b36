#include "PropagationCompute.h"

#include "core/Error.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/gl/GlObjects.h"
#include "meshlight_gpu_shaders.h"

#include <chrono>

namespace ml {

namespace {

double since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

struct PropagationCompute::Gpu {
    GlProgram step;
    GlBuffer moving, next, transfer, blocking, absorbed;
};

PropagationCompute::PropagationCompute(GlContext& context, const PropagationVolume& volume)
    : context_(context), grid_(volume.grid()), gpu_(std::make_unique<Gpu>()) {
    const GlApi& gl = context_.gl();
    Gpu& g = *gpu_;
    g.step = GlProgram(gl, {{GL_COMPUTE_SHADER, "propagate_step.comp", glslSource({shaders::propagate_step_comp})}});
    const size_t cells = grid_.count();
    std::vector<float> transfer;
    for (const auto& matrix : PropagationTransfer::get().matrix)
        for (const auto& row : matrix)
            for (double m : row) transfer.push_back(float(m));
    std::vector<float> blocking(3 * cells, 0.0f);
    for (int a = 0; a < 3; ++a)
        for (int k = 0; k < grid_.dims[2]; ++k)
            for (int j = 0; j < grid_.dims[1]; ++j)
                for (int i = 0; i < grid_.dims[0]; ++i)
                    blocking[size_t(a) * cells + grid_.index(i, j, k)] =
                        volume.settings().occlusion ? float(volume.blocking(a, i, j, k)) : 0.0f;
    g.transfer = makeBuffer(gl, transfer.size() * sizeof(float), transfer.data());
    g.blocking = makeBuffer(gl, blocking.size() * sizeof(float), blocking.data());
    g.moving = makeBuffer(gl, 27 * cells * sizeof(float), nullptr, GL_DYNAMIC_COPY);
    g.next = makeBuffer(gl, 27 * cells * sizeof(float), nullptr, GL_DYNAMIC_COPY);
    g.absorbed = makeBuffer(gl, 18 * cells * sizeof(float), nullptr, GL_DYNAMIC_COPY);
    checkGl(gl, "creating the propagation compute pass");
}

PropagationCompute::~PropagationCompute() = default;

PropagationCompute::Result PropagationCompute::propagate(const std::vector<ShRgb>& injected, int steps) {
    ML_ASSERT(injected.size() == grid_.count(), "propagation compute: ", injected.size(), " cells injected, the grid has ",
              grid_.count());
    const GlApi& gl = context_.gl();
    Gpu& g = *gpu_;
    const size_t cells = grid_.count();
    Result r;
    auto t = std::chrono::steady_clock::now();
    std::vector<float> field(27 * cells);
    for (size_t c = 0; c < cells; ++c)
        for (size_t i = 0; i < 9; ++i)
            for (int ch = 0; ch < 3; ++ch) field[27 * c + 3 * i + size_t(ch)] = float(injected[c].c[i][ch]);
    gl.NamedBufferSubData(g.moving.id(), 0, GLsizeiptr(field.size() * sizeof(float)), field.data());
    const std::vector<float> zeros(18 * cells, 0.0f);
    gl.NamedBufferSubData(g.absorbed.id(), 0, GLsizeiptr(zeros.size() * sizeof(float)), zeros.data());
    gl.Finish();
    r.uploadSeconds = since(t);

    t = std::chrono::steady_clock::now();
    g.step.use();
    gl.Uniform3i(g.step.uniform("dims"), grid_.dims[0], grid_.dims[1], grid_.dims[2]);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, g.transfer.id());
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, g.blocking.id());
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, g.absorbed.id());
    GLuint from = g.moving.id(), to = g.next.id();
    for (int s = 0; s < steps; ++s) {
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, from);
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, to);
        gl.DispatchCompute(GLuint((grid_.dims[0] + 3) / 4), GLuint((grid_.dims[1] + 3) / 4),
                           GLuint((grid_.dims[2] + 3) / 4));
        gl.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        std::swap(from, to);
    }
    gl.Finish();
    r.propagateSeconds = since(t);

    t = std::chrono::steady_clock::now();
    std::vector<float> absorbed(18 * cells);
    gl.GetNamedBufferSubData(g.absorbed.id(), 0, GLsizeiptr(absorbed.size() * sizeof(float)), absorbed.data());
    for (size_t d = 0; d < 6; ++d) {
        r.absorbed[d].resize(cells);
        for (size_t c = 0; c < cells; ++c)
            r.absorbed[d][c] = Rgb(absorbed[3 * (d * cells + c)], absorbed[3 * (d * cells + c) + 1],
                                   absorbed[3 * (d * cells + c) + 2]);
    }
    r.readbackSeconds = since(t);
    checkGl(gl, "propagating on the GPU");
    return r;
}

}  // namespace ml
