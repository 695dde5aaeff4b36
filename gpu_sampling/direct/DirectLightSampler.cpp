#include "DirectLightSampler.h"

#include "Jitter.h"
#include "CpuCoverage.h"
#include "LightFrustum.h"
#include "OccluderBvh.h"
#include "OccluderPolygons.h"
#include "core/EmitterTexture.h"
#include "core/Error.h"
#include "core/reference/Lambert.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/gl/GlObjects.h"
#include "meshlight_gpu_shaders.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>

namespace ml {

DirectMethod parseDirectMethod(const std::string& name) {
    if (name == "query") return DirectMethod::OcclusionQuery;
    if (name == "regular") return DirectMethod::Regular;
    if (name == "jittered") return DirectMethod::Jittered;
    throw InputError(concat("unknown direct-light method '", name, "' (use query, regular or jittered)"));
}

const char* directMethodName(DirectMethod m) {
    switch (m) {
        case DirectMethod::OcclusionQuery: return "query";
        case DirectMethod::Regular: return "regular";
        case DirectMethod::Jittered: return "jittered";
    }
    return "?";
}

DirectEstimator parseDirectEstimator(const std::string& name) {
    if (name == "plain") return DirectEstimator::Plain;
    if (name == "cv") return DirectEstimator::ControlVariate;
    throw InputError(concat("unknown estimator '", name, "' (use plain or cv)"));
}

const char* directEstimatorName(DirectEstimator e) {
    return e == DirectEstimator::Plain ? "plain" : "cv";
}

const char* directPathName(DirectPath p) {
    switch (p) {
        case DirectPath::Unlit: return "unlit";
        case DirectPath::Unoccluded: return "unoccluded";
        case DirectPath::Rasterised: return "rasterised";
        case DirectPath::Occluded: return "occluded";
        case DirectPath::CpuRasterised: return "cpu-rasterised";
    }
    return "?";
}

void DirectSamplerSettings::validate() const {
    if (imageSize < 4 || imageSize > 1024)
        throw InputError(concat("image size ", imageSize, " is not in [4, 1024]"));
    if (bits != 1 && bits != 4 && bits != 8 && bits != 16 && bits != 32)
        throw InputError(concat("bits per pixel ", bits, " is not one of 1, 4, 8, 16, 32"));
    if (!(maxHalfAngleDegrees > 10 && maxHalfAngleDegrees < 80))
        throw InputError(concat("maximum half angle ", maxHalfAngleDegrees, " is not in (10, 80) degrees"));
    if (!(eyeOffset > 0 && eyeOffset < 1e-2) || !(planeTolerance > 0 && planeTolerance < 1e-2))
        throw InputError("eye offset and plane tolerance must be in (0, 1e-2) of the scene size");
    if (cpuCoverageTriangles < 0)
        throw InputError(concat("CPU coverage triangles ", cpuCoverageTriangles, " is negative"));
}

namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// GPU triangle corner (std430 vec4): position relative to the buffer's
// origin; w of a triangle's first corner holds the bits of 1 + the index of
// the light the face belongs to (0 for non-emitters), of its second 1 + the
// index of its cut-out record (CutOuts; 0 for opaque faces).
struct Corner {
    float x, y, z;
    uint32_t id;
};

// Occluders with a cut-out (Material::alphaMap), for the coverage pass's
// MASKS variant (direct_coverage.frag): per face two vec4, its corners'
// texture coordinates and its material's slot; per slot a header of 12
// words (texel offset, width, height, wrap and filter flags, then as float
// bits the coverage factor, cut-off, scale and offset of the map) and the
// image's coverage (Texture::coverage of each texel, 0..255), four texels a
// word. The shader reads it as Texture::coverage does: wrapped, nearest or
// bilinear.
struct CutOuts {
    std::vector<glm::vec4> faces;
    std::vector<uint32_t> images;
    std::map<const Material*, uint32_t> slots;

    // 1 + the record of face t of `mesh` (0 when it is opaque).
    uint32_t add(const Scene& scene, const Mesh& mesh, size_t t) {
        const Material& m = scene.materials[mesh.materials[t]];
        if (!m.alphaMap || mesh.texcoords.empty()) return 0;
        const glm::uvec3 v = mesh.triangles[t];
        const glm::vec2 a(mesh.texcoords[v.x]), b(mesh.texcoords[v.y]), c(mesh.texcoords[v.z]);
        faces.push_back(glm::vec4(a, b));
        faces.push_back(glm::vec4(c, glm::uintBitsToFloat(slot(m)), 0.0f));
        return uint32_t(faces.size() / 2);
    }
    uint32_t slot(const Material& m) {
        const auto found = slots.find(&m);
        if (found != slots.end()) return found->second;
        const uint32_t s = uint32_t(slots.size());
        slots.emplace(&m, s);
        // Headers first: images start after room for every slot's header is
        // known, so they are appended to a list of their own and joined later.
        const Texture& t = *m.alphaMap.image;
        const TextureMap& map = m.alphaMap;
        headers.push_back({uint32_t(texels.size()), uint32_t(t.width), uint32_t(t.height),
                           uint32_t(t.wrapS) | uint32_t(t.wrapT) << 2 | (t.nearest ? 16u : 0u),
                           glm::floatBitsToUint(float(map.factor.r)), glm::floatBitsToUint(float(m.alphaCutoff)),
                           glm::floatBitsToUint(float(map.scale.x)), glm::floatBitsToUint(float(map.scale.y)),
                           glm::floatBitsToUint(float(map.offset.x)), glm::floatBitsToUint(float(map.offset.y)), 0u,
                           0u});
        for (int y = 0; y < t.height; ++y)
            for (int x = 0; x < t.width; ++x)
                texels.push_back(uint8_t(std::lround(
                    255 * t.coverage(Vec2((x + 0.5) / t.width, (y + 0.5) / t.height)))));
        return s;
    }
    // The image buffer: every header (12 words each), then the texels.
    void finish() {
        const uint32_t base = uint32_t(headers.size() * 12);
        for (const auto& h : headers) {
            std::array<uint32_t, 12> w = h;
            w[0] += 4 * base;  // texel index in the whole buffer, four a word
            images.insert(images.end(), w.begin(), w.end());
        }
        images.resize(base + (texels.size() + 3) / 4, 0u);
        for (size_t i = 0; i < texels.size(); ++i) images[base + i / 4] |= uint32_t(texels[i]) << (8 * (i % 4));
    }
    std::vector<std::array<uint32_t, 12>> headers;
    std::vector<uint8_t> texels;
};

glm::mat4 toFloat(const Mat4& m) { return glm::mat4(m); }

// Set bits of a word, branch-free: without -mpopcnt, __builtin_popcount is a
// call into libgcc, measurable in the weighting loop.
inline uint32_t bitCount(uint32_t v) {
    v = v - ((v >> 1) & 0x55555555u);
    v = (v & 0x33333333u) + ((v >> 2) & 0x33333333u);
    return (((v + (v >> 4)) & 0x0f0f0f0fu) * 0x01010101u) >> 24;
}

// Where the samples of one sampling image lie and what each weighs.
struct SampleGrid {
    double left, bottom, pw, ph;  // window origin and pixel size at distance 1
    double nx, ny, nz;            // receiver normal in camera coordinates
    uint32_t seed;
    int strataX, strataY;
    int count;                    // samples per pixel: strataX × strataY
    bool jitter;
    float cellX[32], cellY[32];   // each sample's stratum, as jitter::position has it

