#include "VoxelSlices.h"

#include "core/Error.h"
#include "detail/VoxelSlicesGpu.h"
#include "gpu_sampling/gl/GlContext.h"
#include "meshlight_gpu_shaders.h"

#include <chrono>

namespace ml {

namespace {

struct FillVertex {
    glm::vec3 position, radiance;
    glm::vec4 normalClosed;
};

}  // namespace

VoxelSlices::VoxelSlices(GlContext& context, const RadianceProxy& proxy, const std::vector<Rgb>& radiance,
                         int supersample)
    : grid_(proxy.grid()), gpu_(std::make_unique<Gpu>()) {
    const auto t0 = std::chrono::steady_clock::now();
    const GlApi& gl = context.gl();
    ML_ASSERT(radiance.size() == proxy.positions().size(), "one radiance per proxy position");
    ML_ASSERT(supersample >= 1 && supersample <= 8, "slice supersampling ", supersample, " not in 1..8");
    const int ss = supersample;

    // The proxy, relative to the grid's origin (float keeps its digits there).
    std::vector<FillVertex> vertices(proxy.positions().size());
    for (size_t v = 0; v < vertices.size(); ++v) {
        vertices[v].position = glm::vec3(proxy.positions()[v] - grid_.origin);
        vertices[v].radiance = glm::vec3(radiance[v]);
    }
    for (const ProxyTriangle& t : proxy.triangles())
        for (int k = 0; k < 3; ++k) vertices[t.corners[k]].normalClosed = glm::vec4(glm::vec3(t.normal), t.closed ? 1.f : 0.f);
    const GlBuffer vbo = makeBuffer(gl, std::max<size_t>(vertices.size(), 1) * sizeof(FillVertex), vertices.data());
    const GlVertexArray vao = makeVertexArray(gl);
    {
        GLuint offset = 0;
        const int counts[] = {3, 3, 4};
        for (GLuint i = 0; i < 3; ++i) {
            gl.EnableVertexArrayAttrib(vao.id(), i);
            gl.VertexArrayAttribFormat(vao.id(), i, counts[i], GL_FLOAT, GL_FALSE, offset);
            gl.VertexArrayAttribBinding(vao.id(), i, 0);
            offset += GLuint(counts[i] * sizeof(float));
        }
        gl.VertexArrayVertexBuffer(vao.id(), 0, vbo.id(), 0, sizeof(FillVertex));
    }
    const GlProgram fill(gl, {{GL_VERTEX_SHADER, "slice_fill.vert", glslSource({shaders::slice_fill_vert})},
                              {GL_FRAGMENT_SHADER, "slice_fill.frag", glslSource({shaders::slice_fill_frag})}});
    const GlProgram down(gl, {{GL_COMPUTE_SHADER, "slice_downsample.comp", glslSource({shaders::slice_downsample_comp})}});
    const GlQuery query = makeQuery(gl, GL_SAMPLES_PASSED);

    // Slices are a hair thicker than a voxel, so a surface lying exactly on
    // a slice plane is in both slices rather than in neither.
    const double eps = 1e-3 * grid_.voxel;
    int maxW = 1, maxH = 1;
    for (int a = 0; a < 3; ++a) {
        maxW = std::max(maxW, grid_.texels((a + 1) % 3));
        maxH = std::max(maxH, grid_.texels((a + 2) % 3));
    }
    arrayWidth_ = maxW;
    arrayHeight_ = maxH;
    const GlTexture color = makeTexture2D(gl, GL_RGBA32F, maxW * ss, maxH * ss);
    const GlTexture where = makeTexture2D(gl, GL_RG32F, maxW * ss, maxH * ss);
    const GlTexture depth = makeTexture2D(gl, GL_DEPTH_COMPONENT32F, maxW * ss, maxH * ss);
    const GlFramebuffer fb = makeFramebuffer(gl, {color.id(), where.id()}, depth.id(), "voxel slices");
    gl.BindFramebuffer(GL_FRAMEBUFFER, fb.id());
    // The state this pass assumes, whatever ran before on the context (the
    // direct sampler leaves zero-to-one depth and depth clamping on).
    gl.ClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
    gl.Disable(GL_DEPTH_CLAMP);
    gl.Disable(GL_STENCIL_TEST);
    gl.Disable(GL_SCISSOR_TEST);
    gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl.ColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl.Enable(GL_DEPTH_TEST);
    gl.DepthFunc(GL_LESS);
    gl.DepthMask(GL_TRUE);
    gl.Disable(GL_BLEND);
    gl.Disable(GL_CULL_FACE);

    std::array<GlTexture, 3> scratches, scratchDepths;
    std::array<std::vector<bool>, 3> keptByAxis;
    for (int a = 0; a < 3; ++a) {
        Axis& ax = axes_[size_t(a)];
        const int ua = (a + 1) % 3, va = (a + 2) % 3, n = grid_.dims[size_t(a)];
        ax.width = grid_.texels(ua);
        ax.height = grid_.texels(va);
        // Triangles by slice along this axis.
        std::vector<std::vector<uint32_t>> bins(static_cast<size_t>(n));
        for (const ProxyTriangle& t : proxy.triangles()) {
            double lo = kInf, hi = -kInf;
            for (int k = 0; k < 3; ++k) {
                const double c = proxy.positions()[t.corners[k]][a] - grid_.origin[a];
                lo = std::min(lo, c), hi = std::max(hi, c);
            }
            const int i0 = std::clamp(int(std::floor((lo - eps) / grid_.voxel)), 0, n - 1);
            const int i1 = std::clamp(int(std::floor((hi + eps) / grid_.voxel)), 0, n - 1);
            for (int i = i0; i <= i1; ++i)
                for (int k = 0; k < 3; ++k) bins[size_t(i)].push_back(t.corners[k]);
        }
        std::vector<uint32_t> indices;
        std::vector<size_t> first(size_t(n) + 1, 0);
        for (int i = 0; i < n; ++i) {
            first[size_t(i)] = indices.size();
            indices.insert(indices.end(), bins[size_t(i)].begin(), bins[size_t(i)].end());
        }
        first[size_t(n)] = indices.size();
        const GlBuffer ebo = makeBuffer(gl, std::max<size_t>(indices.size(), 1) * sizeof(uint32_t), indices.data());
        gl.VertexArrayElementBuffer(vao.id(), ebo.id());

        // Every face into a scratch array (upper faces at layer i, lower at
        // n + i), then the non-empty ones into the kept array.
        GLuint scratchId = 0;
        gl.CreateTextures(GL_TEXTURE_2D_ARRAY, 1, &scratchId);
        scratches[size_t(a)] = GlTexture(gl, scratchId);
        gl.TextureStorage3D(scratchId, 1, GL_RGBA32F, ax.width, ax.height, 2 * n);
        GLuint scratchDepthId = 0;
        gl.CreateTextures(GL_TEXTURE_2D_ARRAY, 1, &scratchDepthId);
        scratchDepths[size_t(a)] = GlTexture(gl, scratchDepthId);
        gl.TextureStorage3D(scratchDepthId, 1, GL_R32F, ax.width, ax.height, 2 * n);
        std::vector<bool> kept(size_t(2 * n), false);
        const float extentU = float(ax.width * grid_.voxel), extentV = float(ax.height * grid_.voxel);
        for (int side = 0; side < 2; ++side)  // 0: upper faces (viewer above), 1: lower
            for (int i = 0; i < n; ++i) {
                const size_t count = first[size_t(i) + 1] - first[size_t(i)];
                if (count == 0) continue;
                const float lo = float(i * grid_.voxel - eps), hi = float((i + 1) * grid_.voxel + eps);
                gl.Viewport(0, 0, ax.width * ss, ax.height * ss);
                const float clear[4] = {0, 0, 0, 0};
                gl.ClearBufferfv(GL_COLOR, 0, clear);
                gl.ClearBufferfv(GL_COLOR, 1, clear);
                const float one = 1.0f;
                gl.ClearBufferfv(GL_DEPTH, 0, &one);
                fill.use();
                gl.Uniform1i(fill.uniform("axis"), a);
                gl.Uniform2f(fill.uniform("extentUV"), extentU, extentV);
                gl.Uniform2f(fill.uniform("texelOrigin"), float(0.5 * grid_.voxel), float(0.5 * grid_.voxel));
                gl.Uniform1f(fill.uniform("nearPlane"), side == 0 ? hi : lo);
                gl.Uniform1f(fill.uniform("farPlane"), side == 0 ? lo : hi);
                gl.Uniform1f(fill.uniform("towardViewer"), side == 0 ? 1.0f : -1.0f);
                gl.BindVertexArray(vao.id());
                gl.BeginQuery(GL_SAMPLES_PASSED, query.id());
                gl.DrawElements(GL_TRIANGLES, GLsizei(count), GL_UNSIGNED_INT,
                                reinterpret_cast<const void*>(first[size_t(i)] * sizeof(uint32_t)));
                gl.EndQuery(GL_SAMPLES_PASSED);
                GLuint samples = 0;
                gl.GetQueryObjectuiv(query.id(), GL_QUERY_RESULT, &samples);
                if (samples == 0) continue;  // nothing in it: freed, never drawn
                kept[size_t(side * n + i)] = true;
                down.use();
                gl.BindTextureUnit(0, color.id());
                gl.BindTextureUnit(1, where.id());
                gl.BindImageTexture(0, scratchId, 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
                gl.BindImageTexture(1, scratchDepthId, 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
                gl.Uniform1i(down.uniform("ss"), ss);
                gl.Uniform1i(down.uniform("layer"), side * n + i);
                gl.Uniform2i(down.uniform("size"), ax.width, ax.height);
                gl.DispatchCompute(GLuint((ax.width + 7) / 8), GLuint((ax.height + 7) / 8), 1);
                gl.MemoryBarrier(GL_ALL_BARRIER_BITS);
            }
        ax.upperBefore.assign(size_t(n) + 1, 0);
        ax.lowerBefore.assign(size_t(n) + 1, 0);
        for (int i = 0; i < n; ++i) {
            ax.upperBefore[size_t(i) + 1] = ax.upperBefore[size_t(i)] + (kept[size_t(i)] ? 1 : 0);
            ax.lowerBefore[size_t(i) + 1] = ax.lowerBefore[size_t(i)] + (kept[size_t(n + i)] ? 1 : 0);
        }
        keptByAxis[size_t(a)] = kept;
    }
    // The kept faces, axis by axis, into one array.
    int total = 0;
    for (Axis& ax : axes_) {
        ax.firstLayer = total;
        total += ax.layers();
    }
    std::vector<glm::vec2> planes;
    if (total > 0) {
        auto makeArray = [&](GLenum format) {
            GLuint id = 0;
            gl.CreateTextures(GL_TEXTURE_2D_ARRAY, 1, &id);
            gl.TextureStorage3D(id, 1, format, arrayWidth_, arrayHeight_, total);
            gl.TextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
            gl.TextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
            gl.TextureParameteri(id, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
            gl.TextureParameteri(id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
            return GlTexture(gl, id);
        };
        gpu_->faces = makeArray(GL_RGBA32F);
        gpu_->depths = makeArray(GL_R32F);
        const GLuint keptId = gpu_->faces.id();
        int layer = 0;
        for (int a = 0; a < 3; ++a) {
            const Axis& ax = axes_[size_t(a)];
            const int n = grid_.dims[size_t(a)];
            for (int side = 0; side < 2; ++side)
                for (int i = 0; i < n; ++i) {
                    if (!keptByAxis[size_t(a)][size_t(side * n + i)]) continue;
                    gl.CopyImageSubData(scratches[size_t(a)].id(), GL_TEXTURE_2D_ARRAY, 0, 0, 0, side * n + i, keptId,
                                        GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, ax.width, ax.height, 1);
                    gl.CopyImageSubData(scratchDepths[size_t(a)].id(), GL_TEXTURE_2D_ARRAY, 0, 0, 0, side * n + i,
                                        gpu_->depths.id(), GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, ax.width, ax.height, 1);
                    // An upper face lies on the slice's upper plane.
                    planes.emplace_back(float((i + (side == 0 ? 1 : 0)) * grid_.voxel), side == 0 ? 1.0f : -1.0f);
                    ++layer;
                }
        }
    }
    gpu_->planes = makeBuffer(gl, std::max<size_t>(planes.size(), 1) * sizeof(glm::vec2), planes.data());
    for (GlTexture& t : scratches) t.reset();
    for (GlTexture& t : scratchDepths) t.reset();
    std::vector<int32_t> table;
    for (int a = 0; a < 3; ++a) {
        const Axis& ax = axes_[size_t(a)];
        const int n = grid_.dims[size_t(a)];
        for (int i = 0; i < n; ++i) {
            const bool upper = ax.upperBefore[size_t(i) + 1] > ax.upperBefore[size_t(i)];
            const bool lower = ax.lowerBefore[size_t(i) + 1] > ax.lowerBefore[size_t(i)];
            table.push_back(upper ? ax.firstLayer + ax.upperBefore[size_t(i)] : -1);
            table.push_back(lower ? ax.firstLayer + ax.upperBefore[size_t(n)] + ax.lowerBefore[size_t(i)] : -1);
        }
    }
    gpu_->layerTable = makeBuffer(gl, table.size() * sizeof(int32_t), table.data());
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl.Finish();
    checkGl(gl, "building the voxel slices");
    buildSeconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

VoxelSlices::~VoxelSlices() = default;

int VoxelSlices::facesKept() const { return axes_[0].layers() + axes_[1].layers() + axes_[2].layers(); }

size_t VoxelSlices::memoryBytes() const {
    size_t n = 0;
    for (const Axis& a : axes_) n += size_t(a.layers()) * arrayWidth_ * arrayHeight_ * (16 + 4);
    return n;
}

}  // namespace ml
