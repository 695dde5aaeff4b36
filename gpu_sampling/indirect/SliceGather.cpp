#include "SliceGather.h"

#include "core/Error.h"
#include "detail/GatherReadback.h"
#include "detail/VoxelSlicesGpu.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/gl/GlObjects.h"
#include "meshlight_gpu_shaders.h"

#include <chrono>

namespace ml {

void GatherSettings::validate() const {
    if (imageSize < 4 || imageSize > 1024)
        throw InputError(concat("gather image size ", imageSize, " is not in 4..1024"));
    if (resolution < 4 || resolution > 512)
        throw InputError(concat("voxel resolution ", resolution, " is not in 4..512"));
    if (nearVoxels < 0 || nearVoxels > 8) throw InputError(concat("near voxels ", nearVoxels, " is not in 0..8"));
    if (sliceSupersample < 1 || sliceSupersample > 8)
        throw InputError(concat("slice supersampling ", sliceSupersample, " is not in 1..8"));
}

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

}  // namespace

struct SliceGather::Gpu {
    GlProgram slicePass, marchPass, nearPass;
    // One colour + depth target per image size in use.
    struct Target {
        GlTexture color, depth;
        GlFramebuffer fb;
    };
    Target& target(const GlApi& gl, int imageSize);
    std::map<int, Target> targets;
    GlVertexArray emptyVao;
    GlBuffer nearBuffer;
    size_t nearCapacity = 0;
};

SliceGather::SliceGather(GlContext& context, const Scene& scene, const GatherSettings& settings)
    : context_(context),
      settings_((settings.validate(), settings)),
      proxy_(scene, VoxelGrid::fit(scene.bounds, settings.resolution)),
      gpu_(std::make_unique<Gpu>()),
      nearField_(proxy_) {
    const GlApi& gl = context_.gl();
    const std::string common = glslSource({shaders::common_jitter_glsl, shaders::fisheye_common_glsl});
    auto body = [&](const char* src) { return common + src; };
    Gpu& g = *gpu_;
    g.slicePass = GlProgram(gl, {{GL_VERTEX_SHADER, "fullscreen.vert", glslSource({shaders::fullscreen_vert})},
                                 {GL_FRAGMENT_SHADER, "gather_slices.frag", body(shaders::gather_slices_frag)}});
    g.marchPass = GlProgram(gl, {{GL_VERTEX_SHADER, "fullscreen.vert", glslSource({shaders::fullscreen_vert})},
                                 {GL_FRAGMENT_SHADER, "gather_slices_march.frag", body(shaders::gather_slices_march_frag)}});
    g.nearPass = GlProgram(gl, {{GL_VERTEX_SHADER, "fullscreen.vert", glslSource({shaders::fullscreen_vert})},
                                {GL_FRAGMENT_SHADER, "gather_near.frag", body(shaders::gather_near_frag)}});
    g.emptyVao = makeVertexArray(gl);
    checkGl(gl, "creating the slice gather");
}

SliceGather::~SliceGather() = default;

SliceGather::Gpu::Target& SliceGather::Gpu::target(const GlApi& gl, int n) {
    auto it = targets.find(n);
    if (it != targets.end()) return it->second;
    Target t;
    t.color = makeTexture2D(gl, GL_RGBA32F, n, n);
    t.depth = makeTexture2D(gl, GL_DEPTH_COMPONENT32F, n, n);
    t.fb = makeFramebuffer(gl, {t.color.id()}, t.depth.id(), "fish-eye gather");
    gl.NamedFramebufferReadBuffer(t.fb.id(), GL_COLOR_ATTACHMENT0);
    return targets.emplace(n, std::move(t)).first->second;
}

void SliceGather::setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance) {
    const auto t0 = Clock::now();
    Slot s;
    s.imageSize = std::min(settings_.imageSize,
                           std::max(16, int(std::lround(settings_.imageSize * std::sqrt(std::clamp(importance, 0.0, 1.0))))));
    s.radiance = proxy_.radianceFrom(irradiance);
    s.slices = std::make_unique<VoxelSlices>(context_, proxy_, s.radiance, settings_.sliceSupersample);
    const VoxelSlices& v = *s.slices;
    slots_[slot] = std::move(s);
    stats_.buildSeconds += since(t0);
    stats_.source = concat(v.grid().describe(), " voxels, gathers of ", slots_[slot].imageSize, "x",
                           slots_[slot].imageSize, ", ", v.facesKept(), " of ", v.facesTotal(),
                           " slice faces kept, ", v.memoryBytes() / 1e6, " MB; proxy of ", proxy_.triangles().size(),
                           " triangles; built in ", since(t0), " s");
}

