#include "Compositor.h"

#include "EmitterOutlines.h"
#include "SpecularPaths.h"

#include "core/image/Illuminance.h"
#include "core/Error.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/gl/GlObjects.h"
#include "meshlight_compositor_shaders.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <future>
#include <limits>
#include <map>
#include <numeric>
#include <optional>

namespace ml {

float textureLodShiftFor(int passes) { return passes > 1 ? float(-0.5 * std::log2(double(passes)) - 1.0) : 0.0f; }

int subpixelPassesWithin(double onePassSeconds, double refineSeconds) {
    int k = 1;
    while (k < 64 && 2 * k * onePassSeconds <= 0.1 * refineSeconds) k *= 2;
    return k;
}

int outlinePassesWithin(int passes, double onePassSeconds, double budget) {
    if (passes * onePassSeconds <= budget) return passes;
    int k = 1;
    while (2 * k < passes && 2 * k * onePassSeconds <= budget) k *= 2;
    return k;
}

void CompositorSettings::validate() const {
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw InputError(concat("image size ", width, "x", height, " is not within 1..16384"));
    if (supersample < 1 || supersample > 16)
        throw InputError(concat("supersampling ", supersample, " is not within 1..16"));
    if (long(width) * supersample > 16384 || long(height) * supersample > 16384)
        throw InputError(concat("image ", width, "x", height, " with supersampling ", supersample,
                                " exceeds 16384 sub-pixels per side: lower --supersample"));
    if (passes < 1 || passes > 64) throw InputError(concat("sub-pixel passes ", passes, " is not within 1..64"));
    if (outlinePasses < 0 || outlinePasses > 1024)
        throw InputError(concat("outline passes ", outlinePasses, " is not within 0..1024"));
    if (!(outlineSeconds >= 0) || !std::isfinite(outlineSeconds))
        throw InputError(concat("outline seconds ", outlineSeconds, " is not a finite number of seconds >= 0"));
    photometry.validate();
}

LightWeights LightWeights::unit(size_t lights) {
    LightWeights w;
    w.light.assign(lights, Rgb(1.0));
    return w;
}

namespace {

struct SceneVertex {
    glm::vec3 position, kd;
    int32_t light;  // index into Scene::lights, −1 for faces that emit nothing
    glm::vec2 uv;   // Mesh::texcoords; (0, 0) for faces that draw no texture
};
static_assert(sizeof(SceneVertex) == 9 * sizeof(float), "SceneVertex is tightly packed");

// Whether a face draws its material's textures: the material has one and
// the mesh has coordinates for it.
bool drawsTexture(const Scene& scene, const Mesh& m, size_t triangle) {
    const Material& mat = scene.materials[m.materials[triangle]];
    return !m.texcoords.empty() && (mat.kdMap || mat.keMap || mat.alphaMap);
}

glm::vec4 transformOf(const TextureMap& map) {
    return glm::vec4(float(map.scale.x), float(map.scale.y), float(map.offset.x), float(map.offset.y));
}

GLint glWrap(TextureWrap w) {
    switch (w) {
        case TextureWrap::Repeat: return GL_REPEAT;
        case TextureWrap::MirroredRepeat: return GL_MIRRORED_REPEAT;
        case TextureWrap::ClampToEdge: return GL_CLAMP_TO_EDGE;
    }
    return GL_REPEAT;
}

int quantityCode(CompositeQuantity q) {
    switch (q) {
        case CompositeQuantity::Radiance: return 0;
        case CompositeQuantity::Reflectance: return 1;
        case CompositeQuantity::Illuminance: return 2;
    }
    return 0;
}

int operatorCode(ToneOperator op) {
    switch (op) {
        case ToneOperator::Aces: return 0;
        case ToneOperator::Reinhard: return 1;
        case ToneOperator::Clamp: return 2;
    }
    return 0;
}

glm::vec3 toVec3(const Rgb& c) { return glm::vec3(c); }

// 0: no specular image in this composite; 1: added; 2: alone (SpecularPart).
int specularCode(SpecularPart p) { return p == SpecularPart::Only ? 2 : 1; }

// What each light's front shows: its radiance times its emission weight.
std::vector<Rgb> emittedRadiance(const Scene& scene, const LightWeights& weights) {
    ML_ASSERT(weights.light.size() == scene.lights.size() &&
                  (weights.emission.empty() || weights.emission.size() == scene.lights.size()),
              weights.light.size(), " weights and ", weights.emission.size(), " emission weights for ",
              scene.lights.size(), " lights");
    std::vector<Rgb> e;
    for (size_t l = 0; l < scene.lights.size(); ++l)
        e.push_back(scene.lights[l].radiance * (weights.emission.empty() ? weights.light[l] : weights.emission[l]));
    return e;
}

// K passes' grid shifts: pass k moves the grid by ((k + ½)/K − ½,
// (row(k) + ½)/K − ½) sub-pixels, row a permutation spreading the rows (bit
// reversal for powers of two, else k·⌊K/2 + 1⌋ mod K when coprime): a rook
// pattern in each sub-pixel. Two halves of the passes, by the parity of
// column + row, each span the sub-pixel along both axes (a split by pass
// number puts one half's rows above the other's); where that parity does
// not split them (K = 2), by number.
struct RookPattern {
    explicit RookPattern(int passes) : passes(passes) {
        int odds = 0;
        for (int k = 0; k < passes; ++k) odds += (k + row(k)) % 2;
        byParity = odds > 0 && odds < passes;
    }
    int row(int k) const {
        if ((passes & (passes - 1)) == 0) {
            int r = 0;
            for (int bit = 1, rev = passes >> 1; bit < passes; bit <<= 1, rev >>= 1)
                if (k & bit) r |= rev;
            return r;
        }
        int step = passes / 2 + 1;
        while (std::gcd(step, passes) != 1) ++step;
        return (k * step) % passes;
    }
    bool odd(int k) const { return (byParity ? k + row(k) : k) % 2 == 1; }
    int odds() const {
        int n = 0;
        for (int k = 0; k < passes; ++k) n += odd(k);
        return n;
    }
    // Pass k's settings: `s` with its grid shift, in output pixels.
    CompositorSettings shifted(CompositorSettings s, int k) const {
        s.shiftX = ((k + 0.5) / passes - 0.5) / s.supersample;
        s.shiftY = ((row(k) + 0.5) / passes - 0.5) / s.supersample;
        return s;
    }
    int passes;
    bool byParity = false;
};

// The sub-pixels (GL rows from the bottom) of a width × height image at
// `supersample` seen through `mvp` where a Radiance composite of `weights`
// without a specular image can be non-zero, in whole pixels: the screen
// bounds of the footprints (GpuCacheMeshes::Mesh::footprint) of the meshes
// it adds, two pixels wider each way, so that the emitters' outlines
// (EmitterOutlines::apply, which pools a pixel's 3×3 neighbours) read zeros
// outside as they would have composited them. Empty (the whole target) when
// it shows emission or a mesh's footprint is not known. Clipped to it, such
// a composite is bit for bit the same image: every sub-pixel outside adds
// nothing (no mesh covers it, no emission).
EmitterOutlines::Rect partRect(const Scene& scene, const glm::mat4& mvp, int width, int height, int supersample,
                               const GpuCacheMeshes& meshes, const LightWeights& weights) {
    for (const Rgb& e : emittedRadiance(scene, weights))
        if (e != Rgb(0.0)) return {};
    const int w = width * supersample, h = height * supersample;
    float x0 = std::numeric_limits<float>::max(), y0 = x0, x1 = -x0, y1 = -x0;
    auto add = [&](const GpuCacheMeshes::Mesh& m, const Rgb& weight) {
        if (m.triangleCount == 0 || weight == Rgb(0.0)) return true;
        if (m.footprint.empty()) return false;
        for (const GpuCacheMeshes::Cell& box : m.footprint) {
            // The box's part in front of the camera (clip w ≥ ε) is a
            // convex solid whose corners are the box's corners there and
            // the points where its edges cross w = ε: its image is
            // theirs. Points near w = ε land far off screen (clamped).
            std::array<glm::vec4, 8> c;
            for (int k = 0; k < 8; ++k)
                c[k] = mvp * glm::vec4(k & 1 ? box.hi.x : box.lo.x, k & 2 ? box.hi.y : box.lo.y,
                                       k & 4 ? box.hi.z : box.lo.z, 1.0f);
            const float epsilon = 1e-6f * std::max({std::abs(c[0].w), std::abs(c[7].w), 1e-30f});
            auto project = [&](const glm::vec4& p) {
                const float x = std::clamp(p.x / p.w, -2.0f, 2.0f), y = std::clamp(p.y / p.w, -2.0f, 2.0f);
                x0 = std::min(x0, (x * 0.5f + 0.5f) * float(w)), x1 = std::max(x1, (x * 0.5f + 0.5f) * float(w));
                y0 = std::min(y0, (y * 0.5f + 0.5f) * float(h)), y1 = std::max(y1, (y * 0.5f + 0.5f) * float(h));
            };
            for (int k = 0; k < 8; ++k) {
                if (!std::isfinite(c[k].x) || !std::isfinite(c[k].y) || !std::isfinite(c[k].w)) return false;
                if (c[k].w >= epsilon) project(c[k]);
                for (int axis = 1; axis < 8; axis <<= 1) {  // the edges from k to its neighbour along each axis
                    const int j = k | axis;
                    if (j == k || (c[k].w >= epsilon) == (c[j].w >= epsilon)) continue;
                    const float f = (epsilon - c[k].w) / (c[j].w - c[k].w);
                    glm::vec4 q = c[k] + f * (c[j] - c[k]);
                    q.w = epsilon;
                    project(q);
                }
            }
        }
        return true;
    };
    const size_t lights = scene.lights.size();
    for (size_t l = 0; l < meshes.directCount(); ++l)
        if (!add(meshes.direct(l), l < lights ? weights.light[l] : weights.shared)) return {};
    for (size_t b = 0; b < meshes.indirectCount(); ++b)
        if (!add(meshes.indirect(b), weights.indirect)) return {};
    const int s = supersample, margin = 2;
    if (x0 > x1) return {0, 0, s, s};  // nothing to add: one pixel, read back as zeros
    auto pixel = [&](float v, int pixels, bool up) {
        const float p = (up ? std::ceil(v / float(s)) + margin : std::floor(v / float(s)) - margin);
        return std::clamp(int(std::clamp(p, -1.0f, float(pixels) + 1.0f)), 0, pixels);
    };
    const int px0 = pixel(x0, width, false), px1 = pixel(x1, width, true);
    const int py0 = pixel(y0, height, false), py1 = pixel(y1, height, true);
    if (px1 <= px0 || py1 <= py0) return {0, 0, s, s};  // wholly out of view
    if (px0 == 0 && py0 == 0 && px1 == width && py1 == height) return {};
    return {px0 * s, py0 * s, (px1 - px0) * s, (py1 - py0) * s};
}

bool sameCamera(const Camera& a, const Camera& b) {
    return a.position == b.position && a.target == b.target && a.up == b.up && a.fovYDegrees == b.fovYDegrees;
}

bool sameWeights(const LightWeights& a, const LightWeights& b) {
    return a.light == b.light && a.indirect == b.indirect && a.shared == b.shared && a.emission == b.emission;
}

}  // namespace

struct Compositor::Impl {
    const GlApi& gl;
    const Scene& scene;
    Vec3 origin;
    GlProgram surfaceProgram, irradianceProgram, occluderProgram, accumulateProgram, resolveProgram, wireframeProgram;
    // Variants compiled on first use (see common_composite.glsl), by key.
    std::map<int, GlProgram> compositePrograms, displayPrograms, forwardPrograms;
    GlBuffer sceneBuffer, lightEmissionBuffer, paletteBuffer;
    GlVertexArray sceneVao, emptyVao;
    GLsizei sceneVertices = 0;

