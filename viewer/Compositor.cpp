#include "Compositor.h"

#include "core/Error.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/gl/GlObjects.h"
#include "meshlight_viewer_lib_shaders.h"

#include <glm/gtc/matrix_transform.hpp>

namespace ml {

void CompositorSettings::validate() const {
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw InputError(concat("image size ", width, "x", height, " is not within 1..16384"));
    if (supersample < 1 || supersample > 16)
        throw InputError(concat("supersampling ", supersample, " is not within 1..16"));
    if (long(width) * supersample > 16384 || long(height) * supersample > 16384)
        throw InputError(concat("image ", width, "x", height, " with supersampling ", supersample,
                                " exceeds 16384 sub-pixels per side: lower --supersample"));
}

namespace {

struct SceneVertex {
    glm::vec3 position, kd, ke;
};
struct CacheVertex {
    glm::vec3 position, irradiance;
};

// Vertex layout of interleaved float attributes, `counts` floats each.
void describeFloats(const GlApi& gl, GLuint vao, GLuint buffer, std::initializer_list<int> counts) {
    GLuint offset = 0, index = 0;
    for (int c : counts) {
        gl.EnableVertexArrayAttrib(vao, index);
        gl.VertexArrayAttribFormat(vao, index, c, GL_FLOAT, GL_FALSE, offset);
        gl.VertexArrayAttribBinding(vao, index, 0);
        offset += GLuint(c * sizeof(float));
        ++index;
    }
    gl.VertexArrayVertexBuffer(vao, 0, buffer, 0, GLsizei(offset));
}

}  // namespace

struct Compositor::Impl {
    const GlApi& gl;
    const Scene& scene;
    Vec3 origin;
    GlProgram gbuffer, irradiance, composite;
    GlBuffer sceneBuffer;
    GlVertexArray sceneVao, emptyVao;
    GLsizei sceneVertices = 0;

    Impl(GlContext& ctx, const Scene& s) : gl(ctx.gl()), scene(s), origin(s.bounds.center()) {
        gbuffer = GlProgram(gl, {{GL_VERTEX_SHADER, "scene_gbuffer.vert", glslSource({shaders::scene_gbuffer_vert})},
                                 {GL_FRAGMENT_SHADER, "scene_gbuffer.frag", glslSource({shaders::scene_gbuffer_frag})}});
        irradiance = GlProgram(gl, {{GL_VERTEX_SHADER, "irradiance.vert", glslSource({shaders::irradiance_vert})},
                                    {GL_FRAGMENT_SHADER, "irradiance.frag", glslSource({shaders::irradiance_frag})}});
        composite = GlProgram(gl, {{GL_VERTEX_SHADER, "composite.vert", glslSource({shaders::composite_vert})},
                                   {GL_FRAGMENT_SHADER, "composite.frag", glslSource({shaders::composite_frag})}});
        // The scene as a triangle soup: materials are per face.
        std::vector<SceneVertex> soup;
        soup.reserve(scene.triangleCount() * 3);
        for (const Mesh& m : scene.meshes)
            for (size_t t = 0; t < m.triangles.size(); ++t) {
                const Material& mat = scene.materials[m.materials[t]];
                for (const Vec3& p : m.triangle(t))
                    soup.push_back({glm::vec3(p - origin), glm::vec3(mat.kd), glm::vec3(mat.ke)});
            }
        sceneVertices = GLsizei(soup.size());
        sceneBuffer = makeBuffer(gl, std::max<size_t>(soup.size(), 1) * sizeof(SceneVertex), soup.data());
        sceneVao = makeVertexArray(gl);
        describeFloats(gl, sceneVao.id(), sceneBuffer.id(), {3, 3, 3});
        emptyVao = makeVertexArray(gl);
        checkGl(gl, "creating the compositor");
    }