    SampleGrid(const SamplingFrustum& f, int size, const Vec3& n, uint32_t seed_, int bits, bool jitter_)
        : left(f.left), bottom(f.bottom), pw((f.rightEdge - f.left) / size), ph((f.top - f.bottom) / size),
          nx(glm::dot(n, f.right)), ny(glm::dot(n, f.up)), nz(glm::dot(n, f.forward)), seed(seed_),
          jitter(jitter_) {
        jitter::strata(bits, strataX, strataY);
        count = strataX * strataY;
        for (int k = 0; k < count; ++k) {
            cellX[k] = float(uint32_t(k) % uint32_t(strataX));
            cellY[k] = float(uint32_t(k) / uint32_t(strataX));
        }
    }
    // Window positions of the samples of pixel (i, j), in bit order: the
    // points the GPU tested. jitter::position for every bit at once, with the
    // same float operations, written without branches so that it vectorises
    // (a sample at a time, the weighting was a third of a rasterised pair).
    void points(int i, int j, uint32_t pixel, double* u, double* v) const {
        const float sx = float(strataX), sy = float(strataY);
        for (int k = 0; k < count; ++k) {
            float rx = 0.5f, ry = 0.5f;
            if (jitter) {
                const uint32_t h = jitter::hash((pixel * 32u + uint32_t(k)) ^ seed);
                rx = (float(h & 0xffffu) + 0.5f) * (1.0f / 65536.0f);
                ry = (float(h >> 16) + 0.5f) * (1.0f / 65536.0f);
            }
            u[k] = left + (i + double((cellX[k] + rx) / sx)) * pw;
            v[k] = bottom + (j + double((cellY[k] + ry) / sy)) * ph;
        }
    }
    // cosθ·dω per unit window area at each (u, v) (eq. 3): the direction is
    // (u, v, 1) in camera coordinates, so cosθ / |s|⁴ with |s|² = 1 + u² + v².
    // Zero below the receiver's horizon.
    void weights(const double* u, const double* v, double* w) const {
        for (int k = 0; k < count; ++k) {
            const double cosine = nx * u[k] + ny * v[k] + nz;
            const double r2 = 1.0 + u[k] * u[k] + v[k] * v[k];
            // max, not a branch, so that the loop vectorises: 0 where the
            // cosine is 0 or below (−0 where it is −0, which adds to a sum as +0 does).
            w[k] = std::max(cosine / (r2 * r2), 0.0);
        }
    }
};

// sum + the weights of the samples whose bit is set in `mask`, added in bit
// order: bit for bit the sum of a loop over the set bits alone, as adding
// +0 to a sum of non-negative weights (which starts at +0) changes nothing,
// and without its unpredictable branches.
inline double addMasked(double sum, const double* w, uint32_t mask, int count) {
    for (int k = 0; k < count; ++k) {
        uint64_t bits;
        std::memcpy(&bits, &w[k], sizeof bits);
        bits &= 0 - uint64_t(mask >> k & 1u);  // w[k] or +0
        double x;
        std::memcpy(&x, &bits, sizeof x);
        sum += x;
    }
    return sum;
}

// ∫ cosθ·dω over the window rectangle [u0, u1] × [v0, v1] of `grid`'s
// frustum: the integral of SampleGrid::weights' w du dv, in closed form
// (Lambert's, in camera coordinates, where the receiver's normal is
// (nx, ny, nz) and the window lies at depth 1). The rectangle must lie above
// the receiver's horizon, as the light's pieces do.
double windowRectangleWeight(const SampleGrid& grid, double u0, double u1, double v0, double v1) {
    const std::vector<Vec3> local = {Vec3(0.0), Vec3(u1 - u0, 0.0, 0.0), Vec3(u1 - u0, v1 - v0, 0.0),
                                     Vec3(0.0, v1 - v0, 0.0)};
    return std::abs(signedCosineSolidAngle(Vec3(grid.nx, grid.ny, grid.nz), Vec3(u0, v0, 1.0), local));
}

// Pixels per side of the blocks that textureCorrection draws one sample from.
constexpr int kCorrectionBlock = 4;

}  // namespace

Rgb texturedIrradiance(const Rgb& radiance, bool controlVariate, double exactUnoccluded, double lightWeight,
                       const Rgb& texturedLight, const Rgb& texturedOccluded, bool anyVisible) {
    if (!controlVariate) return radiance * glm::max(texturedLight - texturedOccluded, Rgb(0.0));
    if (!anyVisible) return Rgb(0.0);
    return radiance * glm::max(exactUnoccluded + (texturedLight - Rgb(lightWeight)) - texturedOccluded, Rgb(0.0));
}

struct DirectLightSampler::Impl {
    const GlApi& gl;
    const Scene& scene;
    DirectSamplerSettings settings;
    bool phaseTiming = false;
    DirectPhaseTimes times;

    std::vector<EmitterTexture> emitters;  // per light: its emission texture, if any
    // Occluders with cut-outs (CutOuts): the MASKS variant of the coverage
    // pass tests them per sample; a scene without any compiles MASKS 0.
    bool masks = false;
    GlBuffer maskFaces, maskImages;
    Vec3 origin;        // occluder positions are stored relative to this
    double sceneSize;   // bounding diagonal
    OccluderBvh bvh;
    size_t maxLightTriangles = 0;
    // The triangles in the BVH's leaf order (double, as culled) and 1 + the
    // index of the light each belongs to (0: none), as in the GPU buffer.
    std::vector<Triangle3> leafTriangles;
    std::vector<uint32_t> leafLightId;
    std::unique_ptr<OccluderPolygons> polygons;  // for pairs in umbra (OccluderPolygons.h)
    std::unique_ptr<CpuCoverage> cpuCoverage;    // for pairs with few occluders (CpuCoverage.h)

    GlProgram coverage;
    GlBuffer occluderBuffer;
    GlVertexArray emptyVao;  // vertices are pulled from the buffers
    // Where one sampling image is drawn. sample() uses the first; a batch
    // draws into several before reading any back, each with a light buffer
    // of its own so that no upload waits for an earlier image's draw. All
    // alike, so an image's bits do not depend on which one it went to.
    struct Target {
        GlTexture visibleBits, lightBits, depth;
        GlFramebuffer fbo;
        GlBuffer lightBuffer;
    };
    std::vector<Target> targets;
    GlQuery queryLight, queryVisible;
    struct {
        GLint clipFromLocal, lightPlane, nearPlane, pixelNdc, cullBackFaces, skipLightId, clipToLightPlane,
            planeTolerance, seed, imageSize, horizonPlane;
    } loc{};

    // What culling leaves in one frustum.
    struct FrustumCull {
        std::vector<OccluderBvh::Range> ranges;  // drawn when the frustum is rasterised
        uint32_t drawn = 0;                      // triangles in `ranges`
        bool occluders = false;                  // whether any of them can hide a sample
    };

    // Scratch, reused between samples.
    std::vector<OccluderBvh::Plane> planes;  // of the volume being culled
    std::vector<GLint> firsts;
    std::vector<GLsizei> counts;
    std::vector<uint32_t> visiblePixels, lightPixels;
    std::vector<uint8_t> pixelClass;   // weighAnalytic's, per pixel of a row
    std::vector<Corner> lightCorners;  // of the image being drawn, in its target's light buffer
    GLuint lightBufferDrawn = 0;

    Impl(GlContext& ctx, const Scene& s, const DirectSamplerSettings& set)
        : Impl(ctx, s, set, allTriangles(s)) {}

    Impl(GlContext& ctx, const Scene& s, const DirectSamplerSettings& set, const std::vector<Triangle3>& tris)
        : gl(ctx.gl()), scene(s), settings(set), emitters(EmitterTexture::forLights(s)), origin(s.bounds.center()),
          sceneSize(std::max(s.bounds.diagonal(), 1e-300)), bvh(tris) {
        settings.validate();
        buildBuffers(tris);
        // One program variant per sampler: the bit count and jitter are
        // compile-time constants of the fragment stage.
        const bool jitterOn = settings.method == DirectMethod::Jittered;
        const int bits = jitterOn ? settings.bits : 1;
        int sx = 1, sy = 1;
        jitter::strata(bits, sx, sy);
        const std::string defines = concat("#define BITS ", bits, "\n#define STRATA_X ", sx,
                                           "\n#define STRATA_Y ", sy, "\n#define JITTER ",
                                           jitterOn ? "true" : "false", "\n#define MASKS ", masks ? 1 : 0, "\n");
        const std::string maskDefine = concat("#define MASKS ", masks ? 1 : 0, "\n");
        coverage = GlProgram(gl, {
            {GL_VERTEX_SHADER, "direct_coverage.vert", glslSource({maskDefine.c_str(), shaders::direct_coverage_vert})},
            {GL_FRAGMENT_SHADER, "direct_coverage.frag",
             glslSource({defines.c_str(), shaders::common_jitter_glsl, shaders::direct_coverage_frag})},
        });
        const GlProgram& p = coverage;
        loc = {p.uniform("uClipFromLocal"), p.uniform("uLightPlane"),     p.uniform("uNear"),
               p.uniform("uPixelNdc"),      p.uniform("uCullBackFaces"),  p.uniform("uSkipLightId"),
               p.uniform("uClipToLightPlane"), p.uniform("uPlaneTolerance"), p.uniform("uSeed"),
               p.uniform("uImageSize"),     p.uniform("uHorizonPlane")};
        addTargets(1);
        queryLight = makeQuery(gl, GL_SAMPLES_PASSED);
        queryVisible = makeQuery(gl, GL_SAMPLES_PASSED);
        checkGl(gl, "creating the direct-light sampler");
    }