    // Textures drawn per pixel. Without any, the scene is one draw and the
    // shaders are those of before (TEXTURES 0): untextured scenes render
    // bit for bit as they did. With some, the soup holds the untextured
    // faces first, in the scene's order, then one range per textured
    // material, each drawn with its own textures bound: a handful of
    // draws, where an atlas or an array would need textures of one size
    // or seams handled for every wrap mode.
    bool textured = false;
    // Some face has a cut-out (Material::alphaMap): the cache meshes still
    // cover it whole, so each pass of cache meshes keeps only what lies at
    // the depth of the surface in view, holes open (irradiance.frag).
    bool cutOuts = false;
    struct DrawRange {
        GLint first = 0;
        GLsizei count = 0;
        int material = -1;  // index into Scene::materials; −1: faces with their constant Kd
    };
    std::vector<DrawRange> ranges;
    std::map<const Texture*, GlTexture> textures;  // sRGB8 alpha8, mipmapped
    GLint anisotropy = 1;                          // GL_TEXTURE_MAX_ANISOTROPY when the GL offers it

    // Targets of one size, kept between frames; remade when the size changes.
    struct Targets {
        int width = 0, height = 0, supersample = 0;  // pixels, sub-pixels per side
        // Sub-pixel targets.
        GlTexture surface, emissionScale, irradianceSum, irradianceMesh, composite, sceneDepth, cacheDepth;
        GlFramebuffer surfaceFb, irradianceFb, irradianceMeshFb, compositeFb;
        // Pixel targets: the box-filtered composite; the forward pass's image and depth.
        GlTexture pixels, forwardColour, forwardDepth;
        GlFramebuffer pixelsFb, forwardFb;
    } t;

    // The last compose() drew the irradiance (pass 2); the other passes run
    // when something needs them, at most once per compose.
    glm::mat4 mvp{1.0f};
    std::array<glm::vec4, 5> frustum;  // planes of mvp's view, inside: dot(plane, (p, 1)) ≥ 0
    CompositeQuantity quantity = CompositeQuantity::Radiance;
    Photometry photometry;
    bool composed = false, surfaced = false, composited = false, resolved = false, forwarded = false;
    float textureLodShift = 0;  // common_textures.glsl's uTextureLodShift for this composite
    size_t drawnTriangles = 0;  // by the last compose's irradiance pass
    // The sub-pixels the last compose's part can make non-zero (partRect),
    // to which every pass of it is clipped and from which it is read back,
    // the rest read as zero; empty: the whole target.
    EmitterOutlines::Rect clip;

    // The specular pass, in scenes with a glossy or specular material: the
    // last traced image (RGBA32F, a texel per reduction² sub-pixels, row 0
    // at the top) and what it was traced for.
    std::unique_ptr<SpecularPaths> specularPaths;
    uint64_t specularCacheGeneration = 0;  // setSpecularCache calls
    GlTexture specularTexture;
    struct SpecularTrace {
        bool valid = false;
        Camera camera;
        LightWeights weights;
        CompositorSettings settings;
        int reduction = 1;
        uint64_t cacheGeneration = 0;
        int width = 0, height = 0;  // texels

        // The same view, whatever the reduction.
        bool sameView(const Camera& c, const LightWeights& w, const CompositorSettings& s, uint64_t generation) const {
            return valid && cacheGeneration == generation && sameCamera(camera, c) && sameWeights(weights, w) &&
                   settings.width == s.width && settings.height == s.height &&
                   settings.supersample == s.supersample && settings.shiftX == s.shiftX &&
                   settings.shiftY == s.shiftY;
        }
    } specularTrace;
    // A full-resolution trace on a thread of its own (requestSpecular).
    struct SpecularJob {
        SpecularTrace key;
        std::shared_ptr<std::atomic<bool>> cancel;
        std::future<ImageRgb> image;
    };
    std::optional<SpecularJob> specularJob;
    double specularSeconds = 0;  // traceSpecular's, on this thread
    // composite()'s last traces, one per sub-pixel pass (4 for render: some
    // 12 MB each at 256² pixels of 4×4 sub-pixels).
    static constexpr size_t kRecentSpecular = 4;
    std::vector<std::pair<SpecularTrace, ImageRgb>> recentSpecular;

    ~Impl() { cancelSpecularJob(); }

    void cancelSpecularJob() {
        if (!specularJob) return;
        *specularJob->cancel = true;
        specularJob->image.wait();  // within a row of sub-pixels
        specularJob.reset();
    }
    int specular = 0;  // what the last compose does with it: specularCode, 0 none

    GlProgram program(const char* vertName, std::string vert, const char* fragName, std::string frag) const {
        return GlProgram(gl, {{GL_VERTEX_SHADER, vertName, std::move(vert)}, {GL_FRAGMENT_SHADER, fragName, std::move(frag)}});
    }
    // "#define TEXTURES 0|1\n": set once per scene (common_textures.glsl).
    std::string texturesDefine() const {
        return concat("#define TEXTURES ", textured ? 1 : 0, "\n#define TEXTURE_ANISOTROPY ", anisotropy > 1 ? 1 : 0,
                      "\n");
    }

    // Display variants: operator and contours matter only where they are used.
    static std::string displayDefines(CompositeQuantity q, int supersample, ToneOperator op, bool contours, int& key) {
        const int operatorKey = q == CompositeQuantity::Radiance ? operatorCode(op) : 0;
        const int contourKey = q == CompositeQuantity::Illuminance && contours ? 1 : 0;
        key = ((quantityCode(q) * 32 + supersample) * 4 + operatorKey) * 2 + contourKey;
        return concat("#define QUANTITY ", quantityCode(q), "\n#define SUPERSAMPLE ", supersample,
                      "\n#define OPERATOR ", operatorKey, "\n#define CONTOURS ", contourKey, "\n");
    }

    // "#define SPECULAR 0|1|2\n" of the last compose (common_specular.glsl).
    std::string specularDefine() const { return concat("#define SPECULAR ", specular, "\n"); }

    const GlProgram& compositeProgram(CompositeQuantity q) {
        const int key = quantityCode(q) + 4 * specular;
        auto it = compositePrograms.find(key);
        if (it == compositePrograms.end()) {
            const std::string defines =
                concat("#define QUANTITY ", quantityCode(q), "\n", texturesDefine(), specularDefine());
            it = compositePrograms
                     .emplace(key, program("composite.vert", glslSource({shaders::composite_vert}), "composite.frag",
                                           glslSource({defines.c_str(), shaders::common_constants_glsl,
                                                       shaders::common_specular_glsl, shaders::common_composite_glsl,
                                                       shaders::composite_frag})))
                     .first;
        }
        return it->second;
    }

    const GlProgram& displayProgram(CompositeQuantity q, int supersample, ToneOperator op, bool contours) {
        int key = 0;
        const std::string defines = displayDefines(q, supersample, op, contours, key) + texturesDefine() +
                                    specularDefine();
        key = key * 3 + specular;
        auto it = displayPrograms.find(key);
        if (it == displayPrograms.end())
            it = displayPrograms
                     .emplace(key, program("composite.vert", glslSource({shaders::composite_vert}), "display.frag",
                                           glslSource({defines.c_str(), shaders::common_constants_glsl,
                                                       shaders::common_specular_glsl, shaders::common_composite_glsl,
                                                       shaders::common_display_glsl, shaders::display_frag})))
                     .first;
        return it->second;
    }