    GlFramebuffer framebuffer(std::initializer_list<GLuint> colors, GLuint depth, bool stencil = false) {
        GLuint f = 0;
        gl.CreateFramebuffers(1, &f);
        GlFramebuffer fb(gl, f);
        std::vector<GLenum> buffers;
        for (GLuint c : colors) {
            const GLenum att = GLenum(GL_COLOR_ATTACHMENT0 + buffers.size());
            gl.NamedFramebufferTexture(f, att, c, 0);
            buffers.push_back(att);
        }
        if (depth) gl.NamedFramebufferTexture(f, stencil ? GL_DEPTH_STENCIL_ATTACHMENT : GL_DEPTH_ATTACHMENT, depth, 0);
        gl.NamedFramebufferDrawBuffers(f, GLsizei(buffers.size()), buffers.data());
        if (gl.CheckNamedFramebufferStatus(f, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            throw std::runtime_error("compositor: framebuffer incomplete");
        return fb;
    }

    // Right-handed view, reversed infinite projection (z_ndc = near / depth).
    glm::mat4 clipFromLocal(const Camera& camera, double aspect) const {
        const double f = 1.0 / std::tan(glm::radians(camera.fovYDegrees) * 0.5);
        const double nearDistance = 1e-5 * std::max(scene.bounds.diagonal(), 1e-300);
        Mat4 p(0.0);
        p[0][0] = f / aspect;
        p[1][1] = f;
        p[3][2] = nearDistance;
        p[2][3] = -1.0;
        const Mat4 view = camera.view() * glm::translate(Mat4(1.0), origin);
        return glm::mat4(p * view);
    }

    ImageRgb render(const Camera& camera, const std::vector<IrradianceMeshView>& direct,
                    const CompositorSettings& s) {
        s.validate();
        camera.validate();
        ML_ASSERT(direct.size() == scene.lights.size(), direct.size(), " meshes for ", scene.lights.size(), " lights");
        const int w = s.width * s.supersample, h = s.height * s.supersample;
        const glm::mat4 mvp = clipFromLocal(camera, double(s.width) / s.height);

        GlTexture reflectance = makeTexture2D(gl, GL_RGBA32F, w, h);
        GlTexture emission = makeTexture2D(gl, GL_RGBA32F, w, h);
        GlTexture irradianceSum = makeTexture2D(gl, GL_RGBA32F, w, h);
        GlTexture radiance = makeTexture2D(gl, GL_RGBA32F, w, h);
        GlTexture sceneDepth = makeTexture2D(gl, GL_DEPTH_COMPONENT32F, w, h);
        GlTexture cacheDepth = makeTexture2D(gl, GL_DEPTH32F_STENCIL8, w, h);
        GlFramebuffer gbufferFb = framebuffer({reflectance.id(), emission.id()}, sceneDepth.id());
        GlFramebuffer irradianceFb = framebuffer({irradianceSum.id()}, cacheDepth.id(), true);
        GlFramebuffer radianceFb = framebuffer({radiance.id()}, 0);

        gl.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
        gl.Disable(GL_DEPTH_CLAMP);
        gl.Disable(GL_CULL_FACE);
        gl.Disable(GL_COLOR_LOGIC_OP);
        gl.Viewport(0, 0, w, h);
        gl.DepthMask(GL_TRUE);
        const float zero[4] = {0, 0, 0, 0};
        const float farDepth = 0.0f;  // reversed depth

        // 1. Reflectance and emission from the scene's geometry.
        gl.BindFramebuffer(GL_FRAMEBUFFER, gbufferFb.id());
        gl.ClearBufferfv(GL_COLOR, 0, zero);
        gl.ClearBufferfv(GL_COLOR, 1, zero);
        gl.ClearBufferfv(GL_DEPTH, 0, &farDepth);
        gl.Enable(GL_DEPTH_TEST);
        gl.DepthFunc(GL_GREATER);
        gbuffer.use();
        gl.UniformMatrix4fv(gbuffer.uniform("uClipFromLocal"), 1, GL_FALSE, &mvp[0][0]);
        gl.BindVertexArray(sceneVao.id());
        gl.DrawArrays(GL_TRIANGLES, 0, sceneVertices);

        // 2. Σ over lights of the Gouraud-interpolated cached irradiance. Each
        // mesh first lays its own depth, then adds its nearest surface only.
        gl.BindFramebuffer(GL_FRAMEBUFFER, irradianceFb.id());
        gl.ClearBufferfv(GL_COLOR, 0, zero);
        irradiance.use();
        gl.UniformMatrix4fv(irradiance.uniform("uClipFromLocal"), 1, GL_FALSE, &mvp[0][0]);
        gl.BlendFunc(GL_ONE, GL_ONE);
        gl.BlendEquation(GL_FUNC_ADD);
        for (const IrradianceMeshView& mesh : direct) {
            std::vector<CacheVertex> vertices;
            vertices.reserve(mesh.triangles.size() * 3);
            for (const glm::uvec3& t : mesh.triangles)
                for (int k = 0; k < 3; ++k)
                    vertices.push_back({glm::vec3(mesh.positions[t[k]] - origin), glm::vec3(mesh.irradiance[t[k]])});
            if (vertices.empty()) continue;
            GlBuffer buffer = makeBuffer(gl, vertices.size() * sizeof(CacheVertex), vertices.data());
            GlVertexArray vao = makeVertexArray(gl);
            describeFloats(gl, vao.id(), buffer.id(), {3, 3});
            gl.BindVertexArray(vao.id());
            gl.DepthMask(GL_TRUE);
            gl.StencilMask(0xff);
            gl.ClearBufferfi(GL_DEPTH_STENCIL, 0, farDepth, 0);
            gl.ColorMaski(0, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
            gl.DepthFunc(GL_GREATER);
            gl.DrawArrays(GL_TRIANGLES, 0, GLsizei(vertices.size()));
            gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
            gl.DepthMask(GL_FALSE);
            gl.DepthFunc(GL_EQUAL);
            gl.Enable(GL_BLEND);
            // A cache triangle holds the irradiance of its front (CCW) side; a
            // surface lit from both sides has a second, reversed copy for its
            // back (IrradianceCache). The depth pass above took both sides, so
            // a back seen without a copy stays unlit instead of showing what
            // lies behind it.
            gl.Enable(GL_CULL_FACE);
            gl.CullFace(GL_BACK);
            gl.FrontFace(GL_CCW);
            // Coincident surfaces (two copies of a floor) tie in depth: only
            // the first fragment of a sub-pixel adds its irradiance.
            gl.Enable(GL_STENCIL_TEST);
            gl.StencilFunc(GL_EQUAL, 0, 0xff);
            gl.StencilOp(GL_KEEP, GL_KEEP, GL_INCR);
            gl.DrawArrays(GL_TRIANGLES, 0, GLsizei(vertices.size()));
            gl.Disable(GL_STENCIL_TEST);
            gl.Disable(GL_CULL_FACE);
            gl.Disable(GL_BLEND);
        }
        gl.DepthMask(GL_TRUE);
        gl.Disable(GL_DEPTH_TEST);

        // 3. Radiance per sub-pixel.
        gl.BindFramebuffer(GL_FRAMEBUFFER, radianceFb.id());
        composite.use();
        gl.BindTextureUnit(0, reflectance.id());
        gl.BindTextureUnit(1, emission.id());
        gl.BindTextureUnit(2, irradianceSum.id());
        gl.BindVertexArray(emptyVao.id());
        gl.DrawArrays(GL_TRIANGLES, 0, 3);

        std::vector<float> rgba(size_t(w) * h * 4);
        gl.NamedFramebufferReadBuffer(radianceFb.id(), GL_COLOR_ATTACHMENT0);
        gl.PixelStorei(GL_PACK_ALIGNMENT, 4);
        gl.ReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, rgba.data());
        checkGl(gl, "compositing");

        ImageRgb full(w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float* p = &rgba[(size_t(h - 1 - y) * w + x) * 4];  // GL rows start at the bottom
                const Rgb c(p[0], p[1], p[2]);
                ML_ASSERT(isFinite(c), "non-finite radiance at sub-pixel ", x, ",", y);
                full.set(x, y, c);
            }
        return boxDownsample(full, s.supersample);
    }
};

Compositor::Compositor(GlContext& context, const Scene& scene)
    : impl_(std::make_unique<Impl>(context, scene)) {}
Compositor::~Compositor() = default;

ImageRgb Compositor::render(const Camera& camera, const std::vector<IrradianceMeshView>& direct,
                            const CompositorSettings& settings) {
    return impl_->render(camera, direct, settings);
}

}  // namespace ml