    static std::vector<Triangle3> allTriangles(const Scene& s) {
        std::vector<Triangle3> tris;
        tris.reserve(s.triangleCount());
        for (const Mesh& m : s.meshes)
            for (size_t t = 0; t < m.triangles.size(); ++t) tris.push_back(m.triangle(t));
        return tris;
    }

    void buildBuffers(const std::vector<Triangle3>& tris) {
        // Which light (if any) each triangle belongs to, in scene order.
        std::vector<uint32_t> lightOf;
        std::vector<size_t> meshStart;
        for (const Mesh& m : scene.meshes) {
            meshStart.push_back(lightOf.size());
            lightOf.resize(lightOf.size() + m.triangles.size(), 0);
        }
        for (size_t l = 0; l < scene.lights.size(); ++l) {
            const Light& light = scene.lights[l];
            for (uint32_t t : light.triangles) lightOf[meshStart[light.mesh] + t] = uint32_t(l + 1);
            maxLightTriangles = std::max(maxLightTriangles, light.triangles.size());
        }
        // Each triangle's cut-out record, in scene order (the order of `tris`).
        CutOuts cutOuts;
        std::vector<uint32_t> maskOf;
        maskOf.reserve(tris.size());
        for (const Mesh& m : scene.meshes)
            for (size_t t = 0; t < m.triangles.size(); ++t) maskOf.push_back(cutOuts.add(scene, m, t));
        std::vector<Corner> corners;
        corners.reserve(tris.size() * 3);
        leafTriangles.reserve(tris.size());
        leafLightId.reserve(tris.size());
        std::vector<uint32_t> polygonId;  // leafLightId, with faces that may have holes marked
        for (uint32_t index : bvh.order()) {
            int k = 0;
            for (const Vec3& p : tris[index]) {
                const glm::vec3 r(p - origin);
                corners.push_back({r.x, r.y, r.z, k == 1 ? maskOf[index] : lightOf[index]});
                ++k;
            }
            leafTriangles.push_back(tris[index]);
            leafLightId.push_back(lightOf[index]);
            polygonId.push_back(maskOf[index] && !lightOf[index] ? OccluderPolygons::kHoled : lightOf[index]);
        }
        polygons = std::make_unique<OccluderPolygons>(leafTriangles, polygonId);
        cpuCoverage = std::make_unique<CpuCoverage>(leafTriangles, polygonId);
        masks = !cutOuts.faces.empty();
        if (masks) {
            cutOuts.finish();
            maskFaces = makeBuffer(gl, cutOuts.faces.size() * sizeof(glm::vec4), cutOuts.faces.data());
            maskImages = makeBuffer(gl, cutOuts.images.size() * sizeof(uint32_t), cutOuts.images.data());
        }
        occluderBuffer = makeBuffer(gl, std::max<size_t>(corners.size(), 1) * sizeof(Corner), corners.data());
        emptyVao = makeVertexArray(gl);
    }

    // Targets up to `count` (their textures are made once, then kept).
    void addTargets(size_t count) {
        const int n = settings.imageSize;
        while (targets.size() < count) {
            Target t;
            t.visibleBits = makeTexture2D(gl, GL_R32UI, n, n);
            t.lightBits = makeTexture2D(gl, GL_R32UI, n, n);
            t.depth = makeTexture2D(gl, GL_DEPTH_COMPONENT32F, n, n);
            t.fbo = makeFramebuffer(gl, {t.visibleBits.id(), t.lightBits.id()}, t.depth.id(), "direct-light sampler");
            t.lightBuffer = makeBuffer(gl, std::max<size_t>(maxLightTriangles * 3, 1) * sizeof(Corner), nullptr,
                                       GL_STREAM_DRAW);
            targets.push_back(std::move(t));
        }
        visiblePixels.resize(size_t(n) * n);
        lightPixels.resize(size_t(n) * n);
    }

    // The control variate on a planar light needs only the occluded samples
    // on the light. The light's projection is known exactly, so only the
    // occluders are rasterised; which samples lie on the light is decided on
    // the CPU (weighAnalytic), at the same jittered points.
    bool analyticLight(const Light& light) const {
        return settings.method != DirectMethod::OcclusionQuery && light.planar &&
               settings.estimator == DirectEstimator::ControlVariate;
    }

    // --- culling --------------------------------------------------------------

    // Potential occluders of frustum `f` into `out`: its leaves of the BVH
    // (all triangles without cullOccluders) and, where `refine`, whether any
    // of their triangles can hide a sample of the light's `pieces`.
    void cullFrustum(const Light& light, size_t lightIndex, const SamplingFrustum& f,
                     const std::vector<Polygon3>& pieces, const Vec3& n, double nearDistance, bool refine,
                     FrustumCull& out) {
        // Inside the frustum and in front of the light.
        planes = {{f.right - f.left * f.forward, 0}, {f.rightEdge * f.forward - f.right, 0},
                  {f.up - f.bottom * f.forward, 0},  {f.top * f.forward - f.up, 0},
                  {f.forward, -nearDistance}};
        for (auto& p : planes) p.d += -glm::dot(p.n, f.eye);
        // Nothing wholly below the receiver's horizon can hide a direction above it.
        planes.push_back({n, -glm::dot(n, f.eye)});
        if (light.planar) {
            const double tol = settings.planeTolerance * sceneSize;
            planes.push_back({light.normal, -glm::dot(light.normal, light.centroid) - tol});
        } else {
            double farthest = 0;
            for (const Triangle3& t : light.geometry)
                for (const Vec3& p : t) farthest = std::max(farthest, glm::dot(p - f.eye, f.forward));
            planes.push_back({-f.forward, glm::dot(f.forward, f.eye) + farthest});
        }
        if (settings.cullOccluders) out.drawn = bvh.cull(planes, out.ranges);
        else {
            out.ranges.assign(1, {0, uint32_t(bvh.triangleCount())});
            out.drawn = uint32_t(bvh.triangleCount());
        }
        out.occluders = out.drawn > 0;
        if (!refine || !out.occluders) return;
        // Only what lies between the eye and the light can hide it: per
        // piece, the frustum's volume narrowed to the pyramid from the eye
        // through the piece's edges. (The frustum's rectangular window holds
        // more: from off to the side of the bench's light, its corners reach
        // the occluder while the light's image does not.)
        const size_t frustumPlanes = planes.size();
        out.occluders = false;
        for (const Polygon3& piece : pieces) {
            planes.resize(frustumPlanes);
            addPyramidPlanes(piece, f.eye);
            if (anyOccluderIn(out.ranges, planes, lightIndex)) {
                out.occluders = true;
                break;
            }
        }
        planes.resize(frustumPlanes);
    }

    // Appends to `planes` those through `eye` and each edge of the convex
    // polygon `piece`, facing in. None when the eye is too near the piece's
    // plane for their orientation to be sure: the volume is then the
    // frustum's (more is rasterised, nothing is missed).
    void addPyramidPlanes(const Polygon3& piece, const Vec3& eye) {
        Vec3 centre(0.0);
        for (const Vec3& p : piece) centre += p;
        centre /= double(piece.size());
        const size_t first = planes.size();
        for (size_t i = 0; i < piece.size(); ++i) {
            const Vec3 a = piece[i] - eye, b = piece[(i + 1) % piece.size()] - eye;
            Vec3 m = glm::cross(a, b);
            const double side = glm::dot(m, centre - eye);
            if (!(std::abs(side) > 1e-9 * glm::length(m) * glm::length(centre - eye))) {
                planes.resize(first);
                return;
            }
            if (side < 0) m = -m;
            planes.push_back({m, -glm::dot(m, eye)});
        }
    }