    const GlProgram& forwardProgram(CompositeQuantity q, ToneOperator op, bool contours) {
        int key = 0;
        const std::string defines = displayDefines(q, 1, op, contours, key) + texturesDefine() + specularDefine();
        key = key * 3 + specular;
        auto it = forwardPrograms.find(key);
        if (it == forwardPrograms.end())
            it = forwardPrograms
                     .emplace(key, program("scene_forward.vert",
                                           glslSource({texturesDefine().c_str(), shaders::scene_forward_vert}),
                                           "scene_forward.frag",
                                           glslSource({defines.c_str(), shaders::common_constants_glsl,
                                                       shaders::common_display_glsl, shaders::common_textures_glsl,
                                                       shaders::common_specular_glsl, shaders::scene_forward_frag})))
                     .first;
        return it->second;
    }

    Impl(GlContext& ctx, const Scene& s)
        : gl(ctx.gl()), scene(s), origin(s.bounds.center()), textured(s.hasTextures()) {
        if (textured) anisotropy = textureAnisotropy();
        const std::string tex = texturesDefine();
        surfaceProgram = program("scene_gbuffer.vert", glslSource({tex.c_str(), shaders::scene_gbuffer_vert}),
                                 "scene_gbuffer.frag",
                                 glslSource({tex.c_str(), shaders::common_textures_glsl, shaders::scene_gbuffer_frag}));
        cutOuts = textured && std::any_of(s.meshes.begin(), s.meshes.end(), [&](const Mesh& m) {
            return !m.texcoords.empty() && std::any_of(m.materials.begin(), m.materials.end(),
                                                       [&](uint32_t i) { return bool(s.materials[i].alphaMap); });
        });
        const std::string cut = concat("#define CUT_OUTS ", cutOuts ? 1 : 0, "\n");
        irradianceProgram = program("irradiance.vert", glslSource({shaders::irradiance_vert}), "irradiance.frag",
                                    glslSource({cut.c_str(), shaders::irradiance_frag}));
        occluderProgram = program("scene_gbuffer.vert", glslSource({tex.c_str(), shaders::scene_gbuffer_vert}), "occluder.frag",
                                  glslSource({shaders::occluder_frag}));
        accumulateProgram = program("composite.vert", glslSource({shaders::composite_vert}), "accumulate.frag",
                                    glslSource({shaders::accumulate_frag}));
        resolveProgram = program("composite.vert", glslSource({shaders::composite_vert}), "resolve.frag",
                                 glslSource({shaders::resolve_frag}));
        wireframeProgram = GlProgram(gl, {{GL_VERTEX_SHADER, "wireframe.vert", glslSource({shaders::wireframe_vert})},
                                          {GL_GEOMETRY_SHADER, "wireframe.geom", glslSource({shaders::wireframe_geom})},
                                          {GL_FRAGMENT_SHADER, "wireframe.frag", glslSource({shaders::wireframe_frag})}});

        // The scene as a triangle soup: materials are per face, and so is
        // the light a face emits as.
        std::map<std::pair<uint32_t, uint32_t>, int32_t> lightOf;  // (mesh, triangle) → light
        for (size_t l = 0; l < scene.lights.size(); ++l)
            for (uint32_t tri : scene.lights[l].triangles) lightOf[{scene.lights[l].mesh, tri}] = int32_t(l);
        std::vector<SceneVertex> soup;
        soup.reserve(scene.triangleCount() * 3);
        // Untextured faces first (range material −1), then each textured
        // material's (see `ranges`).
        for (int pass = -1; pass < (textured ? int(scene.materials.size()) : 0); ++pass) {
            const size_t start = soup.size();
            for (uint32_t mi = 0; mi < scene.meshes.size(); ++mi) {
                const Mesh& m = scene.meshes[mi];
                for (size_t tri = 0; tri < m.triangles.size(); ++tri) {
                    const bool mapped = textured && drawsTexture(scene, m, tri);
                    if (pass < 0 ? mapped : !mapped || int(m.materials[tri]) != pass) continue;
                    const Material& mat = scene.materials[m.materials[tri]];
                    int32_t light = -1;
                    if (mat.emissive()) {
                        // Scene::finalize makes every emissive face part of a light.
                        const auto it = lightOf.find({mi, uint32_t(tri)});
                        ML_ASSERT(it != lightOf.end(), "emissive triangle ", tri, " of mesh '", m.name,
                                  "' in no light");
                        light = it->second;
                    }
                    const Triangle3 p = m.triangle(tri);
                    for (int k = 0; k < 3; ++k)
                        soup.push_back({glm::vec3(p[k] - origin), glm::vec3(mat.kd), light,
                                        mapped ? glm::vec2(m.texcoords[m.triangles[tri][k]]) : glm::vec2(0.0f)});
                }
            }
            if (soup.size() > start || pass < 0) ranges.push_back({GLint(start), GLsizei(soup.size() - start), pass});
        }
        if (textured) uploadTextures();
        sceneVertices = GLsizei(soup.size());
        sceneBuffer = makeBuffer(gl, std::max<size_t>(soup.size(), 1) * sizeof(SceneVertex), soup.data());
        sceneVao = makeVertexArray(gl);
        for (GLuint a = 0; a < 2; ++a) {
            gl.EnableVertexArrayAttrib(sceneVao.id(), a);
            gl.VertexArrayAttribFormat(sceneVao.id(), a, 3, GL_FLOAT, GL_FALSE, GLuint(3 * a * sizeof(float)));
            gl.VertexArrayAttribBinding(sceneVao.id(), a, 0);
        }
        gl.EnableVertexArrayAttrib(sceneVao.id(), 2);
        gl.VertexArrayAttribIFormat(sceneVao.id(), 2, 1, GL_INT, GLuint(6 * sizeof(float)));
        gl.VertexArrayAttribBinding(sceneVao.id(), 2, 0);
        gl.EnableVertexArrayAttrib(sceneVao.id(), 3);
        gl.VertexArrayAttribFormat(sceneVao.id(), 3, 2, GL_FLOAT, GL_FALSE, GLuint(7 * sizeof(float)));
        gl.VertexArrayAttribBinding(sceneVao.id(), 3, 0);
        gl.VertexArrayVertexBuffer(sceneVao.id(), 0, sceneBuffer.id(), 0, GLsizei(sizeof(SceneVertex)));
        lightEmissionBuffer = makeBuffer(gl, std::max<size_t>(scene.lights.size(), 1) * sizeof(glm::vec4), nullptr,
                                         GL_DYNAMIC_DRAW);
        std::vector<glm::vec4> palette;
        for (const Rgb& c : falseColourPalette()) palette.emplace_back(glm::vec3(c), 1.0f);
        paletteBuffer = makeBuffer(gl, palette.size() * sizeof(glm::vec4), palette.data());
        emptyVao = makeVertexArray(gl);
        if (SpecularPaths::needed(scene)) specularPaths = std::make_unique<SpecularPaths>(scene);
        checkGl(gl, "creating the compositor");
    }

