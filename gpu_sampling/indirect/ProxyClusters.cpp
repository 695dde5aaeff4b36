#include "ProxyClusters.h"

#include "core/Error.h"
#include "detail/ProxyClustersGpu.h"
#include "gpu_sampling/gl/GlContext.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <unordered_map>

namespace ml {

namespace {

struct ClusterVertex {
    glm::vec3 position;
    glm::vec4 normalClosed;
};

}  // namespace

ProxyClusters::ProxyClusters(GlContext& context, const RadianceProxy& proxy, int blockVoxels)
    : gpu_(std::make_unique<Gpu>()) {
    ML_ASSERT(blockVoxels >= 1, "cluster block of ", blockVoxels, " voxels");
    const GlApi& gl = context.gl();
    gpu_->gl = &gl;
    gpu_->positionCount = proxy.positions().size();
    const VoxelGrid& grid = proxy.grid();
    const std::vector<Vec3>& positions = proxy.positions();
    const std::vector<ProxyTriangle>& triangles = proxy.triangles();

    // Key: block of the triangle's centroid, and the side it belongs to. The
    // proxy's pieces of one side of one scene triangle share their normal
    // exactly (RadianceProxy computes it once), so the normal's bits name the side.
    std::array<int, 3> blocks{};
    for (int a = 0; a < 3; ++a) blocks[size_t(a)] = (grid.dims[size_t(a)] + blockVoxels - 1) / blockVoxels;
    struct Key {
        size_t block;
        double nx, ny, nz;
        bool closed;
        bool operator==(const Key& o) const {
            return block == o.block && std::memcmp(&nx, &o.nx, sizeof(double)) == 0 &&
                   std::memcmp(&ny, &o.ny, sizeof(double)) == 0 && std::memcmp(&nz, &o.nz, sizeof(double)) == 0 &&
                   closed == o.closed;
        }
    };
    struct KeyHash {
        size_t operator()(const Key& k) const {
            auto bits = [](double d) {
                uint64_t u;
                std::memcpy(&u, &d, sizeof u);
                return u;
            };
            uint64_t h = k.block * 0x9e3779b97f4a7c15ull;
            for (uint64_t v : {bits(k.nx), bits(k.ny), bits(k.nz), uint64_t(k.closed)})
                h = (h ^ v) * 0xff51afd7ed558ccdull + (h >> 29);
            return size_t(h);
        }
    };
    std::unordered_map<Key, uint32_t, KeyHash> ids;
    std::vector<uint32_t> clusterOf(triangles.size());
    for (size_t t = 0; t < triangles.size(); ++t) {
        const ProxyTriangle& pt = triangles[t];
        const Vec3 c = (positions[pt.corners.x] + positions[pt.corners.y] + positions[pt.corners.z]) / 3.0;
        const std::array<int, 3> v = grid.cell(c);
        const size_t block =
            (size_t(v[2] / blockVoxels) * size_t(blocks[1]) + size_t(v[1] / blockVoxels)) * size_t(blocks[0]) +
            size_t(v[0] / blockVoxels);
        const Key key{block, pt.normal.x, pt.normal.y, pt.normal.z, pt.closed};
        const auto [it, added] = ids.emplace(key, uint32_t(clusters_.size()));
        if (added) {
            Cluster cl;
            cl.normal = pt.normal;
            cl.closed = pt.closed;
            clusters_.push_back(cl);
        }
        Cluster& cl = clusters_[it->second];
        for (int k = 0; k < 3; ++k) {
            const Vec3& p = positions[pt.corners[k]];
            cl.lo = glm::min(cl.lo, p);
            cl.hi = glm::max(cl.hi, p);
            cl.planeMin = std::min(cl.planeMin, glm::dot(cl.normal, p));
        }
        ++cl.count;
        clusterOf[t] = it->second;
    }
    // Indices, cluster by cluster.
    uint32_t next = 0;
    for (Cluster& cl : clusters_) {
        cl.first = next;
        next += 3 * cl.count;
        cl.count = 0;
    }
    indices_.resize(size_t(next));
    triangleOf_.resize(size_t(next) / 3);
    for (size_t t = 0; t < triangles.size(); ++t) {
        Cluster& cl = clusters_[clusterOf[t]];
        for (int k = 0; k < 3; ++k) indices_[cl.first + cl.count + uint32_t(k)] = triangles[t].corners[k];
        triangleOf_[(cl.first + cl.count) / 3] = uint32_t(t);
        cl.count += 3;
    }

    // Vertices: every proxy position with its side's normal (positions are
    // never shared between sides: RadianceProxy makes each side its own).
    std::vector<ClusterVertex> vertices(positions.size());
    for (size_t v = 0; v < positions.size(); ++v) vertices[v].position = glm::vec3(positions[v] - grid.origin);
    for (const ProxyTriangle& t : triangles)
        for (int k = 0; k < 3; ++k)
            vertices[t.corners[k]].normalClosed = glm::vec4(glm::vec3(t.normal), t.closed ? 1.f : 0.f);
    vertexBytes_ = std::max<size_t>(vertices.size(), 1) * sizeof(ClusterVertex);
    gpu_->vertices = makeBuffer(gl, vertexBytes_, vertices.data());
    gpu_->vao = makeVertexArray(gl);
    const GLuint vao = gpu_->vao.id();
    gl.EnableVertexArrayAttrib(vao, 0);
    gl.VertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, 0);
    gl.VertexArrayAttribBinding(vao, 0, 0);
    gl.EnableVertexArrayAttrib(vao, 1);
    gl.VertexArrayAttribFormat(vao, 1, 4, GL_FLOAT, GL_FALSE, GLuint(sizeof(glm::vec3)));
    gl.VertexArrayAttribBinding(vao, 1, 0);
    gl.VertexArrayVertexBuffer(vao, 0, gpu_->vertices.id(), 0, sizeof(ClusterVertex));
    gl.EnableVertexArrayAttrib(vao, 2);
    gl.VertexArrayAttribFormat(vao, 2, 3, GL_FLOAT, GL_FALSE, 0);
    gl.VertexArrayAttribBinding(vao, 2, 1);
    checkGl(gl, "uploading the proxy's clusters");
}

