#include "TriangleGather.h"

#include "core/Error.h"
#include "core/Random.h"
#include "detail/GatherReadback.h"
#include "detail/ProxyClustersGpu.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/gl/GlObjects.h"
#include "meshlight_gpu_shaders.h"

#include <chrono>
#include <cmath>

namespace ml {

const char* triangleProjectionName(TriangleProjection projection) {
    switch (projection) {
        case TriangleProjection::Perspective:
            return "perspective";
        case TriangleProjection::Hemicube:
            return "hemicube";
        case TriangleProjection::Fisheye:
            return "fisheye-triangles";
    }
    return "?";
}

void TriangleGatherSettings::validate() const {
    if (imageSize < 4 || imageSize > 2048)
        throw InputError(concat("gather image size ", imageSize, " is not in 4..2048"));
    if (projection == TriangleProjection::Hemicube && imageSize % 2 != 0)
        throw InputError(concat("hemicube face size ", imageSize, " is odd: its side faces are N x N/2"));
    if (resolution < 2 || resolution > 512)
        throw InputError(concat("proxy resolution ", resolution, " is not in 2..512"));
    if (!(fieldOfViewDegrees > 0 && fieldOfViewDegrees <= 176))
        throw InputError(concat("perspective field of view ", fieldOfViewDegrees, " degrees is not in (0, 176]"));
    if (clusterVoxels < 1 || clusterVoxels > 64)
        throw InputError(concat("cluster size ", clusterVoxels, " voxels is not in 1..64"));
    if (!(tessellationDegrees == 0 || (tessellationDegrees >= 0.5 && tessellationDegrees <= 90)))
        throw InputError(concat("tessellation angle ", tessellationDegrees, " degrees is neither 0 nor in 0.5..90"));
}

double planeRectangleWeight(double x0, double x1, double y0, double y1) {
    // ∫₀^X∫₀^Y dy dx / (1 + x² + y²)², odd in X and in Y.
    auto corner = [](double X, double Y) {
        const double cx = std::sqrt(1 + X * X), cy = std::sqrt(1 + Y * Y);
        return 0.5 * (X / cx * std::atan(Y / cx) + Y / cy * std::atan(X / cy));
    };
    return corner(x1, y1) - corner(x0, y1) - corner(x1, y0) + corner(x0, y0);
}

double sideRectangleWeight(double y0, double y1, double z0, double z1) {
    // ∫₀^Y∫₀^Z z dz dy / (1 + y² + z²)², odd in Y.
    auto corner = [](double Y, double Z) {
        const double c = std::sqrt(1 + Z * Z);
        return 0.5 * (std::atan(Y) - std::atan(Y / c) / c);
    };
    return corner(y1, z1) - corner(y0, z1) - corner(y1, z0) + corner(y0, z0);
}

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double unit(uint32_t h) { return (double(h) + 0.5) * (1.0 / 4294967296.0); }

// One vertex of a tessellated piece: position relative to the grid's origin,
// normal and closed flag, radiance (ten floats, as the piece VAO reads them).
constexpr int kPieceFloats = 10;
// Deep enough for an edge at 1e-6 of its length from the eye.
constexpr int kMaxTessellationDepth = 20;
// Pieces one gather may make, whatever the angle asked.
constexpr size_t kMaxPieces = size_t(1) << 18;

}  // namespace

struct TriangleGather::Gpu {
    GlProgram program;
    GlTexture color, depth;
    GlFramebuffer fb;
    GlBuffer indexBuffer;  // the culled triangles' indices, view by view
    size_t indexCapacity = 0;
    // Fish-eye tessellation: the pieces (TriangleGather::pieces_) and how they are read.
    GlBuffer pieceBuffer;
    size_t pieceCapacity = 0;
    GlVertexArray pieceVao;
    std::map<size_t, GlBuffer> radiance;  // per slot: ProxyClusters::Gpu::uploadRadiance
};