    // Each texture a drawn material uses, once: sRGB 8-bit (the GL decodes
    // to linear before it filters, as Texture::sample does), a full mip
    // chain, trilinear, and anisotropic up to 16 where the GL has it, but
    // not on llvmpipe: it offers GL_ARB_texture_filter_anisotropic, yet its
    // anisotropic path ignores the magnification filter and blurs magnified
    // texels by most of a pixel (tests/test_textures.cpp: a nearest texel
    // came out blended with its neighbour, Kd wrong by up to 2.4×), and
    // each of its taps costs CPU time.
    GLint textureAnisotropy() const {
        const bool llvmpipe = gl.renderer.find("llvmpipe") != std::string::npos;
        if (llvmpipe || !(gl.hasExtension("GL_ARB_texture_filter_anisotropic") ||
                          gl.hasExtension("GL_EXT_texture_filter_anisotropic")))
            return 1;
        GLint most = 1;
        gl.GetIntegerv(GL_MAX_TEXTURE_MAX_ANISOTROPY, &most);
        return std::clamp(most, 1, 16);
    }
    void uploadTextures() {
        for (const DrawRange& r : ranges) {
            if (r.material < 0) continue;
            const Material& mat = scene.materials[size_t(r.material)];
            for (const TextureMap* map : {&mat.kdMap, &mat.keMap, &mat.alphaMap}) {
                if (!*map || textures.count(map->image.get())) continue;
                const Texture& image = *map->image;
                GLuint n = 0;
                gl.CreateTextures(GL_TEXTURE_2D, 1, &n);
                GlTexture texture(gl, n);
                int levels = 1;
                while ((std::max(image.width, image.height) >> levels) > 0) ++levels;
                gl.TextureStorage2D(n, levels, GL_SRGB8_ALPHA8, image.width, image.height);
                gl.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
                gl.TextureSubImage2D(n, 0, 0, 0, image.width, image.height, GL_RGBA, GL_UNSIGNED_BYTE,
                                     image.rgba.data());
                gl.GenerateTextureMipmap(n);
                gl.TextureParameteri(n, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
                gl.TextureParameteri(n, GL_TEXTURE_MAG_FILTER, image.nearest ? GL_NEAREST : GL_LINEAR);
                gl.TextureParameteri(n, GL_TEXTURE_WRAP_S, glWrap(image.wrapS));
                gl.TextureParameteri(n, GL_TEXTURE_WRAP_T, glWrap(image.wrapT));
                if (anisotropy > 1) gl.TextureParameteri(n, GL_TEXTURE_MAX_ANISOTROPY, anisotropy);
                textures.emplace(&image, std::move(texture));
            }
        }
    }

    // The scene's faces with program `p` in use and its vertex array bound:
    // one draw without textures, else a draw per range with its uniforms.
    void drawSceneRanges(const GlProgram& p) {
        gl.BindVertexArray(sceneVao.id());
        if (!textured) {
            gl.DrawArrays(GL_TRIANGLES, 0, sceneVertices);
            return;
        }
        gl.Uniform1f(p.uniform("uTextureLodShift"), textureLodShift);  // the same for every range
        for (const DrawRange& r : ranges) {
            if (r.count == 0) continue;
            const Material* mat = r.material >= 0 ? &scene.materials[size_t(r.material)] : nullptr;
            const bool kd = mat && mat->kdMap, ke = mat && mat->keMap;
            gl.Uniform1i(p.uniform("uKdMapped"), kd ? 1 : 0);
            gl.Uniform1i(p.uniform("uKeMapped"), ke ? 1 : 0);
            if (kd) {
                gl.BindTextureUnit(4, textures.at(mat->kdMap.image.get()).id());
                const glm::vec3 f(mat->kdMap.factor);
                const glm::vec4 x = transformOf(mat->kdMap);
                gl.Uniform3f(p.uniform("uKdFactor"), f.r, f.g, f.b);
                gl.Uniform4f(p.uniform("uKdTransform"), x.x, x.y, x.z, x.w);
            }
            if (ke) {
                gl.BindTextureUnit(5, textures.at(mat->keMap.image.get()).id());
                glm::vec3 scale(0.0f);
                for (int c = 0; c < 3; ++c)
                    if (mat->ke[c] > 0) scale[c] = float(mat->keMap.factor[c] / mat->ke[c]);
                const glm::vec4 x = transformOf(mat->keMap);
                gl.Uniform3f(p.uniform("uKeScale"), scale.r, scale.g, scale.b);
                gl.Uniform4f(p.uniform("uKeTransform"), x.x, x.y, x.z, x.w);
            }
            bindCutOut(p, mat);
            gl.DrawArrays(GL_TRIANGLES, r.first, r.count);
        }
    }

    // A range's cut-out (Material::alphaMap; common_textures.glsl's cutAway).
    void bindCutOut(const GlProgram& p, const Material* mat) {
        const bool cut = mat && mat->alphaMap;
        gl.Uniform1i(p.uniform("uAlphaMapped"), cut ? 1 : 0);
        if (!cut) return;
        const TextureMap& map = mat->alphaMap;
        gl.BindTextureUnit(8, textures.at(map.image.get()).id());
        const glm::vec4 x = transformOf(map);
        gl.Uniform4f(p.uniform("uAlphaTransform"), x.x, x.y, x.z, x.w);
        gl.Uniform1f(p.uniform("uAlphaFactor"), float(map.factor.r));
        gl.Uniform1f(p.uniform("uAlphaCutoff"), float(mat->alphaCutoff));
        gl.Uniform1i(p.uniform("uAlphaFromGrey"), map.image->hasAlpha ? 0 : 1);
    }

    void ensureTargets(int width, int height, int supersample) {
        if (t.width == width && t.height == height && t.supersample == supersample) return;
        t = Targets{};
        const int w = width * supersample, h = height * supersample;
        t.surface = makeTexture2D(gl, GL_RGBA32F, w, h);
        t.irradianceSum = makeTexture2D(gl, GL_RGBA32F, w, h);
        t.composite = makeTexture2D(gl, GL_RGBA32F, w, h);
        t.sceneDepth = makeTexture2D(gl, GL_DEPTH_COMPONENT32F, w, h);
        t.irradianceMesh = makeTexture2D(gl, GL_RGBA32F, w, h);
        t.cacheDepth = makeTexture2D(gl, GL_DEPTH_COMPONENT32F, w, h);
        if (textured) {
            t.emissionScale = makeTexture2D(gl, GL_RGBA16F, w, h);
            t.surfaceFb = makeFramebuffer(gl, {t.surface.id(), t.emissionScale.id()}, t.sceneDepth.id(), "compositor");
        } else {
            t.surfaceFb = makeFramebuffer(gl, {t.surface.id()}, t.sceneDepth.id(), "compositor");
        }
        t.irradianceFb = makeFramebuffer(gl, {t.irradianceSum.id()}, t.cacheDepth.id(), "compositor");
        t.irradianceMeshFb = makeFramebuffer(gl, {t.irradianceMesh.id()}, t.cacheDepth.id(), "compositor");
        t.compositeFb = makeFramebuffer(gl, {t.composite.id()}, 0, "compositor");
        t.pixels = makeTexture2D(gl, GL_RGBA32F, width, height);
        t.pixelsFb = makeFramebuffer(gl, {t.pixels.id()}, 0, "compositor");
        t.forwardColour = makeTexture2D(gl, GL_RGBA8, width, height);
        t.forwardDepth = makeTexture2D(gl, GL_DEPTH_COMPONENT32F, width, height);
        t.forwardFb = makeFramebuffer(gl, {t.forwardColour.id()}, t.forwardDepth.id(), "compositor");
        t.width = width;
        t.height = height;
        t.supersample = supersample;
    }

    // Right-handed view, reversed infinite projection (z_ndc = near / depth).
    // `shift`: the image moved by this much in NDC (x_ndc + shift.x).
    glm::mat4 clipFromLocal(const Camera& camera, double aspect, const Vec2& shift = Vec2(0.0)) const {
        const double f = 1.0 / std::tan(glm::radians(camera.fovYDegrees) * 0.5);
        const double nearDistance = 1e-5 * std::max(scene.bounds.diagonal(), 1e-300);
        Mat4 p(0.0);
        p[0][0] = f / aspect;
        p[1][1] = f;
        // w_clip = −z: x_ndc = (p00 x + p20 z) / (−z) = p00 x / (−z) − p20.
        p[2][0] = -shift.x;
        p[2][1] = -shift.y;
        p[3][2] = nearDistance;
        p[2][3] = -1.0;
        const Mat4 view = camera.view() * glm::translate(Mat4(1.0), origin);
        return glm::mat4(p * view);
    }

    // The state every pass relies on, whatever ran before (ImGui among others).
    void baseState(int width, int height) {
        gl.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
        gl.Disable(GL_DEPTH_CLAMP);
        gl.Disable(GL_CULL_FACE);
        gl.Disable(GL_COLOR_LOGIC_OP);
        gl.Disable(GL_SCISSOR_TEST);
        gl.Disable(GL_BLEND);
        gl.Disable(GL_STENCIL_TEST);
        gl.Disable(GL_DEPTH_TEST);
        gl.Disable(GL_FRAMEBUFFER_SRGB);
        gl.Viewport(0, 0, width, height);
        gl.DepthMask(GL_TRUE);
        gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        if (!clip.empty() && width == t.width * t.supersample && height == t.height * t.supersample) {
            gl.Enable(GL_SCISSOR_TEST);  // clears too: outside, the targets keep what they held
            gl.Scissor(clip.x, clip.y, clip.width, clip.height);
        }
    }

    // Adds one mesh's weighted irradiance where it is the nearest cache
    // surface. Each mesh is drawn once, with its own depth test: the first
    // straight into the sum, the others into a target of their own that is
    // then added to the sum (blending them in directly would add the
    // surfaces each hides). Back faces occlude and add nothing (a cache
    // triangle holds the irradiance of its front, CCW, side; a surface lit
    // from both sides has a reversed copy for its back), and sit a hair
    // behind their depth so that such a copy wins over them whatever the
    // order; of coincident front faces (two copies of a floor) the first
    // drawn wins, so a sub-pixel adds one of them only. On llvmpipe the cost
    // of a large cache is per triangle: one draw, not a depth pass and then
    // a shading pass.
    void drawIrradianceMesh(const GpuCacheMeshes::Mesh& mesh, const Rgb& weight, bool& first) {
        if (mesh.triangleCount == 0 || weight == Rgb(0.0)) return;  // nothing to add
        const float zero[4] = {0, 0, 0, 0};
        const float farDepth = 0.0f;  // reversed depth
        gl.BindFramebuffer(GL_FRAMEBUFFER, first ? t.irradianceFb.id() : t.irradianceMeshFb.id());
        if (!first) gl.ClearBufferfv(GL_COLOR, 0, zero);
        gl.ClearBufferfv(GL_DEPTH, 0, &farDepth);
        gl.Enable(GL_DEPTH_TEST);
        gl.DepthFunc(GL_GREATER);
        gl.DepthMask(GL_TRUE);
        useIrradianceProgram(weight);
        gl.BindVertexArray(mesh.vertexArray());
        drawnTriangles += drawTriangles(mesh);
        gl.Disable(GL_DEPTH_TEST);
        if (!first) {
            gl.BindFramebuffer(GL_FRAMEBUFFER, t.irradianceFb.id());
            gl.Enable(GL_BLEND);
            gl.BlendFunc(GL_ONE, GL_ONE);
            gl.BlendEquation(GL_FUNC_ADD);
            accumulateProgram.use();
            gl.BindTextureUnit(3, t.irradianceMesh.id());
            gl.BindVertexArray(emptyVao.id());
            gl.DrawArrays(GL_TRIANGLES, 0, 3);
            gl.Disable(GL_BLEND);
        }
        first = false;
    }

    void useIrradianceProgram(const Rgb& weight) {
        irradianceProgram.use();
        gl.UniformMatrix4fv(irradianceProgram.uniform("uClipFromLocal"), 1, GL_FALSE, &mvp[0][0]);
        gl.Uniform3f(irradianceProgram.uniform("uWeight"), float(weight.r), float(weight.g), float(weight.b));
    }

    // The lights' own meshes where lights share (each keeps only some of the
    // scene's faces), added straight into the sum. A mesh's own depth test
    // would let it add, where it lacks the face in view, what it keeps
    // behind it (the wall behind a partition it does not cover); so the
    // scene's own surfaces go first into the depth buffer, a hair behind
    // their depth (occluder.frag), and the meshes are tested against them
    // without writing depth: each adds only on the surface in view. One
    // depth pass of the scene's triangles, then one draw per mesh.
    void drawPartialMeshes(const GpuCacheMeshes& meshes, const LightWeights& weights, bool& first) {
        const float farDepth = 0.0f;  // reversed depth
        gl.BindFramebuffer(GL_FRAMEBUFFER, t.irradianceFb.id());
        gl.ClearBufferfv(GL_DEPTH, 0, &farDepth);
        gl.Enable(GL_DEPTH_TEST);
        gl.DepthFunc(GL_GREATER);
        gl.DepthMask(GL_TRUE);
        gl.ColorMaski(0, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
        occluderProgram.use();
        gl.UniformMatrix4fv(occluderProgram.uniform("uClipFromLocal"), 1, GL_FALSE, &mvp[0][0]);
        gl.BindVertexArray(sceneVao.id());
        gl.DrawArrays(GL_TRIANGLES, 0, sceneVertices);
        gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        gl.DepthMask(GL_FALSE);
        gl.Enable(GL_BLEND);
        gl.BlendFunc(GL_ONE, GL_ONE);
        gl.BlendEquation(GL_FUNC_ADD);
        for (size_t l = 0; l < weights.light.size(); ++l) {
            const GpuCacheMeshes::Mesh& mesh = meshes.direct(l);
            if (mesh.triangleCount == 0 || weights.light[l] == Rgb(0.0)) continue;
            useIrradianceProgram(weights.light[l]);
            gl.BindVertexArray(mesh.vertexArray());
            drawnTriangles += drawTriangles(mesh);
        }
        gl.Disable(GL_BLEND);
        gl.DepthMask(GL_TRUE);
        gl.Disable(GL_DEPTH_TEST);
        first = false;
    }

    // Left, right, bottom, top and near planes of the view (the projection
    // has no far plane; clip z ≥ 0 holds in front of the camera).
    void setFrustum() {
        auto row = [&](int i) { return glm::vec4(mvp[0][i], mvp[1][i], mvp[2][i], mvp[3][i]); };
        frustum = {row(3) + row(0), row(3) - row(0), row(3) + row(1), row(3) - row(1), row(3) - row(2)};
    }

    bool inView(const GpuCacheMeshes::Cell& c) const {
        for (const glm::vec4& plane : frustum) {
            // The box's corner furthest along the plane's normal.
            const glm::vec3 corner(plane.x >= 0 ? c.hi.x : c.lo.x, plane.y >= 0 ? c.hi.y : c.lo.y,
                                   plane.z >= 0 ? c.hi.z : c.lo.z);
            if (glm::dot(glm::vec3(plane), corner) + plane.w < 0) return false;
        }
        return true;
    }

    // A mesh's triangles, those of its cells out of view left out (its
    // vertex array bound). Cells are in buffer order: neighbours in view
    // make one draw. Returns the triangles drawn.
    size_t drawTriangles(const GpuCacheMeshes::Mesh& mesh) {
        if (mesh.cells.empty()) {
            gl.DrawElements(GL_TRIANGLES, GLsizei(mesh.triangleCount * 3), GL_UNSIGNED_INT, nullptr);
            return mesh.triangleCount;
        }
        size_t first = 0, count = 0, drawn = 0;
        auto flush = [&] {
            if (count)
                gl.DrawElements(GL_TRIANGLES, GLsizei(count * 3), GL_UNSIGNED_INT,
                                reinterpret_cast<const void*>(first * sizeof(glm::uvec3)));
            drawn += count;
            count = 0;
        };
        for (const GpuCacheMeshes::Cell& c : mesh.cells) {
            if (!inView(c)) continue;
            if (count && first + count == c.first) {
                count += c.count;
            } else {
                flush();
                first = c.first;
                count = c.count;
            }
        }
        flush();
        return drawn;
    }

    // Pass 2, the irradiance, for the passes that follow.
    // `clipped`: only where the part can be non-zero (partRect), for
    // composite()'s parts; the viewer's frames are whole.
    void compose(const Camera& camera, const GpuCacheMeshes& meshes, const LightWeights& weights,
                 const CompositorSettings& s, bool clipped = false) {
        s.validate();
        camera.validate();
        ML_ASSERT(meshes.directCount() == scene.lights.size() || meshes.directCount() == scene.lights.size() + 1,
                  meshes.directCount(), " meshes for ", scene.lights.size(), " lights");
        ML_ASSERT(weights.light.size() == scene.lights.size(), weights.light.size(), " weights for ",
                  scene.lights.size(), " lights");
        ML_ASSERT(weights.emission.empty() || weights.emission.size() == scene.lights.size(),
                  weights.emission.size(), " emission weights for ", scene.lights.size(), " lights");
        ensureTargets(s.width, s.height, s.supersample);
        mvp = clipFromLocal(camera, double(s.width) / s.height, Vec2(2 * s.shiftX / s.width, 2 * s.shiftY / s.height));
        setFrustum();
        quantity = s.quantity;
        photometry = s.photometry;
        textureLodShift = textureLodShiftFor(s.passes);
        // The last traced specular image, if it is of this view's grid.
        const SpecularTrace& st = specularTrace;
        const bool specularFits = st.valid && st.settings.width == s.width && st.settings.height == s.height &&
                                  st.settings.supersample == s.supersample;
        specular = specularPaths && specularFits && s.quantity == CompositeQuantity::Radiance &&
                           s.specular != SpecularPart::Off
                       ? specularCode(s.specular)
                       : 0;
        clip = clipped && quantity == CompositeQuantity::Radiance && !specular
                   ? partRect(scene, mvp, t.width, t.height, t.supersample, meshes, weights)
                   : EmitterOutlines::Rect{};
        if (!scene.lights.empty()) {
            std::vector<glm::vec4> emission;
            for (const Rgb& e : emittedRadiance(scene, weights)) emission.emplace_back(toVec3(e), 1.0f);
            gl.NamedBufferSubData(lightEmissionBuffer.id(), 0, GLsizeiptr(emission.size() * sizeof(glm::vec4)),
                                  emission.data());
        }
        if (cutOuts) {
            // The surfaces in view first, holes open: their depth bounds
            // what the cache meshes may add (irradiance.frag).
            composed = true;
            surfaced = false;
            ensureSurface();
            gl.BindTextureUnit(9, t.sceneDepth.id());
        }
        baseState(s.width * s.supersample, s.height * s.supersample);
        const float zero[4] = {0, 0, 0, 0};
        gl.BindFramebuffer(GL_FRAMEBUFFER, t.irradianceFb.id());
        gl.ClearBufferfv(GL_COLOR, 0, zero);
        drawnTriangles = 0;
        bool first = true;
        // Each light's own mesh, then the mesh the lights share, if any:
        // with a shared mesh, the lights' own meshes keep only some faces.
        if (meshes.directCount() > scene.lights.size()) {
            drawPartialMeshes(meshes, weights, first);
            drawIrradianceMesh(meshes.direct(scene.lights.size()), weights.shared, first);
        } else {
            for (size_t l = 0; l < meshes.directCount(); ++l) drawIrradianceMesh(meshes.direct(l), weights.light[l], first);
        }
        for (size_t b = 0; b < meshes.indirectCount(); ++b) drawIrradianceMesh(meshes.indirect(b), weights.indirect, first);
        checkGl(gl, "compositing the irradiance");
        composed = true;
        surfaced = cutOuts;  // drawn above for this view when the scene has cut-outs
        composited = resolved = forwarded = false;
    }

    // --- Emitters' outlines (CompositorSettings::outlinePasses) -------------
    // The surfaces alone, from `camera` with s's grid shift: no cache mesh is
    // drawn, so a pass costs the scene's triangles, not the cache's. Leaves
    // nothing composited (the irradiance is not this view's).
    // Only the sub-pixels of `rect` are drawn.
    void drawSurfacesOnly(const Camera& camera, const CompositorSettings& s, const EmitterOutlines::Rect& rect) {
        clip = {};  // its own rectangle
        ensureTargets(s.width, s.height, s.supersample);
        mvp = clipFromLocal(camera, double(s.width) / s.height, Vec2(2 * s.shiftX / s.width, 2 * s.shiftY / s.height));
        setFrustum();
        drawSurfaces(rect);
        composed = surfaced = composited = resolved = forwarded = false;
    }

    // The sub-pixels of the last surface pass (GL rows, from the bottom):
    // what each sees, and the emission textures' scale where it has any.
    // Those of `rect` (empty: all).
    EmitterOutlines::SubPixels readSurfaceSubPixels(const EmitterOutlines::Rect& rect = {}) {
        EmitterOutlines::SubPixels p;
        p.rect = rect.empty() ? clip : rect;  // none given: the whole target, or the part's clip
        p.surface = readTarget(t.surfaceFb.id(), GL_COLOR_ATTACHMENT0, p.rect);
        if (textured) p.emissionScale = readTarget(t.surfaceFb.id(), GL_COLOR_ATTACHMENT1, p.rect);
        return p;
    }
    // The last composite's sub-pixels (GL rows, from the bottom; those of
    // the part's clip, if any), and the image readImage() makes of them.
    ImageRgb readImage(std::vector<float>& subPixels) {
        ensureComposite();
        subPixels = readTarget(t.compositeFb.id(), GL_COLOR_ATTACHMENT0);
        return imageOf(subPixels);
    }

    // Pass 1: reflectance, and which light's front is seen, per sub-pixel.
    void ensureSurface() {
        ML_ASSERT(composed, "nothing composited yet");
        if (surfaced) return;
        drawSurfaces();
        surfaced = true;
    }
    // The surface pass from mvp, only within `scissor` if it is not empty.
    void drawSurfaces(const EmitterOutlines::Rect& scissor = {}) {
        baseState(t.width * t.supersample, t.height * t.supersample);
        if (!scissor.empty()) {
            gl.Enable(GL_SCISSOR_TEST);
            gl.Scissor(scissor.x, scissor.y, scissor.width, scissor.height);
        }
        const float zero[4] = {0, 0, 0, 0};
        const float farDepth = 0.0f;  // reversed depth
        gl.BindFramebuffer(GL_FRAMEBUFFER, t.surfaceFb.id());
        gl.ClearBufferfv(GL_COLOR, 0, zero);
        if (textured) gl.ClearBufferfv(GL_COLOR, 1, zero);
        gl.ClearBufferfv(GL_DEPTH, 0, &farDepth);
        gl.Enable(GL_DEPTH_TEST);
        gl.DepthFunc(GL_GREATER);
        surfaceProgram.use();
        gl.UniformMatrix4fv(surfaceProgram.uniform("uClipFromLocal"), 1, GL_FALSE, &mvp[0][0]);
        drawSceneRanges(surfaceProgram);
        gl.Disable(GL_DEPTH_TEST);
        gl.Disable(GL_SCISSOR_TEST);
        checkGl(gl, "drawing the surfaces");
    }

    // The composite's inputs and uniforms, for composite.frag and display.frag.
    void bindCompositeInputs(const GlProgram& p) {
        setLuxFactors(p);
        gl.BindTextureUnit(0, t.surface.id());
        gl.BindTextureUnit(1, t.irradianceSum.id());
        if (textured) gl.BindTextureUnit(6, t.emissionScale.id());
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, lightEmissionBuffer.id());
        bindSpecular(p, t.height * t.supersample);
    }

    // The specular image for common_specular.glsl; `rows`: sub-pixel rows
    // of the target drawn.
    void bindSpecular(const GlProgram& p, int rows) {
        if (!specular) return;
        gl.BindTextureUnit(7, specularTexture.id());
        gl.Uniform1i(p.uniform("uSpecularReduction"), specularTrace.reduction);
        gl.Uniform1i(p.uniform("uSpecularRows"), rows);
    }

    void uploadSpecular(const ImageRgb& image) {
        if (specularTrace.width != image.width || specularTrace.height != image.height || !specularTexture.id()) {
            specularTexture = makeTexture2D(gl, GL_RGBA32F, image.width, image.height);
            specularTrace.width = image.width;
            specularTrace.height = image.height;
        }
        gl.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
        gl.TextureSubImage2D(specularTexture.id(), 0, 0, 0, image.width, image.height, GL_RGB, GL_FLOAT,
                             image.data.data());
        checkGl(gl, "uploading the specular image");
    }

    // An image's composite: every sub-pixel traced, where it is shown. The
    // last few traces are kept on the CPU: render's specular layer composites
    // the beauty image's sub-pixel passes again, with the same weights.
    void traceSpecularFor(const Camera& camera, const LightWeights& weights, const CompositorSettings& s) {
        if (s.quantity != CompositeQuantity::Radiance || s.specular == SpecularPart::Off) return;
        if (!specularPaths || !specularPaths->hasCache()) return;
        if (specularTrace.sameView(camera, weights, s, specularCacheGeneration) && specularTrace.reduction == 1) return;
        for (const auto& [key, image] : recentSpecular)
            if (key.sameView(camera, weights, s, specularCacheGeneration)) {
                uploadSpecular(image);
                keep(key);
                return;
            }
        const auto start = std::chrono::steady_clock::now();
        ImageRgb image = specularPaths->trace(camera, s, weights, 1);
        specularSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        uploadSpecular(image);
        keep(keyOf(camera, weights, s, 1));
        if (recentSpecular.size() == kRecentSpecular) recentSpecular.erase(recentSpecular.begin());
        recentSpecular.emplace_back(specularTrace, std::move(image));
    }

    // `key` is the image uploaded (its texel size set by uploadSpecular).
    void keep(const SpecularTrace& key) {
        const int width = specularTrace.width, height = specularTrace.height;
        specularTrace = key;
        specularTrace.width = width;
        specularTrace.height = height;
    }

    bool traceSpecular(const Camera& camera, const LightWeights& weights, const CompositorSettings& s, int reduction) {
        if (!specularPaths || !specularPaths->hasCache()) return false;
        const SpecularTrace& st = specularTrace;
        if (st.sameView(camera, weights, s, specularCacheGeneration) && st.reduction <= reduction) return false;
        const auto start = std::chrono::steady_clock::now();
        const ImageRgb image = specularPaths->trace(camera, s, weights, reduction);
        specularSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        uploadSpecular(image);
        keep(keyOf(camera, weights, s, reduction));
        return true;
    }

    SpecularTrace keyOf(const Camera& camera, const LightWeights& weights, const CompositorSettings& s,
                        int reduction) const {
        SpecularTrace k;
        k.valid = true;
        k.camera = camera;
        k.weights = weights;
        k.settings = s;
        k.reduction = reduction;
        k.cacheGeneration = specularCacheGeneration;
        return k;
    }

    void requestSpecular(const Camera& camera, const LightWeights& weights, const CompositorSettings& s) {
        if (!specularPaths || !specularPaths->hasCache()) return;
        if (specularTrace.sameView(camera, weights, s, specularCacheGeneration) && specularTrace.reduction == 1)
            return;
        if (specularJob && specularJob->key.sameView(camera, weights, s, specularCacheGeneration)) return;
        cancelSpecularJob();
        SpecularJob job;
        job.key = keyOf(camera, weights, s, 1);
        job.cancel = std::make_shared<std::atomic<bool>>(false);
        const SpecularPaths* paths = specularPaths.get();
        job.image = std::async(std::launch::async, [paths, camera, weights, s, cancel = job.cancel] {
            return paths->trace(camera, s, weights, 1, cancel.get());
        });
        specularJob = std::move(job);
    }

    bool collectSpecular() {
        if (!specularJob ||
            specularJob->image.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
            return false;
        SpecularJob job = std::move(*specularJob);
        specularJob.reset();
        const ImageRgb image = job.image.get();  // rethrows the trace's exception
        const SpecularTrace& k = job.key;
        // Kept only while the view it was traced for is the one shown.
        if (!specularTrace.sameView(k.camera, k.weights, k.settings, specularCacheGeneration)) return false;
        uploadSpecular(image);
        keep(k);
        return true;
    }

    void setLuxFactors(const GlProgram& p) {
        const Rgb k = photometry.factors();
        gl.Uniform3f(p.uniform("uLuxFactors"), float(k.r), float(k.g), float(k.b));
    }

    void bindDisplayUniforms(const GlProgram& p, const DisplaySettings& d) {
        gl.Uniform1f(p.uniform("uExposure"), float(d.exposure));
        gl.Uniform1f(p.uniform("uLog10LuxMin"), float(std::log10(std::max(d.luxMin, 1e-30))));
        gl.Uniform1f(p.uniform("uLog10LuxMax"), float(std::log10(std::max(d.luxMax, 1e-30))));
        gl.Uniform1i(p.uniform("uPaletteSize"), GLint(falseColourPalette().size()));
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, paletteBuffer.id());
    }

    // Pass 3: the quantity per sub-pixel, for images read back.
    void ensureComposite() {
        ensureSurface();
        if (composited) return;
        baseState(t.width * t.supersample, t.height * t.supersample);
        gl.BindFramebuffer(GL_FRAMEBUFFER, t.compositeFb.id());
        const GlProgram& composite = compositeProgram(quantity);
        composite.use();
        bindCompositeInputs(composite);
        gl.BindVertexArray(emptyVao.id());
        gl.DrawArrays(GL_TRIANGLES, 0, 3);
        checkGl(gl, "compositing");
        composited = true;
    }

    // The box filter to pixels, on the GPU.
    void resolvePixels() {
        ensureComposite();
        if (resolved) return;
        baseState(t.width, t.height);
        gl.BindFramebuffer(GL_FRAMEBUFFER, t.pixelsFb.id());
        resolveProgram.use();
        gl.Uniform1i(resolveProgram.uniform("uSupersample"), t.supersample);
        gl.BindTextureUnit(2, t.composite.id());
        gl.BindVertexArray(emptyVao.id());
        gl.DrawArrays(GL_TRIANGLES, 0, 3);
        checkGl(gl, "resolving pixels");
        resolved = true;
    }

    void displayTo(GLuint framebuffer, const DisplaySettings& d) {
        ML_ASSERT(composed, "nothing composited yet");
        if (t.supersample == 1) {
            // One sample per pixel: the scene's faces shaded straight from
            // the irradiance, into a target with a float depth buffer (the
            // window's is fixed-point, too coarse for reversed depth), then
            // copied to the framebuffer.
            baseState(t.width, t.height);
            const float background[4] = {quantity == CompositeQuantity::Illuminance ? 0.08f : 0.0f,
                                         quantity == CompositeQuantity::Illuminance ? 0.08f : 0.0f,
                                         quantity == CompositeQuantity::Illuminance ? 0.08f : 0.0f, 1.0f};
            const float farDepth = 0.0f;
            gl.BindFramebuffer(GL_FRAMEBUFFER, t.forwardFb.id());
            gl.ClearBufferfv(GL_COLOR, 0, background);
            gl.ClearBufferfv(GL_DEPTH, 0, &farDepth);
            gl.Enable(GL_DEPTH_TEST);
            gl.DepthFunc(GL_GREATER);
            const GlProgram& forward = forwardProgram(quantity, d.op, d.contours);
            forward.use();
            gl.UniformMatrix4fv(forward.uniform("uClipFromLocal"), 1, GL_FALSE, &mvp[0][0]);
            setLuxFactors(forward);
            gl.BindTextureUnit(1, t.irradianceSum.id());
            gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, lightEmissionBuffer.id());
            bindSpecular(forward, t.height);
            bindDisplayUniforms(forward, d);
            drawSceneRanges(forward);
            gl.Disable(GL_DEPTH_TEST);
            gl.BlitNamedFramebuffer(t.forwardFb.id(), framebuffer, 0, 0, t.width, t.height, 0, 0, t.width, t.height,
                                    GL_COLOR_BUFFER_BIT, GL_NEAREST);
            // What is drawn next (the controls) goes where the image went.
            gl.BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
            forwarded = true;
        } else {
            ensureSurface();
            baseState(t.width, t.height);
            gl.BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
            const GlProgram& display = displayProgram(quantity, t.supersample, d.op, d.contours);
            display.use();
            bindCompositeInputs(display);
            bindDisplayUniforms(display, d);
            gl.BindVertexArray(emptyVao.id());
            gl.DrawArrays(GL_TRIANGLES, 0, 3);
        }
        checkGl(gl, "displaying the composite");
    }