    // Whether a triangle of `rs` has a part of positive area inside
    // `volume` (touching counts), other than a face of light `lightIndex`
    // (the shader skips those). The BVH keeps whole leaves of up to 16
    // triangles (the bench's six are one leaf, the Cornell box's 32 two), so
    // its answer alone is seldom "nothing"; a triangle outside the volume
    // covers no sample. Exact in double; stops at the first one found.
    bool anyOccluderIn(const std::vector<OccluderBvh::Range>& rs, const std::vector<OccluderBvh::Plane>& volume,
                       size_t lightIndex) const {
        const uint32_t skip = uint32_t(lightIndex + 1);
        for (const OccluderBvh::Range& r : rs)
            for (uint32_t i = r.first; i < r.first + r.count; ++i) {
                if (leafLightId[i] == skip) continue;
                const Triangle3& t = leafTriangles[i];
                bool outside = false;  // all corners outside one plane: the common case, no clipping
                for (const OccluderBvh::Plane& p : volume)
                    if (glm::dot(p.n, t[0]) + p.d < 0 && glm::dot(p.n, t[1]) + p.d < 0 &&
                        glm::dot(p.n, t[2]) + p.d < 0) {
                        outside = true;
                        break;
                    }
                if (outside) continue;
                Polygon3 poly{t[0], t[1], t[2]};
                for (const OccluderBvh::Plane& p : volume) {
                    poly = clipPolygon(poly, p.n, p.d);
                    if (poly.empty()) break;
                }
                if (!poly.empty()) return true;
            }
        return false;
    }

    // --- one sampling image -------------------------------------------------

    struct ImageResult {
        double lightWeight = 0;     // Σ weights of samples on the light
        double occludedWeight = 0;  // Σ weights of those that are occluded
        // A textured light's (EmitterTexture.h, τ = L / L̄ at a sample):
        // Σ w·τ over the samples on the light, estimated as lightWeight +
        // textureCorrection (lightWeight 0 where the closed form stands in
        // for it), and Σ w·τ over the occluded ones, each weighed.
        Rgb texturedLight{0.0}, texturedOccluded{0.0};
        uint32_t lightSamples = 0, visibleSamples = 0;
    };

    // Off-axis projection with z_clip = near and w = d (reversed, infinite
    // depth: z_ndc = near / d in [0, 1] with glClipControl zero-to-one).
    static Mat4 projection(const SamplingFrustum& f, double nearDistance) {
        const double a = 2.0 / (f.rightEdge - f.left), c = -(f.rightEdge + f.left) / (f.rightEdge - f.left);
        const double b = 2.0 / (f.top - f.bottom), d = -(f.top + f.bottom) / (f.top - f.bottom);
        Mat4 p(0.0);  // column-major: p[col][row]
        p[0][0] = a;
        p[2][0] = c;
        p[1][1] = b;
        p[2][1] = d;
        p[3][2] = nearDistance;
        p[2][3] = 1.0;
        return p;
    }
    // Camera coordinates (x, y, d) from coordinates relative to `from`.
    static Mat4 viewFrom(const SamplingFrustum& f, const Vec3& from) {
        Mat4 v(1.0);
        for (int col = 0; col < 3; ++col) {
            v[col][0] = f.right[col];
            v[col][1] = f.up[col];
            v[col][2] = f.forward[col];
        }
        const Vec3 t = from - f.eye;
        v[3][0] = glm::dot(f.right, t);
        v[3][1] = glm::dot(f.up, t);
        v[3][2] = glm::dot(f.forward, t);
        return v;
    }

    SampleGrid gridFor(const SamplingFrustum& f, const Vec3& n, uint32_t seed) const {
        const bool jitter = settings.method == DirectMethod::Jittered;
        return SampleGrid(f, settings.imageSize, n, seed, jitter ? settings.bits : 1, jitter);
    }
    int bitsPerPixel() const { return settings.method == DirectMethod::Jittered ? settings.bits : 1; }

    // An image of an analytic light with no occluder in it: no sample is
    // occluded, so only the samples on the light are counted, with no GL.
    ImageResult weighUnoccluded(const SamplingFrustum& f, const std::vector<Polygon3>& pieces, const Vec3& n,
                                uint32_t seed, const EmitterTexture& texture) {
        ImageResult out;
        weighAnalytic(f, pieces, gridFor(f, n, seed), bitsPerPixel(), nullptr, texture, out);
        return out;
    }

    // Σ w (τ − 1) over a textured light's samples in frustum `f`, estimated
    // from one sample per block of kCorrectionBlock² pixels, its pixel and
    // bit drawn by a hash of the frustum's seed and the block, weighed for
    // the block's every sample: unbiased (each of them is equally likely),
    // at 1/(16 × bits) of the cost of reading the texture at all of them
    // (1.1 ms a pair at 64², 8 bits). `onLight(pixel, bit, u, v)`: whether
    // that sample, at window point (u, v), lies on the light.
    template <class OnLight>
    Rgb textureCorrection(const SamplingFrustum& f, const SampleGrid& grid, int bits, const EmitterTexture& texture,
                          const OnLight& onLight) const {
        const int size = settings.imageSize, b = kCorrectionBlock;
        double u[32], v[32], w[32];
        Rgb sum(0.0);
        for (int bj = 0; bj < size; bj += b)
            for (int bi = 0; bi < size; bi += b) {
                const int bw = std::min(b, size - bi), bh = std::min(b, size - bj);
                const uint32_t h = jitter::hash(grid.seed ^ (uint32_t(bj * size + bi) * 0x9e3779b9u + 0x7f4a7c15u));
                const int i = bi + int(h % uint32_t(bw)), j = bj + int((h >> 8) % uint32_t(bh));
                const int k = int((h >> 16) % uint32_t(bits));
                const uint32_t pixel = uint32_t(j * size + i);
                grid.points(i, j, pixel, u, v);
                if (!onLight(pixel, k, u[k], v[k])) continue;
                grid.weights(u, v, w);
                if (!(w[k] > 0)) continue;
                sum += double(bw * bh * bits) * w[k] * (texture.weightAlong(f.eye, f.direction(u[k], v[k])) - Rgb(1.0));
            }
        return sum * (grid.pw * grid.ph / bits);
    }

    // textureCorrection for a light known exactly on the window (analytic):
    // membership from its pieces, in double.
    Rgb analyticCorrection(const SamplingFrustum& f, const std::vector<Polygon3>& pieces, const SampleGrid& grid,
                           int bits, const EmitterTexture& texture) const {
        const std::vector<WindowPiece> light = windowPieces(f, pieces, grid.pw, grid.ph);
        return textureCorrection(f, grid, bits, texture, [&](uint32_t, int, double u, double v) {
            return onAnyPiece(light, u, v);
        });
    }

    // --- one pair -----------------------------------------------------------

    // A pair (receiver, light) on its way through the sampler: what setup
    // found, then each frustum's image. A batch keeps its pairs whole until
    // every image is drawn, read back and weighed.
    struct Pair {
        size_t request = 0;  // its index in a batch
        size_t lightIndex = 0;
        Vec3 x{0.0}, n{0.0};  // receiver and unit normal
        uint32_t seed = 0;
        std::vector<Polygon3> pieces;
        std::vector<SamplingFrustum> frusta;
        std::vector<FrustumCull> culls;   // per frustum
        std::vector<ImageResult> images;  // per frustum, summed in frustum order by finishPair
        double exactUnoccluded = 0, nearDistance = 0;
        bool cpuFrusta = false;  // frusta with no occluder are weighed on the CPU
        DirectSample result;

        uint32_t frustumSeed(size_t k) const { return jitter::hash(seed + uint32_t(k) * 0x9e3779b9u); }
    };