void SliceGather::releaseSource(size_t slot) { slots_.erase(slot); }

Rgb SliceGather::estimate(size_t slot, const Vec3& x, const Vec3& normal, uint32_t seed) {
    GatherReadback readback(phases_, stats_, timePhases_);
    const Slot& s = slots_.at(slot);
    const VoxelSlices& slices = *s.slices;
    const VoxelGrid& grid = proxy_.grid();
    const GlApi& gl = context_.gl();
    const int imageSize = s.imageSize;

    const Vec3 n = glm::normalize(normal);
    Vec3 r, u;
    orthonormalBasis(n, r, u);
    // The near box, the eye (lifted off the surface, nudged off edges) and
    // the near triangles it may see: NearField.
    const double diagonal = glm::length(grid.upper() - grid.origin);
    std::vector<NearTriangleGpu>& near = near_;
    const NearField::Gather box = nearField_.collect(s.radiance, x, n, settings_.nearVoxels, near);
    const std::array<int, 3> cell = grid.cell(x);
    const Vec3 eye = box.eye - grid.origin;
    const Vec3 nearLo = box.lo, nearHi = box.hi;
    const int k = settings_.nearVoxels;
    lastNear_ = near.size();
    Gpu& g = *gpu_;
    if (near.size() > g.nearCapacity) {
        g.nearCapacity = std::max(near.size(), 2 * g.nearCapacity);
        g.nearBuffer = makeBuffer(gl, g.nearCapacity * sizeof(NearTriangleGpu), nullptr, GL_DYNAMIC_DRAW);
    }
    if (!near.empty())
        gl.NamedBufferSubData(g.nearBuffer.id(), 0, GLsizeiptr(near.size() * sizeof(NearTriangleGpu)), near.data());
    readback.cpuDone();

    Gpu::Target& target = g.target(gl, imageSize);
    pixels_.resize(size_t(imageSize) * imageSize * 4);
    lastImageSize_ = imageSize;
    gl.BindFramebuffer(GL_FRAMEBUFFER, target.fb.id());
    gl.Viewport(0, 0, imageSize, imageSize);
    const float clear[4] = {0, 0, 0, 0}, far = 1.0f;
    gl.ClearBufferfv(GL_COLOR, 0, clear);
    gl.ClearBufferfv(GL_DEPTH, 0, &far);
    // The state these passes assume, whatever ran before on the context.
    gl.ClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
    gl.Disable(GL_DEPTH_CLAMP);
    gl.Disable(GL_STENCIL_TEST);
    gl.Disable(GL_SCISSOR_TEST);
    gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl.Enable(GL_DEPTH_TEST);
    gl.DepthFunc(GL_LESS);
    gl.DepthMask(GL_TRUE);
    gl.Disable(GL_BLEND);
    gl.Disable(GL_CULL_FACE);
    gl.BindVertexArray(g.emptyVao.id());
    const glm::mat3 basis{glm::vec3(r), glm::vec3(u), glm::vec3(n)};
    auto common = [&](const GlProgram& p) {
        p.use();
        gl.Uniform1i(p.uniform("imageSize"), imageSize);
        gl.Uniform1ui(p.uniform("gatherSeed"), seed);
        gl.Uniform3f(p.uniform("eye"), float(eye.x), float(eye.y), float(eye.z));
        gl.UniformMatrix3fv(p.uniform("basis"), 1, GL_FALSE, &basis[0][0]);
        gl.Uniform1f(p.uniform("maxDistance"), float(2 * diagonal));
        gl.Uniform3f(p.uniform("nearLo"), float(nearLo.x), float(nearLo.y), float(nearLo.z));
        gl.Uniform3f(p.uniform("nearHi"), float(nearHi.x), float(nearHi.y), float(nearHi.z));
        gl.Uniform3i(p.uniform("nearCellLo"), cell[0] - k, cell[1] - k, cell[2] - k);
        gl.Uniform3i(p.uniform("nearCellHi"), cell[0] + k, cell[1] + k, cell[2] + k);
    };
    if (!near.empty()) {
        common(g.nearPass);
        gl.Uniform1i(g.nearPass.uniform("nearCount"), GLint(near.size()));
        gl.Uniform1f(g.nearPass.uniform("minDistance"), float(1e-7 * diagonal));
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, g.nearBuffer.id());
        gl.DrawArrays(GL_TRIANGLES, 0, 3);
    }
    if (settings_.quadPerFace) {
        const GlProgram& slicePass = g.slicePass;
        common(slicePass);
        for (int a = 0; a < 3; ++a) {
            const VoxelSlices::Axis& ax = slices.axes()[size_t(a)];
            if (ax.layers() == 0) continue;
            const int dims = grid.dims[size_t(a)];
            const int c = std::clamp(int(std::floor(eye[a] / grid.voxel)), 0, dims - 1);
            gl.Uniform1i(slicePass.uniform("axis"), a);
            gl.Uniform2f(slicePass.uniform("extentUV"), float(ax.width * grid.voxel), float(ax.height * grid.voxel));
            gl.Uniform1f(slicePass.uniform("voxel"), float(grid.voxel));
            gl.Uniform2f(slicePass.uniform("texelOrigin"), float(0.5 * grid.voxel), float(0.5 * grid.voxel));
            gl.Uniform2f(slicePass.uniform("texScale"), float(ax.width) / float(slices.arrayWidth()),
                         float(ax.height) / float(slices.arrayHeight()));
            gl.BindTextureUnit(0, slices.gpu().faces.id());
            gl.BindTextureUnit(1, slices.gpu().depths.id());
            gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, slices.gpu().planes.id());
            gl.Uniform1i(slicePass.uniform("ownSlice"), 0);
            // Upper faces of the slices below the point, seen when it can look down...
            const int uppers = ax.upperBefore[size_t(c)];
            if (uppers > 0 && n[a] < 0.99999) {
                gl.Uniform1i(slicePass.uniform("firstLayer"), ax.firstLayer);
                gl.DrawArraysInstancedBaseInstance(GL_TRIANGLES, 0, 3, uppers, 0);
            }
            // ...lower faces of the slices above it, when it can look up.
            const int lowerFirst = ax.upperBefore[size_t(dims)] + ax.lowerBefore[size_t(c) + 1];
            const int lowers = ax.layers() - lowerFirst;
            if (lowers > 0 && n[a] > -0.99999) {
                gl.Uniform1i(slicePass.uniform("firstLayer"), ax.firstLayer + lowerFirst);
                gl.DrawArraysInstancedBaseInstance(GL_TRIANGLES, 0, 3, lowers, 0);
            }
            // ...and the point's own slice, along axes its surface is nearly
            // parallel to (gather_slices_march.frag says why).
            if (std::abs(n[a]) < 0.1) {
                gl.Uniform1i(slicePass.uniform("ownSlice"), 1);
                if (ax.upperBefore[size_t(c) + 1] > ax.upperBefore[size_t(c)]) {
                    gl.Uniform1i(slicePass.uniform("firstLayer"), ax.firstLayer + ax.upperBefore[size_t(c)]);
                    gl.DrawArraysInstancedBaseInstance(GL_TRIANGLES, 0, 3, 1, 0);
                }
                if (ax.lowerBefore[size_t(c) + 1] > ax.lowerBefore[size_t(c)]) {
                    gl.Uniform1i(slicePass.uniform("firstLayer"),
                                 ax.firstLayer + ax.upperBefore[size_t(dims)] + ax.lowerBefore[size_t(c)]);
                    gl.DrawArraysInstancedBaseInstance(GL_TRIANGLES, 0, 3, 1, 0);
                }
            }
        }
    } else {
        const GlProgram& marchPass = g.marchPass;
        common(marchPass);
        gl.Uniform3i(marchPass.uniform("layerOffset"), slices.layerTableOffset(0), slices.layerTableOffset(1),
                     slices.layerTableOffset(2));
        gl.Uniform3i(marchPass.uniform("dims"), grid.dims[0], grid.dims[1], grid.dims[2]);
        gl.Uniform1f(marchPass.uniform("voxel"), float(grid.voxel));
        gl.Uniform2f(marchPass.uniform("arraySize"), float(slices.arrayWidth()), float(slices.arrayHeight()));
        gl.BindTextureUnit(0, slices.gpu().faces.id());
        gl.BindTextureUnit(1, slices.gpu().depths.id());
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, slices.gpu().layerTable.id());
        gl.DrawArrays(GL_TRIANGLES, 0, 3);
    }
    return readback.finish(
        gl, [&] { return readFisheyeIrradiance(gl, imageSize, pixels_); }, "gathering indirect light", x);
}

IndirectStats SliceGather::stats() const {
    IndirectStats s = stats_;
    s.sourceBytes = proxy_.memoryBytes();
    for (const auto& [slot, v] : slots_) s.sourceBytes += v.slices->memoryBytes() + v.radiance.size() * sizeof(Rgb);
    return s;
}

}  // namespace ml