    void drawWireframe(GLuint framebuffer, const GpuCacheMeshes& meshes, const std::vector<Rgb>& colours) {
        ML_ASSERT(composed && !colours.empty(), "wireframe before compose, or without colours");
        // The depth of the surfaces seen: the forward pass's, or the sub-pixels'.
        if (!forwarded) ensureSurface();
        baseState(t.width, t.height);
        gl.BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
        gl.Enable(GL_CULL_FACE);  // the side a cache triangle holds is its front
        gl.CullFace(GL_BACK);
        gl.FrontFace(GL_CCW);
        gl.Enable(GL_BLEND);
        gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
        gl.BlendEquation(GL_FUNC_ADD);
        wireframeProgram.use();
        gl.UniformMatrix4fv(wireframeProgram.uniform("uClipFromLocal"), 1, GL_FALSE, &mvp[0][0]);
        gl.Uniform1i(wireframeProgram.uniform("uSupersample"), forwarded ? 1 : t.supersample);
        gl.BindTextureUnit(0, forwarded ? t.forwardDepth.id() : t.sceneDepth.id());
        const size_t count = meshes.directCount() + meshes.indirectCount();
        for (size_t i = 0; i < count; ++i) {
            const GpuCacheMeshes::Mesh& m = i < meshes.directCount() ? meshes.direct(i)
                                                                     : meshes.indirect(i - meshes.directCount());
            if (m.triangleCount == 0) continue;
            const Rgb& c = colours[i % colours.size()];
            gl.Uniform3f(wireframeProgram.uniform("uColor"), float(c.r), float(c.g), float(c.b));
            gl.BindVertexArray(m.vertexArray());
            drawTriangles(m);
        }
        gl.Disable(GL_BLEND);
        gl.Disable(GL_CULL_FACE);
        checkGl(gl, "drawing the cache wireframe");
    }