    // Draws frustum `k` of `p` into target `slot`: its light (unless
    // analytic) and its occluders, with no wait for the GPU.
    void drawImage(Pair& p, size_t k, size_t slot, Clock::time_point& t0) {
        const Light& light = scene.lights[p.lightIndex];
        const SamplingFrustum& f = p.frusta[k];
        const FrustumCull& cull = p.culls[k];
        const Target& target = targets[slot];
        const int size = settings.imageSize;
        const bool planar = light.planar;
        const bool analytic = analyticLight(light);
        const double tol = settings.planeTolerance * sceneSize;

        p.result.trianglesDrawn += cull.drawn;
        firsts.clear();
        counts.clear();
        for (const auto& r : cull.ranges) {  // six vertices (a quad) per triangle
            firsts.push_back(GLint(r.first * 6));
            counts.push_back(GLsizei(r.count * 6));
        }

        // The light in camera coordinates, computed in double, then to
        // float. The frustum's axis runs through the light, so its corners'
        // x and y keep digits relative to the light's own extent: a light
        // 1e-5 wide, or a tiny light far away, keeps its shape. (Relative to
        // the eye in world axes, float rounding of the distance, 6e-8 of it,
        // moved the edges of a light 1e-5 wide by up to 1 % of its width:
        // the plain estimator's mean was 0.2 % off.)
        lightCorners.clear();
        lightBufferDrawn = target.lightBuffer.id();
        if (!analytic) {
            for (const Triangle3& t : light.geometry)
                for (const Vec3& c : t) {
                    const glm::vec3 r(f.toCamera(c));
                    lightCorners.push_back({r.x, r.y, r.z, 0});
                }
            gl.NamedBufferSubData(target.lightBuffer.id(), 0, GLsizeiptr(lightCorners.size() * sizeof(Corner)),
                                  lightCorners.data());
        }

        const Mat4 proj = projection(f, p.nearDistance);
        const glm::mat4 clipFromCamera = toFloat(proj);
        const glm::mat4 clipFromOrigin = toFloat(proj * viewFrom(f, origin));
        // Light plane in origin-relative coordinates, positive on the eye's side.
        const glm::vec4 plane(glm::vec3(light.normal), float(glm::dot(light.normal, origin - light.centroid)));

        gl.BindFramebuffer(GL_FRAMEBUFFER, target.fbo.id());
        gl.Viewport(0, 0, size, size);
        // Reversed depth in [0, 1]: float depth keeps its precision at every
        // distance, so occluders 1e-4 in front of a light still win. Set per
        // image: other passes share the context.
        gl.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
        gl.Enable(GL_DEPTH_CLAMP);
        gl.Disable(GL_CULL_FACE);
        gl.Disable(GL_BLEND);
        // Clears obey the write masks: open them all first.
        gl.DepthMask(GL_TRUE);
        gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        gl.ColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        const GLuint zero[4] = {0, 0, 0, 0};
        const GLuint ones[4] = {~0u, ~0u, ~0u, ~0u};
        gl.ClearBufferuiv(GL_COLOR, 0, analytic ? ones : zero);
        gl.ClearBufferuiv(GL_COLOR, 1, zero);
        const float depthClear = 0.0f;  // reversed depth: 0 is infinitely far
        gl.ClearBufferfv(GL_DEPTH, 0, &depthClear);

        coverage.use();
        gl.BindVertexArray(emptyVao.id());
        gl.Uniform1f(loc.nearPlane, float(p.nearDistance));
        gl.Uniform1f(loc.pixelNdc, 2.0f / float(size));
        gl.Uniform1f(loc.planeTolerance, float(tol));
        gl.Uniform1ui(loc.seed, p.frustumSeed(k));
        gl.Uniform1i(loc.imageSize, size);
        gl.Uniform4f(loc.lightPlane, plane.x, plane.y, plane.z, plane.w);
        const glm::vec4 horizon(glm::vec3(p.n), float(glm::dot(p.n, origin - f.eye)));
        gl.Uniform4f(loc.horizonPlane, horizon.x, horizon.y, horizon.z, horizon.w);
        const Clock::time_point t1 = Clock::now();
        times.setup += seconds(t0, t1);

        if (settings.method == DirectMethod::OcclusionQuery)
            renderQuery(p.lightIndex, clipFromCamera, clipFromOrigin, planar, p.images[k]);
        else
            renderBits(p.lightIndex, clipFromCamera, clipFromOrigin, planar, analytic);
        t0 = Clock::now();
        if (phaseTiming && settings.method != DirectMethod::OcclusionQuery) {
            gl.Finish();
            t0 = Clock::now();
        }
        times.draw += seconds(t1, t0);
    }

    // Reads target `slot` back and weighs it as frustum `k` of `p`.
    void readAndWeigh(Pair& p, size_t k, size_t slot, Clock::time_point& t0) {
        const Light& light = scene.lights[p.lightIndex];
        const int size = settings.imageSize;
        const bool analytic = analyticLight(light);
        const GLuint fbo = targets[slot].fbo.id();
        gl.NamedFramebufferReadBuffer(fbo, GL_COLOR_ATTACHMENT0);
        gl.BindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
        gl.ReadPixels(0, 0, size, size, GL_RED_INTEGER, GL_UNSIGNED_INT, visiblePixels.data());
        if (!analytic) {
            gl.NamedFramebufferReadBuffer(fbo, GL_COLOR_ATTACHMENT1);
            gl.ReadPixels(0, 0, size, size, GL_RED_INTEGER, GL_UNSIGNED_INT, lightPixels.data());
        }
        const Clock::time_point t1 = Clock::now();
        times.readback += seconds(t0, t1);

        const SampleGrid grid = gridFor(p.frusta[k], p.n, p.frustumSeed(k));
        ImageResult& out = p.images[k];
        const EmitterTexture& texture = emitters[p.lightIndex];
        if (analytic)
            weighAnalytic(p.frusta[k], p.pieces, grid, bitsPerPixel(), visiblePixels.data(), texture, out);
        else
            weigh(p.frusta[k], grid, bitsPerPixel(), light.planar, visiblePixels.data(), lightPixels.data(), texture,
                  out);
        t0 = Clock::now();
        times.weighting += seconds(t1, t0);
    }