TriangleGather::TriangleGather(GlContext& context, const Scene& scene, const TriangleGatherSettings& settings)
    : context_(context),
      settings_((settings.validate(), settings)),
      proxy_(scene, VoxelGrid::fit(scene.bounds, settings.resolution)),
      clusters_(context, proxy_, settings.clusterVoxels),
      eyeRule_(proxy_),
      gpu_(std::make_unique<Gpu>()) {
    const GlApi& gl = context_.gl();
    Gpu& g = *gpu_;
    const int n = settings_.imageSize;
    switch (settings_.projection) {
        case TriangleProjection::Perspective: {
            const double a = std::tan(0.5 * settings_.fieldOfViewDegrees * kPi / 180.0);
            View v;
            v.left = v.bottom = -a;
            v.right = v.top = a;
            v.width = v.height = n;
            views_ = {v};
            atlasWidth_ = atlasHeight_ = n;
            break;
        }
        case TriangleProjection::Hemicube: {
            View top;
            top.width = top.height = n;
            views_ = {top};
            // Side faces: forward r, u, −r, −u; the upper half of a 90° view.
            const int at[4][2] = {{n, 0}, {n, n / 2}, {0, n}, {n, n}};
            for (int k = 0; k < 4; ++k) {
                View s;
                s.forward = k % 2;
                s.negate = k >= 2;
                s.bottom = 0;
                s.x = at[k][0];
                s.y = at[k][1];
                s.width = n;
                s.height = n / 2;
                views_.push_back(s);
            }
            atlasWidth_ = 2 * n;
            atlasHeight_ = n + n / 2;
            break;
        }
        case TriangleProjection::Fisheye: {
            View v;
            v.width = v.height = n;
            views_ = {v};
            atlasWidth_ = atlasHeight_ = n;
            break;
        }
    }
    // Weights per atlas pixel.
    weights_.assign(size_t(atlasWidth_) * atlasHeight_, 0.0);
    for (size_t k = 0; k < views_.size(); ++k) {
        const View& v = views_[k];
        const bool side = settings_.projection == TriangleProjection::Hemicube && k > 0;
        for (int j = 0; j < v.height; ++j)
            for (int i = 0; i < v.width; ++i) {
                double w;
                if (settings_.projection == TriangleProjection::Fisheye) {
                    // Equal projected solid angle: (2/N)² of the unit disc
                    // per pixel whose sample point the triangles cover.
                    w = 4.0 / (double(n) * n);
                } else {
                    const double x0 = v.left + (v.right - v.left) * i / v.width;
                    const double x1 = v.left + (v.right - v.left) * (i + 1) / v.width;
                    const double y0 = v.bottom + (v.top - v.bottom) * j / v.height;
                    const double y1 = v.bottom + (v.top - v.bottom) * (j + 1) / v.height;
                    w = side ? sideRectangleWeight(x0, x1, y0, y1) : planeRectangleWeight(x0, x1, y0, y1);
                }
                weights_[size_t(v.y + j) * atlasWidth_ + size_t(v.x + i)] = w;
            }
    }
    if (settings_.projection != TriangleProjection::Fisheye) {
        double total = 0;
        for (double w : weights_) total += w;
        coverage_ = total / kPi;
    }

    const bool fisheye = settings_.projection == TriangleProjection::Fisheye;
    for (const ProxyTriangle& t : proxy_.triangles())
        for (int k = 0; k < 3; ++k)
            maxProxyEdge_ = std::max(maxProxyEdge_, glm::length(proxy_.positions()[t.corners[k]] -
                                                                proxy_.positions()[t.corners[(k + 1) % 3]]));
    if (fisheye) {
        g.pieceVao = makeVertexArray(gl);
        const int counts[] = {3, 4, 3};
        GLuint offset = 0;
        for (GLuint i = 0; i < 3; ++i) {
            gl.EnableVertexArrayAttrib(g.pieceVao.id(), i);
            gl.VertexArrayAttribFormat(g.pieceVao.id(), i, counts[i], GL_FLOAT, GL_FALSE, offset);
            gl.VertexArrayAttribBinding(g.pieceVao.id(), i, 0);
            offset += GLuint(counts[i] * sizeof(float));
        }
    }
    g.program = GlProgram(
        gl,
        {{GL_VERTEX_SHADER, fisheye ? "gather_triangles_fisheye.vert" : "gather_triangles_perspective.vert",
          glslSource({fisheye ? shaders::gather_triangles_fisheye_vert : shaders::gather_triangles_perspective_vert})},
         {GL_FRAGMENT_SHADER, "gather_triangles.frag",
          glslSource({fisheye ? "#define FISHEYE_DEPTH\n" : "", shaders::gather_triangles_frag})}});
    g.color = makeTexture2D(gl, GL_RGBA32F, atlasWidth_, atlasHeight_);
    g.depth = makeTexture2D(gl, GL_DEPTH_COMPONENT32F, atlasWidth_, atlasHeight_);
    g.fb = makeFramebuffer(gl, {g.color.id()}, g.depth.id(), "triangle gather");
    gl.NamedFramebufferReadBuffer(g.fb.id(), GL_COLOR_ATTACHMENT0);
    pixels_.resize(size_t(atlasWidth_) * atlasHeight_ * 4);
    checkGl(gl, "creating the triangle gather");
}