    // Float rows of a framebuffer attachment, bottom row first.
    std::vector<float> readFloats(GLuint fb, GLenum attachment, GLenum format, int components, int x, int y, int w,
                                  int h) {
        std::vector<float> values(size_t(w) * h * components);
        if (attachment != GL_DEPTH_ATTACHMENT) gl.NamedFramebufferReadBuffer(fb, attachment);
        gl.BindFramebuffer(GL_READ_FRAMEBUFFER, fb);
        gl.PixelStorei(GL_PACK_ALIGNMENT, 4);
        gl.ReadPixels(x, y, w, h, format, GL_FLOAT, values.data());
        gl.BindFramebuffer(GL_READ_FRAMEBUFFER, 0);
        checkGl(gl, "reading the composite back");
        return values;
    }
    std::vector<float> readRgba(GLuint fb, int x, int y, int w, int h) {
        return readFloats(fb, GL_COLOR_ATTACHMENT0, GL_RGBA, 4, x, y, w, h);
    }
    // The sub-pixels of the part's clip, or of the whole target.
    EmitterOutlines::Rect clipOrWhole() const {
        return clip.empty() ? EmitterOutlines::Rect{0, 0, t.width * t.supersample, t.height * t.supersample} : clip;
    }
    // An RGBA sub-pixel target's `rect` (empty: its clipOrWhole()).
    std::vector<float> readTarget(GLuint fb, GLenum attachment, const EmitterOutlines::Rect& rect = {}) {
        const EmitterOutlines::Rect r = rect.empty() ? clipOrWhole() : rect;
        return readFloats(fb, attachment, GL_RGBA, 4, r.x, r.y, r.width, r.height);
    }
    // The image of readTarget()'s sub-pixels, box-filtered: black outside
    // the clip (which holds whole pixels), the same pixels inside.
    ImageRgb imageOf(const std::vector<float>& rgba) const {
        const EmitterOutlines::Rect r = clipOrWhole();
        const int s = t.supersample;
        ImageRgb pixels = boxDownsample(toImage(rgba, r.width, r.height), s);
        if (clip.empty()) return pixels;
        ImageRgb image(t.width, t.height);
        const int left = r.x / s, top = t.height - (r.y + r.height) / s;  // rows from the top
        for (int y = 0; y < pixels.height; ++y)
            for (int x = 0; x < pixels.width; ++x) image.set(left + x, top + y, pixels.at(x, y));
        return image;
    }

