#include "VoxelMarchGather.h"

#include "VoxelSlices.h"
#include "core/Error.h"
#include "detail/GatherReadback.h"
#include "detail/VoxelSlicesGpu.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/gl/GlObjects.h"
#include "meshlight_gpu_shaders.h"

#include <chrono>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

size_t volumeBytes(const VoxelGrid& g) { return 6 * g.count() * 16; }

}  // namespace

struct VoxelMarchGather::Gpu {
    GlProgram marchPass, fillPass;
    GlTexture color;
    GlFramebuffer fb;
    GlVertexArray emptyVao;
    GlBuffer nearBuffer;
    size_t nearCapacity = 0;
    std::map<size_t, GlTexture> volumes;  // per slot: the six face directions' blocks (volume_fill.comp)
};

VoxelMarchGather::VoxelMarchGather(GlContext& context, const Scene& scene, const GatherSettings& settings)
    : context_(context),
      settings_((settings.validate(), settings)),
      proxy_(scene, VoxelGrid::fit(scene.bounds, settings.resolution)),
      near_(proxy_),
      gpu_(std::make_unique<Gpu>()) {
    const GlApi& gl = context_.gl();
    Gpu& g = *gpu_;
    GLint max3d = 0;
    gl.GetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max3d);
    const VoxelGrid& grid = proxy_.grid();
    if (6 * grid.dims[2] > max3d || grid.dims[0] > max3d || grid.dims[1] > max3d)
        throw InputError(concat("ray march: ", grid.describe(), " voxels need a 3D texture ", grid.dims[0], "x",
                                grid.dims[1], "x", 6 * grid.dims[2], ", more than this GL's ", max3d));
    g.marchPass = GlProgram(gl, {{GL_VERTEX_SHADER, "fullscreen.vert", glslSource({shaders::fullscreen_vert})},
                                 {GL_FRAGMENT_SHADER, "gather_volume_march.frag",
                                  glslSource({shaders::common_jitter_glsl, shaders::fisheye_common_glsl,
                                              shaders::common_near_field_glsl, shaders::gather_volume_march_frag})}});
    g.fillPass = GlProgram(gl, {{GL_COMPUTE_SHADER, "volume_fill.comp", glslSource({shaders::volume_fill_comp})}});
    const int n = settings_.imageSize;
    g.color = makeTexture2D(gl, GL_RGBA32F, n, n);
    g.fb = makeFramebuffer(gl, {g.color.id()}, 0, "ray-march gather");
    gl.NamedFramebufferReadBuffer(g.fb.id(), GL_COLOR_ATTACHMENT0);
    g.emptyVao = makeVertexArray(gl);
    g.nearCapacity = 64;  // bound even when empty
    g.nearBuffer = makeBuffer(gl, g.nearCapacity * sizeof(NearTriangleGpu), nullptr, GL_DYNAMIC_DRAW);
    pixels_.resize(size_t(n) * n * 4);
    checkGl(gl, "creating the ray-march gather");
}

VoxelMarchGather::~VoxelMarchGather() = default;

void VoxelMarchGather::setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double) {
    const auto t0 = Clock::now();
    const GlApi& gl = context_.gl();
    const VoxelGrid& grid = proxy_.grid();
    std::vector<Rgb> radiance = proxy_.radianceFrom(irradiance);
    // VoxelSlices draws with GL's default clip state; other passes on this
    // context (the direct-light sampler) change it.
    gl.ClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
    gl.Disable(GL_DEPTH_CLAMP);
    gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    const VoxelSlices slices(context_, proxy_, radiance, settings_.sliceSupersample);

    GLuint id = 0;
    gl.CreateTextures(GL_TEXTURE_3D, 1, &id);
    GlTexture volume(gl, id);
    gl.TextureStorage3D(id, 1, GL_RGBA32F, grid.dims[0], grid.dims[1], 6 * grid.dims[2]);
    gl.TextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl.TextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    const GlProgram& fill = gpu_->fillPass;
    fill.use();
    gl.BindTextureUnit(0, slices.gpu().faces.id());
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, slices.gpu().layerTable.id());
    gl.BindImageTexture(0, id, 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    gl.Uniform3i(fill.uniform("layerOffset"), slices.layerTableOffset(0), slices.layerTableOffset(1),
                 slices.layerTableOffset(2));
    gl.Uniform3i(fill.uniform("dims"), grid.dims[0], grid.dims[1], grid.dims[2]);
    gl.Uniform3i(fill.uniform("texels"), grid.texels(0), grid.texels(1), grid.texels(2));
    gl.DispatchCompute(GLuint((grid.dims[0] + 3) / 4), GLuint((grid.dims[1] + 3) / 4),
                       GLuint((6 * grid.dims[2] + 3) / 4));
    gl.MemoryBarrier(GL_ALL_BARRIER_BITS);
    gl.Finish();  // the slices go when this returns
    checkGl(gl, "filling the ray march's 3D texture");
    const int kept = slices.facesKept(), total = slices.facesTotal();
    radiance_[slot] = std::move(radiance);
    gpu_->volumes[slot] = std::move(volume);
    stats_.buildSeconds += since(t0);
    stats_.source =
        concat(grid.describe(), " voxels in a 3D texture of ", volumeBytes(grid) / 1e6, " MB (from ", kept, " of ",
               total, " slice faces); proxy of ", proxy_.triangles().size(), " triangles; built in ", since(t0), " s");
}