TriangleGather::~TriangleGather() = default;

void TriangleGather::setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double) {
    const auto t0 = Clock::now();
    std::vector<Rgb> radiance = proxy_.radianceFrom(irradiance);
    GlBuffer buffer = clusters_.gpu().uploadRadiance(radiance);
    radiance_[slot] = std::move(radiance);
    gpu_->radiance[slot] = std::move(buffer);
    checkGl(context_.gl(), "uploading the proxy's radiance");
    stats_.buildSeconds += since(t0);
    stats_.source =
        concat(proxy_.grid().describe(), " voxels: proxy of ", proxy_.triangles().size(), " triangles in ",
               clusters_.clusterCount(), " clusters, ", memoryBytes() / 1e6, " MB; built in ", since(t0), " s");
}

void TriangleGather::releaseSource(size_t slot) {
    radiance_.erase(slot);
    gpu_->radiance.erase(slot);
}

Rgb TriangleGather::estimate(size_t slot, const Vec3& x, const Vec3& normal, uint32_t seed) {
    GatherReadback readback(phases_, stats_, timePhases_);
    const std::vector<Rgb>& radiance = radiance_.at(slot);
    Gpu& g = *gpu_;
    const GlBuffer& radianceBuffer = g.radiance.at(slot);
    const VoxelGrid& grid = proxy_.grid();
    const GlApi& gl = context_.gl();
    const bool fisheye = settings_.projection == TriangleProjection::Fisheye;

    // The tangent frame, turned about the normal by the seed's angle.
    const Vec3 n = glm::normalize(normal);
    Vec3 r, u;
    orthonormalBasis(n, r, u);
    Vec2 shift(0.0);
    if (settings_.jitter) {
        const double angle = 2 * kPi * unit(hash32(seed ^ 0x2545f491u));
        const Vec3 r0 = r;
        r = std::cos(angle) * r0 + std::sin(angle) * u;
        u = glm::cross(n, r);
        shift = (Vec2(unit(hash32(seed ^ 0x9e3779b9u)), unit(hash32(seed ^ 0x7f4a7c15u))) - 0.5) *
                (2.0 / settings_.imageSize);
    }
    // The slice gather's eye: lifted off the surface, and on an edge or in a
    // corner moved a hair into its own surface, so that the surfaces meeting
    // there stand in front of it rather than through it.
    const double diagonal = glm::length(grid.upper() - grid.origin);
    const double lift = 1e-6 * diagonal;
    const Vec3 eye = eyeRule_.eye(x, n);
    const Vec3 eyeRel = eye - grid.origin;
    const Vec3 frame[3] = {r, u, n};

    // Culling, view by view, into one index buffer.
    struct ViewFrame {
        Vec3 right, up, forward;
        size_t first = 0, count = 0;  // triangles in indices_
    };
    std::vector<ViewFrame> cameras(views_.size());
    indices_.clear();
    for (size_t k = 0; k < views_.size(); ++k) {
        const View& v = views_[k];
        ViewFrame& c = cameras[k];
        c.forward = v.negate ? -frame[v.forward] : frame[v.forward];
        if (v.forward == 2) {
            c.right = r;
            c.up = u;
        } else {
            c.up = n;
            c.right = glm::cross(c.forward, n);
        }
        std::vector<ViewPlane> planes;
        if (!fisheye)
            planes = {{c.right - v.left * c.forward},
                      {v.right * c.forward - c.right},
                      {c.up - v.bottom * c.forward},
                      {v.top * c.forward - c.up}};
        c.first = indices_.size() / 3;
        const bool tessellate = fisheye && settings_.tessellationDegrees > 0;
        const double angle = settings_.tessellationDegrees * kPi / 180;
        // An edge of length e at distance d spans at most e/d.
        c.count = clusters_.cull(x, n, lift, eye, planes, indices_, tessellate ? maxProxyEdge_ / angle : 0.0,
                                 tessellate ? &nearTriangles_ : nullptr);
    }
    lastTriangles_ = indices_.size() / 3;
    if (fisheye && settings_.tessellationDegrees > 0) tessellate(radiance, x, n, lift, eye);
    nearTriangles_.clear();
    if (indices_.size() > g.indexCapacity) {
        g.indexCapacity = std::max(indices_.size(), 2 * g.indexCapacity);
        g.indexBuffer = makeBuffer(gl, g.indexCapacity * sizeof(uint32_t), nullptr, GL_DYNAMIC_DRAW);
    }
    if (!indices_.empty())
        gl.NamedBufferSubData(g.indexBuffer.id(), 0, GLsizeiptr(indices_.size() * sizeof(uint32_t)), indices_.data());
    const size_t pieceVertices = pieces_.size() / kPieceFloats;
    if (pieceVertices > 0) {
        if (pieces_.size() > g.pieceCapacity) {
            g.pieceCapacity = std::max(pieces_.size(), 2 * g.pieceCapacity);
            g.pieceBuffer = makeBuffer(gl, g.pieceCapacity * sizeof(float), nullptr, GL_DYNAMIC_DRAW);
            gl.VertexArrayVertexBuffer(g.pieceVao.id(), 0, g.pieceBuffer.id(), 0, kPieceFloats * sizeof(float));
        }
        gl.NamedBufferSubData(g.pieceBuffer.id(), 0, GLsizeiptr(pieces_.size() * sizeof(float)), pieces_.data());
        lastTriangles_ += pieceVertices / 3;
    }
    readback.cpuDone();

    // Draw. Every state the pass relies on is set here: other passes share the context.
    const GlProgram& program = g.program;
    gl.BindFramebuffer(GL_FRAMEBUFFER, g.fb.id());
    gl.Viewport(0, 0, atlasWidth_, atlasHeight_);
    gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl.DepthMask(GL_TRUE);
    const float clear[4] = {0, 0, 0, 0};
    const float farDepth = fisheye ? 1.0f : 0.0f;  // perspective: reversed depth, 0 is infinitely far
    gl.ClearBufferfv(GL_COLOR, 0, clear);
    gl.ClearBufferfv(GL_DEPTH, 0, &farDepth);
    gl.Enable(GL_DEPTH_TEST);
    gl.DepthFunc(fisheye ? GL_LESS : GL_GREATER);
    gl.Disable(GL_BLEND);
    gl.Disable(GL_CULL_FACE);
    gl.Disable(GL_DEPTH_CLAMP);  // the near plane clips
    if (fisheye) {
        gl.Enable(GL_CLIP_DISTANCE0);
    } else {
        gl.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    }
    program.use();
    gl.Uniform3f(program.uniform("eye"), float(eyeRel.x), float(eyeRel.y), float(eyeRel.z));
    gl.Uniform1f(program.uniform("maxDistance"), float(2 * diagonal));
    const GlVertexArray& vao = clusters_.gpu().vao;
    gl.VertexArrayVertexBuffer(vao.id(), 1, radianceBuffer.id(), 0, sizeof(glm::vec3));
    gl.VertexArrayElementBuffer(vao.id(), g.indexBuffer.id());
    gl.BindVertexArray(vao.id());
    const double nearDistance = 1e-7 * diagonal;
    if (fisheye) {
        const glm::mat3 basis{glm::vec3(r), glm::vec3(u), glm::vec3(n)};
        gl.UniformMatrix3fv(program.uniform("basis"), 1, GL_FALSE, &basis[0][0]);
        gl.Uniform2f(program.uniform("shift"), float(shift.x), float(shift.y));
    }
    for (size_t k = 0; k < views_.size(); ++k) {
        const View& v = views_[k];
        const ViewFrame& c = cameras[k];
        if (c.count == 0) continue;
        gl.Viewport(v.x, v.y, v.width, v.height);
        if (!fisheye) {
            // Camera coordinates (X, Y, D) of origin-relative positions, then
            // the off-axis projection with z_clip = near and w = D.
            Mat4 view(1.0);
            for (int col = 0; col < 3; ++col) {
                view[col][0] = c.right[col];
                view[col][1] = c.up[col];
                view[col][2] = c.forward[col];
            }
            view[3][0] = -glm::dot(c.right, eyeRel);
            view[3][1] = -glm::dot(c.up, eyeRel);
            view[3][2] = -glm::dot(c.forward, eyeRel);
            Mat4 proj(0.0);  // column-major: proj[col][row]
            proj[0][0] = 2.0 / (v.right - v.left);
            proj[2][0] = -(v.right + v.left) / (v.right - v.left);
            proj[1][1] = 2.0 / (v.top - v.bottom);
            proj[2][1] = -(v.top + v.bottom) / (v.top - v.bottom);
            proj[3][2] = nearDistance;
            proj[2][3] = 1.0;
            const glm::mat4 clipFromOrigin(proj * view);
            gl.UniformMatrix4fv(program.uniform("clipFromOrigin"), 1, GL_FALSE, &clipFromOrigin[0][0]);
        }
        gl.DrawElements(GL_TRIANGLES, GLsizei(3 * c.count), GL_UNSIGNED_INT,
                        reinterpret_cast<const void*>(3 * c.first * sizeof(uint32_t)));
    }
    if (pieceVertices > 0) {
        gl.Viewport(0, 0, atlasWidth_, atlasHeight_);
        gl.BindVertexArray(g.pieceVao.id());
        gl.DrawArrays(GL_TRIANGLES, 0, GLsizei(pieceVertices));
    }
    if (fisheye) {
        gl.Disable(GL_CLIP_DISTANCE0);
    } else {
        gl.ClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);  // GL's default, which other passes assume
    }
    // Each atlas pixel weighted by its ∫cosθ dω.
    auto sum = [&] {
        readRgba(gl, atlasWidth_, atlasHeight_, pixels_);
        Rgb e(0.0);
        for (size_t p = 0; p < weights_.size(); ++p)
            e += weights_[p] * Rgb(pixels_[4 * p], pixels_[4 * p + 1], pixels_[4 * p + 2]);
        return e;
    };
    return readback.finish(gl, sum, "gathering indirect light from triangles", x);
}