    static ImageRgb toImage(const std::vector<float>& rgba, int w, int h) {
        ImageRgb image(w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float* p = &rgba[(size_t(h - 1 - y) * w + x) * 4];  // GL rows start at the bottom
                const Rgb c(p[0], p[1], p[2]);
                ML_ASSERT(isFinite(c), "non-finite value at pixel ", x, ",", y);
                image.set(x, y, c);
            }
        return image;
    }

    ImageRgb readImage() {
        ensureComposite();
        return imageOf(readTarget(t.compositeFb.id(), GL_COLOR_ATTACHMENT0));
    }

    // The illuminance composite box-filtered on the CPU: per pixel the sums
    // of lux × seen and of seen over its sub-pixels.
    LuxImage readIlluminanceImage() {
        ML_ASSERT(quantity == CompositeQuantity::Illuminance, "the last composite is not illuminance");
        ensureComposite();
        const int s = t.supersample, w = t.width * s, h = t.height * s;
        const std::vector<float> rgba = readRgba(t.compositeFb.id(), 0, 0, w, h);
        LuxImage out;
        out.width = t.width;
        out.height = t.height;
        out.lux.resize(size_t(t.width) * size_t(t.height));
        out.coverage.resize(out.lux.size());
        for (int y = 0; y < t.height; ++y)
            for (int x = 0; x < t.width; ++x) {
                double lux = 0, seen = 0;
                for (int dy = 0; dy < s; ++dy)
                    for (int dx = 0; dx < s; ++dx) {
                        // GL rows start at the bottom.
                        const float* p = &rgba[(size_t(h - 1 - (y * s + dy)) * size_t(w) + size_t(x * s + dx)) * 4];
                        ML_ASSERT(std::isfinite(p[0]), "non-finite lux at pixel ", x, ",", y);
                        lux += p[0];
                        seen += p[3];
                    }
                out.lux[out.index(x, y)] = seen > 0 ? float(lux / seen) : 0.0f;
                out.coverage[out.index(x, y)] = float(seen / double(s * s));
            }
        return out;
    }

    ImageRgb readPixels() {
        resolvePixels();
        return toImage(readRgba(t.pixelsFb.id(), 0, 0, t.width, t.height), t.width, t.height);
    }