ProxyClusters::~ProxyClusters() = default;

GlBuffer ProxyClusters::Gpu::uploadRadiance(const std::vector<Rgb>& radiance) const {
    ML_ASSERT(radiance.size() == positionCount, radiance.size(), " radiances for ", positionCount,
              " proxy positions");
    std::vector<glm::vec3> values(std::max<size_t>(radiance.size(), 1), glm::vec3(0.f));
    for (size_t v = 0; v < radiance.size(); ++v) values[v] = glm::vec3(radiance[v]);
    return makeBuffer(*gl, values.size() * sizeof(glm::vec3), values.data());
}

size_t ProxyClusters::cull(const Vec3& x, const Vec3& n, double lift, const Vec3& eye,
                           const std::vector<ViewPlane>& frustum, std::vector<uint32_t>& indices, double nearDistance,
                           std::vector<uint32_t>* near) const {
    size_t added = 0;
    const double horizon = glm::dot(n, x) + lift;
    for (const Cluster& cl : clusters_) {
        // Some triangle of an open side must face the eye; a closed side's
        // back is drawn (black, opaque).
        if (!cl.closed && glm::dot(cl.normal, eye) <= cl.planeMin) continue;
        // Some corner of its box above the horizon, and inside every plane.
        auto anyCornerAbove = [&](const Vec3& m, double offset) {
            // The box corner furthest along m.
            const Vec3 c(m.x > 0 ? cl.hi.x : cl.lo.x, m.y > 0 ? cl.hi.y : cl.lo.y, m.z > 0 ? cl.hi.z : cl.lo.z);
            return glm::dot(m, c) > offset;
        };
        if (!anyCornerAbove(n, horizon)) continue;
        bool inside = true;
        for (const ViewPlane& p : frustum)
            if (!anyCornerAbove(p.normal, glm::dot(p.normal, eye))) {
                inside = false;
                break;
            }
        if (!inside) continue;
        if (near) {
            const Vec3 gap = glm::max(glm::max(cl.lo - eye, eye - cl.hi), Vec3(0.0));
            if (glm::dot(gap, gap) < nearDistance * nearDistance) {
                near->insert(near->end(), triangleOf_.begin() + cl.first / 3,
                             triangleOf_.begin() + (cl.first + cl.count) / 3);
                continue;
            }
        }
        indices.insert(indices.end(), indices_.begin() + cl.first, indices_.begin() + cl.first + cl.count);
        added += cl.count / 3;
    }
    return added;
}

size_t ProxyClusters::memoryBytes() const {
    return vertexBytes_ + (indices_.size() + triangleOf_.size()) * sizeof(uint32_t) +
           clusters_.size() * sizeof(Cluster);
}

}  // namespace ml