void VoxelMarchGather::releaseSource(size_t slot) {
    radiance_.erase(slot);
    gpu_->volumes.erase(slot);
}

Rgb VoxelMarchGather::estimate(size_t slot, const Vec3& x, const Vec3& normal, uint32_t seed) {
    GatherReadback readback(phases_, stats_, timePhases_);
    const std::vector<Rgb>& radiance = radiance_.at(slot);
    const GlTexture& volume = gpu_->volumes.at(slot);
    const VoxelGrid& grid = proxy_.grid();
    const GlApi& gl = context_.gl();
    const int imageSize = settings_.imageSize;

    const Vec3 n = glm::normalize(normal);
    Vec3 r, u;
    orthonormalBasis(n, r, u);
    const double diagonal = glm::length(grid.upper() - grid.origin);
    const NearField::Gather near = near_.collect(radiance, x, n, settings_.nearVoxels, nearTriangles_);
    const Vec3 eye = near.eye - grid.origin;
    lastNear_ = nearTriangles_.size();
    Gpu& g = *gpu_;
    if (nearTriangles_.size() > g.nearCapacity) {
        g.nearCapacity = std::max(nearTriangles_.size(), 2 * g.nearCapacity);
        g.nearBuffer = makeBuffer(gl, g.nearCapacity * sizeof(NearTriangleGpu), nullptr, GL_DYNAMIC_DRAW);
    }
    if (!nearTriangles_.empty())
        gl.NamedBufferSubData(g.nearBuffer.id(), 0, GLsizeiptr(nearTriangles_.size() * sizeof(NearTriangleGpu)),
                              nearTriangles_.data());
    readback.cpuDone();

    gl.BindFramebuffer(GL_FRAMEBUFFER, g.fb.id());
    gl.Viewport(0, 0, imageSize, imageSize);
    gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    const float clear[4] = {0, 0, 0, 0};
    gl.ClearBufferfv(GL_COLOR, 0, clear);
    gl.Disable(GL_DEPTH_TEST);
    gl.Disable(GL_BLEND);
    gl.Disable(GL_CULL_FACE);
    gl.BindVertexArray(g.emptyVao.id());
    const GlProgram& p = g.marchPass;
    p.use();
    const glm::mat3 basis{glm::vec3(r), glm::vec3(u), glm::vec3(n)};
    gl.Uniform1i(p.uniform("imageSize"), imageSize);
    gl.Uniform1ui(p.uniform("gatherSeed"), seed);
    gl.Uniform3f(p.uniform("eye"), float(eye.x), float(eye.y), float(eye.z));
    gl.UniformMatrix3fv(p.uniform("basis"), 1, GL_FALSE, &basis[0][0]);
    gl.Uniform1f(p.uniform("maxDistance"), float(2 * diagonal));
    gl.Uniform3f(p.uniform("nearLo"), float(near.lo.x), float(near.lo.y), float(near.lo.z));
    gl.Uniform3f(p.uniform("nearHi"), float(near.hi.x), float(near.hi.y), float(near.hi.z));
    gl.Uniform3i(p.uniform("nearCellLo"), near.cellLo[0], near.cellLo[1], near.cellLo[2]);
    gl.Uniform3i(p.uniform("nearCellHi"), near.cellHi[0], near.cellHi[1], near.cellHi[2]);
    gl.Uniform3i(p.uniform("texels"), grid.texels(0), grid.texels(1), grid.texels(2));
    gl.Uniform1i(p.uniform("nearCount"), GLint(nearTriangles_.size()));
    gl.Uniform1f(p.uniform("minDistance"), float(1e-7 * diagonal));
    gl.Uniform3i(p.uniform("dims"), grid.dims[0], grid.dims[1], grid.dims[2]);
    gl.Uniform1f(p.uniform("voxel"), float(grid.voxel));
    gl.BindTextureUnit(0, volume.id());
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, g.nearBuffer.id());
    gl.DrawArrays(GL_TRIANGLES, 0, 3);
    return readback.finish(
        gl, [&] { return readFisheyeIrradiance(gl, imageSize, pixels_); }, "ray-marching indirect light", x);
}

IndirectStats VoxelMarchGather::stats() const {
    IndirectStats s = stats_;
    s.sourceBytes = proxy_.memoryBytes();
    for (const auto& [slot, radiance] : radiance_)
        s.sourceBytes += volumeBytes(proxy_.grid()) + radiance.size() * sizeof(Rgb);
    return s;
}

}  // namespace ml