    // From the sub-pixels' irradiance and coverage, without a full-screen pass
    // (the forward pass's depth says what is covered when it ran).
    std::optional<double> readIlluminance(int x, int y) {
        ML_ASSERT(composed, "nothing composited yet");
        if (x < 0 || y < 0 || x >= t.width || y >= t.height) return std::nullopt;
        const int s = t.supersample, gx = x * s, gy = (t.height - 1 - y) * s;
        std::vector<bool> covered(size_t(s) * s);
        if (forwarded) {
            covered[0] = readFloats(t.forwardFb.id(), GL_DEPTH_ATTACHMENT, GL_DEPTH_COMPONENT, 1, x, t.height - 1 - y,
                                    1, 1)[0] > 0;
        } else {
            ensureSurface();
            const std::vector<float> surface = readRgba(t.surfaceFb.id(), gx, gy, s, s);
            for (size_t i = 0; i < covered.size(); ++i) covered[i] = surface[4 * i + 3] > 0;
        }
        const std::vector<float> e = readRgba(t.irradianceFb.id(), gx, gy, s, s);
        double sum = 0;
        int count = 0;
        for (size_t i = 0; i < covered.size(); ++i)
            if (covered[i]) {
                sum += photometry.luminous(Rgb(e[4 * i], e[4 * i + 1], e[4 * i + 2]));
                ++count;
            }
        if (count == 0) return std::nullopt;
        return sum / count;
    }
};

Compositor::Compositor(GlContext& context, const Scene& scene)
    : impl_(std::make_unique<Impl>(context, scene)) {}
Compositor::~Compositor() = default;

ImageRgb Compositor::render(const Camera& camera, const std::vector<IrradianceMeshCopy>& direct,
                            const CompositorSettings& settings) {
    return render(camera, direct, {}, settings);
}

ImageRgb Compositor::render(const Camera& camera, const std::vector<IrradianceMeshCopy>& direct,
                            const std::vector<IrradianceMeshCopy>& indirect, const CompositorSettings& settings) {
    ML_ASSERT(direct.size() == impl_->scene.lights.size() || direct.size() == impl_->scene.lights.size() + 1,
              direct.size(), " meshes for ", impl_->scene.lights.size(), " lights");
    const GpuCacheMeshes meshes = upload(direct, indirect);
    setSpecularCache(direct, indirect);
    return composite(camera, meshes, LightWeights::unit(impl_->scene.lights.size()), settings);
}

bool Compositor::hasSpecularPass() const { return impl_->specularPaths != nullptr; }

void Compositor::setSpecularCache(const std::vector<IrradianceMeshCopy>& direct,
                                  const std::vector<IrradianceMeshCopy>& indirect) {
    if (!impl_->specularPaths) return;
    impl_->specularPaths->setCache(direct, indirect);
    ++impl_->specularCacheGeneration;
    impl_->recentSpecular.clear();
}

bool Compositor::traceSpecular(const Camera& camera, const LightWeights& weights, const CompositorSettings& settings,
                               int reduction) {
    return impl_->traceSpecular(camera, weights, settings, reduction);
}

void Compositor::requestSpecular(const Camera& camera, const LightWeights& weights, const CompositorSettings& settings) {
    impl_->requestSpecular(camera, weights, settings);
}

bool Compositor::collectSpecular() { return impl_->collectSpecular(); }

bool Compositor::specularPending() const { return impl_->specularJob.has_value(); }

double Compositor::specularSeconds() const { return impl_->specularSeconds; }

ImageRgb Compositor::composite(const Camera& camera, const GpuCacheMeshes& meshes, const LightWeights& weights,
                               const CompositorSettings& settings, ImageRgb* spread) {
    return composite(camera, meshes, weights, settings, spread, nullptr);
}

std::vector<ImageRgb> Compositor::composite(const Camera& camera, const GpuCacheMeshes& meshes,
                                            const std::vector<LightWeights>& parts,
                                            const CompositorSettings& settings) {
    // The outlines' surface passes of the first part of each emission,
    // which the parts after it with the same emission take as they are.
    std::vector<EmitterOutlines> drawn;
    std::vector<ImageRgb> images;
    for (const LightWeights& w : parts) images.push_back(composite(camera, meshes, w, settings, nullptr, &drawn));
    return images;
}

std::vector<double> Compositor::partShares(const Camera& camera, const GpuCacheMeshes& meshes,
                                           const std::vector<LightWeights>& parts,
                                           const CompositorSettings& settings) const {
    settings.validate();
    const bool clips = settings.quantity == CompositeQuantity::Radiance &&
                       (!hasSpecularPass() || settings.specular == SpecularPart::Off);
    const glm::mat4 mvp = impl_->clipFromLocal(camera, double(settings.width) / settings.height);
    const double all = double(settings.width) * settings.height * settings.supersample * settings.supersample;
    std::vector<double> shares;
    for (const LightWeights& w : parts) {
        const EmitterOutlines::Rect r =
            clips ? partRect(impl_->scene, mvp, settings.width, settings.height, settings.supersample, meshes, w)
                  : EmitterOutlines::Rect{};
        shares.push_back(r.empty() ? 1.0 : double(r.width) * r.height / all);
    }
    return shares;
}

ImageRgb Compositor::composite(const Camera& camera, const GpuCacheMeshes& meshes, const LightWeights& weights,
                               const CompositorSettings& settings, ImageRgb* spread,
                               std::vector<EmitterOutlines>* drawn) {
    const int passes = std::max(1, settings.passes);
    const bool outlines = settings.outlinePasses > 0 && settings.quantity == CompositeQuantity::Radiance &&
                          settings.specular != SpecularPart::Only && !impl_->scene.lights.empty();
    if (passes == 1 && !outlines) {
        impl_->traceSpecularFor(camera, weights, settings);
        impl_->compose(camera, meshes, weights, settings, drawn != nullptr);
        ImageRgb image = impl_->readImage();
        if (spread) *spread = ImageRgb(image.width, image.height);
        return image;
    }
    std::optional<EmitterOutlines> edges;
    if (outlines)
        edges.emplace(settings.width, settings.height, settings.supersample, emittedRadiance(impl_->scene, weights));
    const RookPattern rook(passes);
    const int odds = rook.odds(), evens = passes - odds;  // used with two passes or more: each half has one
    ImageRgb sum;
    std::vector<double> odd;  // Σ over the odd half
    std::vector<float> subPixels;
    bool clipped = false;  // some pass only composited where the part can be non-zero
    for (int k = 0; k < passes; ++k) {
        const CompositorSettings s = passes > 1 ? rook.shifted(settings, k) : settings;
        impl_->traceSpecularFor(camera, weights, s);
        impl_->compose(camera, meshes, weights, s, drawn != nullptr);
        clipped = clipped || !impl_->clip.empty();
        const ImageRgb image = edges ? impl_->readImage(subPixels) : impl_->readImage();
        if (edges) edges->addFullPass(subPixels, impl_->readSurfaceSubPixels());
        if (k == 0) sum = image;
        else
            for (size_t i = 0; i < sum.data.size(); ++i) sum.data[i] += image.data[i];
        if (spread && passes > 1 && rook.odd(k)) {
            odd.resize(image.data.size(), 0.0);
            for (size_t i = 0; i < image.data.size(); ++i) odd[i] += image.data[i];
        }
    }
    if (spread) {
        *spread = ImageRgb(sum.width, sum.height);
        // With independent errors of one size, the mean of both halves errs
        // by half their difference.
        if (passes > 1)
            for (size_t i = 0; i < sum.data.size(); ++i) {
                const double b = odd[i] / odds, a = (double(sum.data[i]) - odd[i]) / evens;
                spread->data[i] = float(0.5 * std::abs(a - b));
            }
    }
    for (float& v : sum.data) v /= float(passes);
    if (edges) {
        const EmitterOutlines* same = nullptr;
        if (drawn)
            for (const EmitterOutlines& o : *drawn)
                if (!same && o.sharesSurfacePasses(*edges)) same = &o;
        if (same) {
            edges->copySurfacePasses(*same);
        } else {
            const EmitterOutlines::Rect bounds = edges->emitterBounds();
            int count = settings.outlinePasses, from = 0;
            const auto surfacePass = [&](const RookPattern& fine, int k) {
                impl_->drawSurfacesOnly(camera, fine.shifted(settings, k), bounds);
                edges->addSurfacePass(impl_->readSurfaceSubPixels(bounds), fine.odd(k));
            };
            if (settings.outlineSeconds > 0 && count > 1 && !bounds.empty()) {
                // The first pass timed. Fewer passes are a pattern of their
                // own (a prefix of the rook pattern would cover one side of
                // the sub-pixel): the timed pass is dropped, unless one is
                // all that fits (any one shift is as good a grid).
                const auto start = std::chrono::steady_clock::now();
                surfacePass(RookPattern(count), 0);
                const double one = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
                const int fit = outlinePassesWithin(count, one, settings.outlineSeconds);
                from = 1;
                if (fit < count && fit > 1) {
                    edges->clearSurfacePasses();
                    from = 0;
                }
                count = fit;
            }
            const RookPattern fine(count);
            for (int k = from; k < count && !bounds.empty(); ++k) surfacePass(fine, k);
        }
        edges->apply(sum, spread);
        // Kept for the parts after this one (moved: this part is done with
        // it), one per distinct emission: render's layers keep two. Not
        // those of a clipped part: its surface passes cover its clip only.
        if (drawn && !same && !clipped) drawn->push_back(std::move(*edges));
    }
    return sum;
}

GpuCacheMeshes Compositor::upload(const std::vector<IrradianceMeshCopy>& direct,
                                  const std::vector<IrradianceMeshCopy>& indirect) const {
    GpuCacheMeshes meshes(impl_->gl, impl_->origin);
    meshes.upload(direct, indirect);
    return meshes;
}

LuxImage Compositor::renderIlluminance(const Camera& camera, const std::vector<IrradianceMeshCopy>& direct,
                                      const std::vector<IrradianceMeshCopy>& indirect, CompositorSettings settings) {
    GpuCacheMeshes meshes(impl_->gl, impl_->origin);
    meshes.upload(direct, indirect);
    settings.quantity = CompositeQuantity::Illuminance;
    impl_->compose(camera, meshes, LightWeights::unit(impl_->scene.lights.size()), settings);
    return impl_->readIlluminanceImage();
}

void Compositor::compose(const Camera& camera, const GpuCacheMeshes& meshes, const LightWeights& weights,
                         const CompositorSettings& settings) {
    impl_->compose(camera, meshes, weights, settings);
}

void Compositor::display(uint32_t framebuffer, const DisplaySettings& display) { impl_->displayTo(framebuffer, display); }

void Compositor::drawWireframe(uint32_t framebuffer, const GpuCacheMeshes& meshes, const std::vector<Rgb>& colours) {
    impl_->drawWireframe(framebuffer, meshes, colours);
}

ImageRgb Compositor::readPixels() { return impl_->readPixels(); }

std::optional<double> Compositor::readIlluminance(int x, int y) { return impl_->readIlluminance(x, y); }

ImageRgb Compositor::readImage() { return impl_->readImage(); }

size_t Compositor::drawnTriangles() const { return impl_->drawnTriangles; }

}  // namespace ml