void TriangleGather::tessellate(const std::vector<Rgb>& radiance, const Vec3& x, const Vec3& n, double lift,
                                const Vec3& eye) {
    pieces_.clear();
    const VoxelGrid& grid = proxy_.grid();
    const std::vector<Vec3>& positions = proxy_.positions();
    // Chord between unit directions for the largest angle allowed.
    const double chord = 2 * std::sin(0.5 * settings_.tessellationDegrees * kPi / 180);
    struct Piece {
        Vec3 p[3];
        Rgb l[3];
        int depth;
    };
    std::vector<Piece> stack;
    for (uint32_t t : nearTriangles_) {
        const ProxyTriangle& pt = proxy_.triangles()[t];
        Piece root;
        bool above = false;
        for (int k = 0; k < 3; ++k) {
            root.p[k] = positions[pt.corners[k]];
            root.l[k] = radiance[pt.corners[k]];
            above = above || glm::dot(root.p[k] - x, n) > lift;
        }
        if (!above || (!pt.closed && glm::dot(pt.normal, eye - root.p[0]) <= 0)) continue;
        const glm::vec4 normalClosed(glm::vec3(pt.normal), pt.closed ? 1.f : 0.f);
        root.depth = 0;
        stack.push_back(root);
        while (!stack.empty()) {
            const Piece q = stack.back();
            stack.pop_back();
            Vec3 d[3];
            for (int k = 0; k < 3; ++k) d[k] = glm::normalize(q.p[k] - eye);
            const double widest =
                std::max({glm::length(d[0] - d[1]), glm::length(d[1] - d[2]), glm::length(d[2] - d[0])});
            if (widest > chord && q.depth < kMaxTessellationDepth && pieces_.size() < kMaxPieces * 3 * kPieceFloats) {
                // 1 into 4 at the edges' midpoints.
                Vec3 mp[3];
                Rgb ml[3];
                for (int k = 0; k < 3; ++k) {
                    mp[k] = 0.5 * (q.p[k] + q.p[(k + 1) % 3]);
                    ml[k] = 0.5 * (q.l[k] + q.l[(k + 1) % 3]);
                }
                stack.push_back({{q.p[0], mp[0], mp[2]}, {q.l[0], ml[0], ml[2]}, q.depth + 1});
                stack.push_back({{mp[0], q.p[1], mp[1]}, {ml[0], q.l[1], ml[1]}, q.depth + 1});
                stack.push_back({{mp[2], mp[1], q.p[2]}, {ml[2], ml[1], q.l[2]}, q.depth + 1});
                stack.push_back({{mp[0], mp[1], mp[2]}, {ml[0], ml[1], ml[2]}, q.depth + 1});
                continue;
            }
            for (int k = 0; k < 3; ++k) {
                const glm::vec3 p(q.p[k] - grid.origin);
                const glm::vec3 l(q.l[k]);
                const float v[kPieceFloats] = {
                    p.x, p.y, p.z, normalClosed.x, normalClosed.y, normalClosed.z, normalClosed.w, l.x, l.y, l.z};
                pieces_.insert(pieces_.end(), v, v + kPieceFloats);
            }
        }
    }
}

size_t TriangleGather::memoryBytes() const {
    size_t bytes = proxy_.memoryBytes() + clusters_.memoryBytes();
    for (const auto& [slot, radiance] : radiance_) bytes += radiance.size() * (sizeof(Rgb) + sizeof(glm::vec3));
    return bytes;
}

IndirectStats TriangleGather::stats() const {
    IndirectStats s = stats_;
    s.sourceBytes = memoryBytes();
    return s;
}

}  // namespace ml