    void setPassState(bool lightPass, bool planar, size_t lightIndex, const glm::mat4& clipFrom) {
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, lightPass ? lightBufferDrawn : occluderBuffer.id());
        if (masks) {
            gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, maskFaces.id());
            gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, maskImages.id());
        }
        gl.UniformMatrix4fv(loc.clipFromLocal, 1, GL_FALSE, &clipFrom[0][0]);
        gl.Uniform1i(loc.cullBackFaces, lightPass ? 1 : 0);
        gl.Uniform1ui(loc.skipLightId, lightPass ? 0u : uint32_t(lightIndex + 1));
        gl.Uniform1i(loc.clipToLightPlane, !lightPass && planar ? 1 : 0);
    }

    void drawLight() { gl.DrawArrays(GL_TRIANGLES, 0, GLsizei(lightCorners.size() * 2)); }

    void drawOccluders() {
        if (!counts.empty())
            gl.MultiDrawArrays(GL_TRIANGLES, firsts.data(), counts.data(), GLsizei(counts.size()));
    }

    // §4.1.2 / §4.2: light with OR_INVERTED into both images, occluders with
    // AND into the first (an image of ones when the light is analytic). A
    // planar light needs no depth test (occluders are clipped to its plane
    // exactly, per sample); another needs one.
    void renderBits(size_t lightIndex, const glm::mat4& clipFromCamera, const glm::mat4& clipFromOrigin,
                    bool planar, bool analytic) {
        if (!analytic) drawLightBits(lightIndex, clipFromCamera, planar);
        if (planar) gl.Disable(GL_DEPTH_TEST);
        else gl.Enable(GL_DEPTH_TEST);  // occluders must lie in front of the light
        gl.DepthMask(GL_FALSE);
        gl.Enable(GL_COLOR_LOGIC_OP);
        gl.LogicOp(GL_AND);
        gl.ColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
        setPassState(false, planar, lightIndex, clipFromOrigin);
        drawOccluders();
        gl.ColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        gl.Disable(GL_COLOR_LOGIC_OP);
    }

    void drawLightBits(size_t lightIndex, const glm::mat4& clipFromCamera, bool planar) {
        setPassState(true, planar, lightIndex, clipFromCamera);
        if (!planar) {
            // The nearest light surface's depth first, on its own: were the
            // light's samples drawn with the depth test, a triangle behind
            // another at a pixel's centre would lose its samples along their
            // shared edge. Its samples then go in as a union, untested.
            gl.Enable(GL_DEPTH_TEST);
            gl.DepthFunc(GL_GREATER);
            gl.DepthMask(GL_TRUE);
            gl.ColorMaski(0, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
            gl.ColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
            drawLight();
            gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
            gl.ColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        }
        gl.Disable(GL_DEPTH_TEST);
        gl.DepthMask(GL_FALSE);
        gl.Enable(GL_COLOR_LOGIC_OP);
        gl.LogicOp(GL_OR_INVERTED);
        drawLight();
    }

    // §4.1.1: two occlusion queries, the light alone and the light behind
    // the occluders; the visible fraction scales the exact unoccluded value.
    void renderQuery(size_t lightIndex, const glm::mat4& clipFromCamera, const glm::mat4& clipFromOrigin,
                     bool planar, ImageResult& out) {
        gl.ColorMaski(0, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
        gl.ColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
        gl.Disable(GL_DEPTH_TEST);
        setPassState(true, planar, lightIndex, clipFromCamera);
        gl.BeginQuery(GL_SAMPLES_PASSED, queryLight.id());
        drawLight();
        gl.EndQuery(GL_SAMPLES_PASSED);

        gl.Enable(GL_DEPTH_TEST);
        gl.DepthFunc(GL_GREATER);
        gl.DepthMask(GL_TRUE);
        setPassState(false, planar, lightIndex, clipFromOrigin);
        drawOccluders();
        gl.DepthMask(GL_FALSE);
        setPassState(true, planar, lightIndex, clipFromCamera);
        gl.BeginQuery(GL_SAMPLES_PASSED, queryVisible.id());
        drawLight();
        gl.EndQuery(GL_SAMPLES_PASSED);
        gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        gl.ColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        gl.Disable(GL_DEPTH_TEST);

        const Clock::time_point t = Clock::now();
        GLuint all = 0, visible = 0;
        gl.GetQueryObjectuiv(queryLight.id(), GL_QUERY_RESULT, &all);
        gl.GetQueryObjectuiv(queryVisible.id(), GL_QUERY_RESULT, &visible);
        times.readback += seconds(t, Clock::now());
        out.lightSamples = all;
        out.visibleSamples = std::min(visible, all);
    }

    // Σ over samples of cosθ·dω, evaluated at each sample's own jittered
    // point. In camera coordinates the direction through window point (u, v)
    // is (u, v, 1), so cosθ·dω/dA = (n·s)/|s|⁴ with |s|² = 1 + u² + v² (eq. 3).
    void weigh(const SamplingFrustum& f, const SampleGrid& grid, int bits, bool planar, const uint32_t* visiblePx,
               const uint32_t* lightPx, const EmitterTexture& texture, ImageResult& out) const {
        const int size = settings.imageSize;
        // The control variate needs only the occluded samples' weights; the
        // plain estimator needs every light sample's.
        const bool onlyOccluded = settings.estimator == DirectEstimator::ControlVariate && planar;
        double lightSum = 0, occludedSum = 0;
        double u[32], v[32], w[32];
        for (int j = 0; j < size; ++j) {
            for (int i = 0; i < size; ++i) {
                const uint32_t pixel = uint32_t(j * size + i);
                const uint32_t onLight = lightPx[pixel];
                if (!onLight) continue;
                const uint32_t visible = visiblePx[pixel] & onLight;
                out.lightSamples += bitCount(onLight);
                out.visibleSamples += bitCount(visible);
                const uint32_t toWeigh = onlyOccluded ? (onLight & ~visible) : onLight;
                if (!toWeigh) continue;
                grid.points(i, j, pixel, u, v);
                grid.weights(u, v, w);
                lightSum = addMasked(lightSum, w, toWeigh, grid.count);
                occludedSum = addMasked(occludedSum, w, toWeigh & ~visible, grid.count);
            }
        }
        const double sampleArea = grid.pw * grid.ph / bits;
        out.lightWeight = lightSum * sampleArea;
        out.occludedWeight = occludedSum * sampleArea;
        if (texture.textured()) {
            out.texturedLight = Rgb(out.lightWeight) +
                                textureCorrection(f, grid, bits, texture, [&](uint32_t pixel, int k, double, double) {
                                    return (lightPx[pixel] >> k & 1u) != 0;
                                });
            out.texturedOccluded =
                Rgb(out.occludedWeight) +
                textureCorrection(f, grid, bits, texture, [&](uint32_t pixel, int k, double, double) {
                    return (lightPx[pixel] >> k & 1u) != 0 && (visiblePx[pixel] >> k & 1u) == 0;
                });
        }
    }

    // The control variate's weighting when only occluders were rasterised:
    // which samples lie on the light is decided here, at the same jittered
    // points, exactly (double precision). Whole pixels are classified from
    // their centre ± reach (edge functions are affine), so only pixels on the
    // light's outline test single samples. `visible`: the occluder pass's
    // bits per pixel (a sample is occluded where its bit is 0); null when no
    // occluder lies in the frustum. A textured light's corrections for τ, to
    // the closed form and to the occluded weight, are textureCorrection's,
    // from the same block samples: where a block is all in shadow they
    // cancel, as the light it hides does.
    void weighAnalytic(const SamplingFrustum& f, const std::vector<Polygon3>& pieces, const SampleGrid& grid,
                       int bits, const uint32_t* visible, const EmitterTexture& texture, ImageResult& out) {
        const int size = settings.imageSize;
        const double pw = grid.pw, ph = grid.ph;
        const uint32_t allBits = bits >= 32 ? ~0u : ((1u << bits) - 1u);
        const std::vector<WindowPiece> light = windowPieces(f, pieces, pw, ph);
        std::vector<WindowPiece::Span> spans(light.size());
        pixelClass.resize(size_t(size));
        double occludedSum = 0, occludedExact = 0;
        double u[32], v[32], w[32];
        // A run of pixels wholly on the light whose every sample is
        // occluded (the inside of an occluder's shadow on the window): the
        // mean of their jittered weights' sum is the exact integral of the
        // weight over them, which Lambert's form gives for the run's
        // rectangle at once. Unbiased as the samples were, without their
        // noise, and one closed form instead of a hash and a weight per
        // sample (in the office most occluded samples are such).
        int runStart = -1;
        auto closeRun = [&](int j, int end) {
            if (runStart < 0) return;
            occludedExact += windowRectangleWeight(grid, f.left + runStart * pw, f.left + end * pw,
                                                   f.bottom + j * ph, f.bottom + (j + 1) * ph);
            runStart = -1;
        };
        for (int j = 0; j < size; ++j) {
            const double vc = f.bottom + (j + 0.5) * ph;
            int rowLo = size, rowHi = -1;
            for (size_t k = 0; k < light.size(); ++k) {
                const WindowPiece::Span sp = light[k].rowSpan(f.left, pw, vc, size);
                spans[k] = sp;
                if (sp.anyLo <= sp.anyHi) {
                    rowLo = std::min(rowLo, sp.anyLo);
                    rowHi = std::max(rowHi, sp.anyHi);
                }
            }
            // Per pixel of the row: 0 off the light, 1 on its outline, 2 wholly on it.
            if (rowLo > rowHi) continue;
            std::fill(pixelClass.begin() + rowLo, pixelClass.begin() + rowHi + 1, uint8_t(0));
            for (const WindowPiece::Span& sp : spans) {
                for (int i = sp.anyLo; i <= sp.anyHi; ++i) pixelClass[i] = std::max<uint8_t>(pixelClass[i], 1);
                for (int i = sp.fullLo; i <= sp.fullHi; ++i) pixelClass[i] = 2;
            }
            const uint32_t* visibleRow = visible ? visible + size_t(j) * size : nullptr;
            for (int i = rowLo; i <= rowHi; ++i) {
                const uint32_t pixel = uint32_t(j * size + i);
                uint32_t onLight = allBits;
                if (pixelClass[i] == 2) {
                    // Wholly on the light (most pixels): no test, and most of
                    // them have no occluded sample either.
                    const uint32_t occluded = visibleRow ? allBits & ~visibleRow[i] : 0u;
                    out.lightSamples += uint32_t(bits);
                    out.visibleSamples += uint32_t(bits) - bitCount(occluded);
                    if (occluded == allBits) {
                        if (runStart < 0) runStart = i;
                        continue;
                    }
                    closeRun(j, i);
                    if (!occluded) continue;
                    grid.points(i, j, pixel, u, v);
                    grid.weights(u, v, w);
                    occludedSum = addMasked(occludedSum, w, occluded, bits);
                    continue;
                }
                closeRun(j, i);
                if (pixelClass[i] == 0) continue;
                grid.points(i, j, pixel, u, v);
                onLight = 0;
                for (int k = 0; k < bits; ++k)
                    for (const WindowPiece& wp : light)
                        if (wp.contains(u[k], v[k])) {
                            onLight |= 1u << k;
                            break;
                        }
                const uint32_t occluded = visibleRow ? onLight & ~visibleRow[i] : 0u;
                out.lightSamples += bitCount(onLight);
                out.visibleSamples += bitCount(onLight & ~occluded);
                if (!occluded) continue;
                grid.weights(u, v, w);
                occludedSum = addMasked(occludedSum, w, occluded, bits);
            }
            closeRun(j, rowHi + 1);
        }
        const double sampleArea = pw * ph / bits;
        out.occludedWeight = occludedSum * sampleArea + occludedExact;
        if (!texture.textured()) return;
        out.texturedLight = analyticCorrection(f, pieces, grid, bits, texture);  // lightWeight stays 0
        out.texturedOccluded =
            Rgb(out.occludedWeight) +
            textureCorrection(f, grid, bits, texture, [&](uint32_t pixel, int k, double uk, double vk) {
                return visible && (visible[pixel] >> k & 1u) == 0 && onAnyPiece(light, uk, vk);
            });
    }

    // Setup of one pair: its frusta and their culls, or, where it needs no
    // GL (unlit, no occluder in any frustum, in umbra, or with `cover` few
    // occluders: CpuCoverage), its answer. True when answered; `p.result`
    // then holds it.
    bool planPair(Pair& p, size_t lightIndex, const Vec3& x, const Vec3& nIn, uint32_t seed, bool cover) {
        ML_ASSERT(lightIndex < scene.lights.size(), "light ", lightIndex);
        const Clock::time_point start = Clock::now();
        p.lightIndex = lightIndex;
        p.x = x;
        p.seed = seed;
        p.result = DirectSample();
        const Light& light = scene.lights[lightIndex];
        const Vec3 n = glm::normalize(nIn);
        p.n = n;
        if (!isFinite(x) || !isFinite(n)) throw InputError(concat("non-finite receiver point or normal"));
        const double lift = samplingEyeLift(light, x, settings.eyeOffset, sceneSize);
        const Vec3 eye = x + n * lift;
        // Below the horizon or seen from behind: nothing, before any
        // frustum, culling or GL call.
        p.pieces = visibleLightPieces(light, eye, n);
        p.frusta.clear();
        if (!p.pieces.empty()) p.frusta = samplingFrusta(light, p.pieces, eye, settings.maxHalfAngleDegrees);
        if (p.frusta.empty()) {  // (no frustum: a sliver seen edge-on, no sample on it)
            p.result.path = DirectPath::Unlit;
            times.setup += seconds(start, Clock::now());
            return true;
        }
        // Lambert at the receiver itself, not the lifted eye: where nothing
        // occludes, the control variate is then exact, with no bias from the lift.
        const double exactUnoccluded = unoccludedCosineSolidAngle(light, x, n);
        p.exactUnoccluded = exactUnoccluded;
        p.result.frusta = uint32_t(p.frusta.size());

        // Occluders nearer than this to the eye are not drawn: half the eye's
        // lift, so only geometry touching the receiver there is lost.
        p.nearDistance = std::max(0.5 * lift, 1e-12 * sceneSize);
        // Culling first, for every frustum: where the light needs no
        // rasterising (analytic) a frustum with no occluder needs no GL.
        p.cpuFrusta = analyticLight(light) && settings.cpuUnoccludedPairs && settings.cullOccluders;
        p.culls.resize(p.frusta.size());
        bool anyOccluders = false;
        for (size_t k = 0; k < p.frusta.size(); ++k) {
            cullFrustum(light, lightIndex, p.frusta[k], p.pieces, n, p.nearDistance, p.cpuFrusta, p.culls[k]);
            anyOccluders = anyOccluders || p.culls[k].occluders;
        }

        if (p.cpuFrusta && !anyOccluders) {
            // Nothing between the receiver and the light: the control
            // variate subtracts nothing, so the estimate is Lambert's closed
            // form, exactly what the GPU would return. Unlike the GPU path,
            // which returns 0 when no sample falls on the light (a light
            // smaller than a sample's spacing, or a sliver seen edge-on),
            // this returns the exact value then too: that removes a bias.
            // No sample is tested, so lightSamples = visibleSamples = 0:
            // counting them (weighUnoccluded) would cost ~20× the rest of
            // the pair (55 us against 3 us on the Cornell box).
            p.result.unoccluded = exactUnoccluded;
            p.result.cosineSolidAngle = exactUnoccluded;
            p.result.irradiance = light.radiance * exactUnoccluded;
            const EmitterTexture& texture = emitters[lightIndex];
            if (texture.textured()) {
                // Lambert's form assumes the light's mean radiance
                // everywhere: samples on the light (on the CPU, still no
                // GL) add the texture's departure from it, Σ w (τ − 1),
                // unbiased but no longer exact (textureCorrection).
                Rgb correction(0.0);
                for (size_t k = 0; k < p.frusta.size(); ++k)
                    correction += analyticCorrection(p.frusta[k], p.pieces, gridFor(p.frusta[k], n, p.frustumSeed(k)),
                                                     bitsPerPixel(), texture);
                p.result.irradiance =
                    texturedIrradiance(light.radiance, true, exactUnoccluded, 0.0, correction, Rgb(0.0), true);
            }
            p.result.path = DirectPath::Unoccluded;
            times.setup += seconds(start, Clock::now());  // all of a CPU pair's time
            return true;
        }
        if (p.cpuFrusta && hiddenBehindOnePolygon(p, light, eye)) {
            // Every sample would be occluded: exactly zero, what the GPU
            // path gives a pair with no visible sample.
            p.result.unoccluded = exactUnoccluded;
            p.result.path = DirectPath::Occluded;
            times.setup += seconds(start, Clock::now());
            return true;
        }
        times.setup += seconds(start, Clock::now());
        if (cover && p.cpuFrusta && settings.cpuCoverageTriangles > 0 && coverOnCpu(p, light)) {
            p.result.path = DirectPath::CpuRasterised;
            finishPair(p);
            return true;
        }
        p.result.path = DirectPath::Rasterised;
        p.images.assign(p.frusta.size(), ImageResult());
        return false;
    }

    // Every frustum of a planned pair weighed without GL: those with
    // occluders from CpuCoverage's bits, in place of a drawn image. False
    // when one has too many occluders or one with a cut-out (the pair is
    // then rasterised whole: its images are made again).
    bool coverOnCpu(Pair& p, const Light& light) {
        p.images.assign(p.frusta.size(), ImageResult());
        CpuCoverage::Rules rules;
        rules.nearDistance = p.nearDistance;
        rules.lightNormal = light.normal;
        rules.lightPoint = light.centroid;
        rules.planeTolerance = settings.planeTolerance * sceneSize;
        rules.skipLightId = uint32_t(p.lightIndex + 1);
        const int size = settings.imageSize, bits = bitsPerPixel();
        Clock::time_point t0 = Clock::now();
        for (size_t k = 0; k < p.frusta.size(); ++k) {
            if (onCpu(p, k)) {
                weighOnCpu(p, k, t0);
                continue;
            }
            const SamplingFrustum& f = p.frusta[k];
            const SampleGrid grid = gridFor(f, p.n, p.frustumSeed(k));
            if (!cpuCoverage->prepare(f, p.culls[k].ranges, rules, grid.pw, grid.ph,
                                      size_t(settings.cpuCoverageTriangles))) {
                times.draw += seconds(t0, Clock::now());
                return false;
            }
            cpuCoverage->draw(f, size, bits, grid.pw, grid.ph,
                              [&](int i, int j, uint32_t pixel, double* u, double* v) { grid.points(i, j, pixel, u, v); },
                              visiblePixels.data());
            const Clock::time_point t1 = Clock::now();
            times.draw += seconds(t0, t1);
            weighAnalytic(f, p.pieces, grid, bits, visiblePixels.data(), emitters[p.lightIndex], p.images[k]);
            t0 = Clock::now();
            times.weighting += seconds(t1, t0);
        }
        return true;
    }

    // The light wholly behind one occluder polygon of the pair's frusta
    // (OccluderPolygons), by the sampler's own rules for what occludes.
    bool hiddenBehindOnePolygon(const Pair& p, const Light& light, const Vec3& eye) {
        OccluderPolygons::Rules rules;
        rules.eye = eye;
        rules.nearDistance = p.nearDistance;
        rules.lightNormal = light.normal;
        rules.lightPoint = light.centroid;
        rules.planeTolerance = settings.planeTolerance * sceneSize;
        rules.skipLightId = uint32_t(p.lightIndex + 1);
        for (const FrustumCull& c : p.culls)
            if (c.occluders && polygons->hideAll(p.pieces, c.ranges, rules)) return true;
        return false;
    }

    // Whether frustum `k` of a planned pair is weighed on the CPU alone: a
    // face of a split light with no occluder in it. Its samples are still
    // counted (weighUnoccluded), as the pair's visibleSamples (the
    // estimate's "no visible sample gives 0" rule and partiallyVisible)
    // must include them.
    static bool onCpu(const Pair& p, size_t k) { return p.cpuFrusta && !p.culls[k].occluders; }

    void weighOnCpu(Pair& p, size_t k, Clock::time_point& t0) {
        p.images[k] = weighUnoccluded(p.frusta[k], p.pieces, p.n, p.frustumSeed(k), emitters[p.lightIndex]);
        const Clock::time_point t = Clock::now();
        times.weighting += seconds(t0, t);
        t0 = t;
    }

    // The estimate of a rasterised pair from its images, summed in frustum order.
    void finishPair(Pair& p) {
        const Clock::time_point tw = Clock::now();
        const Light& light = scene.lights[p.lightIndex];
        DirectSample& result = p.result;
        double lightWeight = 0, occludedWeight = 0;
        Rgb texturedLight(0.0), texturedOccluded(0.0);
        for (const ImageResult& r : p.images) {
            lightWeight += r.lightWeight;
            occludedWeight += r.occludedWeight;
            texturedLight += r.texturedLight;
            texturedOccluded += r.texturedOccluded;
            result.lightSamples += r.lightSamples;
            result.visibleSamples += r.visibleSamples;
        }
        double e = 0;
        const bool controlVariate = settings.estimator == DirectEstimator::ControlVariate && light.planar;
        if (settings.method == DirectMethod::OcclusionQuery) {
            result.unoccluded = p.exactUnoccluded;
            e = result.lightSamples ? p.exactUnoccluded * result.visibleSamples / result.lightSamples : 0.0;
        } else if (controlVariate) {
            result.unoccluded = p.exactUnoccluded;
            // Unbiased difference; clamped at 0 where the sampled occluded
            // part exceeds the exact total (a point nearly in umbra).
            e = result.visibleSamples == 0 ? 0.0 : std::max(0.0, p.exactUnoccluded - occludedWeight);
        } else {
            result.unoccluded = lightWeight;
            e = lightWeight - occludedWeight;
        }
        result.cosineSolidAngle = e;
        result.irradiance = light.radiance * e;
        // A textured light weighs each sample by its radiance there. (The
        // occlusion query counts pixels, with no weights: it keeps the
        // light's mean radiance, a comparison scheme only.)
        if (emitters[p.lightIndex].textured() && settings.method != DirectMethod::OcclusionQuery)
            result.irradiance = texturedIrradiance(light.radiance, controlVariate, p.exactUnoccluded, lightWeight,
                                                   texturedLight, texturedOccluded, result.visibleSamples > 0);
        times.weighting += seconds(tw, Clock::now());
    }

    Pair single;  // sample()'s, reused

    DirectSample sample(size_t lightIndex, const Vec3& x, const Vec3& n, uint32_t seed) {
        times = {};
        Pair& p = single;
        if (planPair(p, lightIndex, x, n, seed, true)) return p.result;
        Clock::time_point t0 = Clock::now();
        for (size_t k = 0; k < p.frusta.size(); ++k) {
            if (onCpu(p, k)) {
                weighOnCpu(p, k, t0);
                continue;
            }
            drawImage(p, k, 0, t0);
            if (settings.method != DirectMethod::OcclusionQuery) readAndWeigh(p, k, 0, t0);
        }
        finishPair(p);
        checkGl(gl, "direct-light sampling");
        return p.result;
    }

    bool sampleWithoutGl(size_t lightIndex, const Vec3& x, const Vec3& n, uint32_t seed, DirectSample& out) {
        times = {};
        if (!planPair(single, lightIndex, x, n, seed, false)) return false;
        out = single.result;
        return true;
    }

    // --- batches --------------------------------------------------------------

    // Images drawn before the first is read back: as many targets as fit in
    // 8 MiB (two 32-bit colour images and a depth image each), at most 16.
    size_t batchTargets() const {
        const size_t bytes = size_t(settings.imageSize) * size_t(settings.imageSize) * 12;
        return std::clamp<size_t>((size_t(8) << 20) / bytes, 1, 16);
    }

    std::vector<Pair> batchPairs;  // reused: their vectors keep their capacity
    struct Image {
        size_t pair, frustum;  // frustum `frustum` of batchPairs[pair]
    };
    std::vector<Image> drawn;  // in targets 0, 1, ... and not yet read back

    // Reads back and weighs every image in `drawn`, in the order drawn.
    void readDrawn(Clock::time_point& t0) {
        for (size_t slot = 0; slot < drawn.size(); ++slot)
            readAndWeigh(batchPairs[drawn[slot].pair], drawn[slot].frustum, slot, t0);
        drawn.clear();
    }

    void sampleBatch(const std::vector<SampleRequest>& requests, std::vector<DirectSample>& results) {
        results.assign(requests.size(), DirectSample());
        times = {};
        // Occlusion queries answer at once; reading them later would need a
        // query object per image.
        if (settings.method == DirectMethod::OcclusionQuery) {
            DirectPhaseTimes total;
            for (size_t i = 0; i < requests.size(); ++i) {
                const SampleRequest& r = requests[i];
                asBatchRequest(i, [&] { results[i] = sample(r.mesh, r.x, r.n, r.seed); });
                total += times;
            }
            times = total;
            return;
        }
        addTargets(batchTargets());
        drawn.clear();
        size_t pairs = 0;  // batchPairs[0, pairs) wait for images
        Clock::time_point t0 = Clock::now();
        for (size_t i = 0; i < requests.size(); ++i) {
            const SampleRequest& r = requests[i];
            if (batchPairs.size() == pairs) batchPairs.emplace_back();
            Pair& p = batchPairs[pairs];
            bool answered = false;
            asBatchRequest(i, [&] { answered = planPair(p, r.mesh, r.x, r.n, r.seed, true); });
            if (answered) {
                results[i] = p.result;
                continue;
            }
            p.request = i;
            ++pairs;
            t0 = Clock::now();
            for (size_t k = 0; k < p.frusta.size(); ++k) {
                if (onCpu(p, k)) {
                    weighOnCpu(p, k, t0);
                    continue;
                }
                if (drawn.size() == targets.size()) asBatchRequest(batchPairs[drawn[0].pair].request, [&] { readDrawn(t0); });
                drawImage(p, k, drawn.size(), t0);
                drawn.push_back({pairs - 1, k});
            }
        }
        if (!drawn.empty()) asBatchRequest(batchPairs[drawn[0].pair].request, [&] { readDrawn(t0); });
        for (size_t q = 0; q < pairs; ++q) {
            finishPair(batchPairs[q]);
            results[batchPairs[q].request] = batchPairs[q].result;
        }
        if (pairs) asBatchRequest(batchPairs[0].request, [&] { checkGl(gl, "direct-light sampling"); });
    }
};

double samplingEyeLift(const Light& light, const Vec3& x, double eyeOffset, double sceneSize) {
    const Vec3 outside = glm::max(light.bounds.lo - x, x - light.bounds.hi);
    double distance = glm::length(glm::max(outside, Vec3(0.0)));
    if (light.planar) distance = std::max(distance, std::abs(glm::dot(x - light.centroid, light.normal)));
    return std::min(eyeOffset * sceneSize, 1e-4 * distance);
}

DirectLightSampler::DirectLightSampler(GlContext& context, const Scene& scene,
                                       const DirectSamplerSettings& settings)
    : impl_(std::make_unique<Impl>(context, scene, settings)) {}

DirectLightSampler::~DirectLightSampler() = default;

DirectSample DirectLightSampler::sample(size_t lightIndex, const Vec3& x, const Vec3& n, uint32_t seed) {
    return impl_->sample(lightIndex, x, n, seed);
}

void DirectLightSampler::sampleBatch(const std::vector<SampleRequest>& requests, std::vector<DirectSample>& results) {
    impl_->sampleBatch(requests, results);
}

bool DirectLightSampler::sampleWithoutGl(size_t lightIndex, const Vec3& x, const Vec3& n, uint32_t seed,
                                         DirectSample& out) {
    return impl_->sampleWithoutGl(lightIndex, x, n, seed, out);
}

const DirectSamplerSettings& DirectLightSampler::settings() const { return impl_->settings; }
void DirectLightSampler::setPhaseTiming(bool on) { impl_->phaseTiming = on; }
const DirectPhaseTimes& DirectLightSampler::lastTimes() const { return impl_->times; }

}  // namespace ml
