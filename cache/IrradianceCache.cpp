#include "IrradianceCache.h"

#include "core/Error.h"
#include "core/Random.h"
#include "detail/CacheMesh.h"

#include <queue>

namespace ml {

using detail::CacheTriMesh;
using detail::toOm;
using detail::toVec3;

void CacheSettings::validate() const {
    if (!(maxEdgeFraction > 1e-5 && maxEdgeFraction <= 1.0))
        throw InputError(concat("cache maximum edge fraction ", maxEdgeFraction, " is not in (1e-5, 1]"));
}

namespace {

// Copies every object into one mesh. A face OpenMesh refuses (a complex
// edge or vertex: non-manifold input) gets vertices of its own, so nothing
// is lost; the count is reported by the caller.
size_t buildBaseMesh(const Scene& scene, CacheTriMesh& mesh) {
    size_t detached = 0;
    for (const Mesh& m : scene.meshes) {
        std::vector<CacheTriMesh::VertexHandle> handles(m.positions.size());
        for (size_t v = 0; v < m.positions.size(); ++v) {
            handles[v] = mesh.add_vertex(toOm(m.positions[v]));
            mesh.set_normal(handles[v], toOm(m.normals[v]));
        }
        for (const glm::uvec3& t : m.triangles) {
            const CacheTriMesh::FaceHandle f = mesh.add_face(handles[t.x], handles[t.y], handles[t.z]);
            if (f.is_valid()) continue;
            CacheTriMesh::VertexHandle own[3];
            for (int k = 0; k < 3; ++k) {
                own[k] = mesh.add_vertex(toOm(m.positions[t[k]]));
                mesh.set_normal(own[k], toOm(m.normals[t[k]]));
            }
            mesh.add_face(own[0], own[1], own[2]);
            ++detached;
        }
    }
    return detached;
}

// Longest-edge bisection until no edge exceeds maxLength. Splitting an edge
// splits both faces beside it, so the mesh stays conforming (no T-vertex).
void bisectLongEdges(CacheTriMesh& mesh, double maxLength) {
    using Entry = std::pair<double, int>;  // (length, edge index)
    std::priority_queue<Entry> queue;
    auto push = [&](CacheTriMesh::EdgeHandle e) {
        const double len = mesh.calc_edge_length(e);
        if (len > maxLength) queue.push({len, e.idx()});
    };
    for (auto e : mesh.edges()) push(e);
    while (!queue.empty()) {
        const auto [len, idx] = queue.top();
        queue.pop();
        const CacheTriMesh::EdgeHandle e(idx);
        if (std::abs(mesh.calc_edge_length(e) - len) > 1e-12 * len) continue;  // stale entry
        const auto h = mesh.halfedge_handle(e, 0);
        const auto a = mesh.from_vertex_handle(h), b = mesh.to_vertex_handle(h);
        Vec3 n = toVec3(mesh.normal(a)) + toVec3(mesh.normal(b));
        n = glm::length(n) > 0 ? glm::normalize(n) : toVec3(mesh.normal(a));
        const auto mid = mesh.split(e, 0.5 * (mesh.point(a) + mesh.point(b)));
        mesh.set_normal(mid, toOm(n));
        for (auto ve : mesh.ve_range(mid)) push(ve);
        // The faces' far edges keep their lengths; only the new edges can be long.
    }
}

}  // namespace

struct IrradianceCache::Impl {
    struct LightMesh {
        CacheTriMesh mesh;
        std::vector<Rgb> sum;
        std::vector<uint32_t> count;
    };
    std::vector<LightMesh> lights;
    size_t detachedFaces = 0;
};

IrradianceCache::IrradianceCache(const Scene& scene, const CacheSettings& settings)
    : impl_(std::make_unique<Impl>()) {
    settings.validate();
    // Every light's mesh starts as the same refined copy of the scene; they
    // part ways once refinement follows each light's own shadows.
    CacheTriMesh base;
    impl_->detachedFaces = buildBaseMesh(scene, base);
    bisectLongEdges(base, settings.maxEdgeFraction * scene.bounds.diagonal());
    impl_->lights.resize(scene.lights.size());
    for (Impl::LightMesh& lm : impl_->lights) {
        lm.mesh = base;
        lm.sum.assign(base.n_vertices(), Rgb(0.0));
        lm.count.assign(base.n_vertices(), 0);
    }
}

IrradianceCache::~IrradianceCache() = default;

size_t IrradianceCache::lightCount() const { return impl_->lights.size(); }
size_t IrradianceCache::vertexCount(size_t l) const { return impl_->lights.at(l).mesh.n_vertices(); }
size_t IrradianceCache::triangleCount(size_t l) const { return impl_->lights.at(l).mesh.n_faces(); }

Vec3 IrradianceCache::position(size_t l, size_t v) const {
    return toVec3(impl_->lights.at(l).mesh.point(CacheTriMesh::VertexHandle(int(v))));
}
Vec3 IrradianceCache::normal(size_t l, size_t v) const {
    return toVec3(impl_->lights.at(l).mesh.normal(CacheTriMesh::VertexHandle(int(v))));
}

void IrradianceCache::addSample(size_t l, size_t v, const Rgb& e) {
    Impl::LightMesh& lm = impl_->lights.at(l);
    ML_ASSERT(v < lm.sum.size(), "vertex ", v);
    ML_ASSERT(isFinite(e), "non-finite irradiance at vertex ", v, " of light ", l);
    lm.sum[v] += e;
    lm.count[v] += 1;
}

IrradianceMeshView IrradianceCache::view(size_t l) const {
    const Impl::LightMesh& lm = impl_->lights.at(l);
    IrradianceMeshView out;
    const size_t n = lm.mesh.n_vertices();
    out.positions.reserve(n);
    out.normals.reserve(n);
    for (auto v : lm.mesh.vertices()) {
        out.positions.push_back(toVec3(lm.mesh.point(v)));
        out.normals.push_back(toVec3(lm.mesh.normal(v)));
        const uint32_t c = lm.count[size_t(v.idx())];
        out.irradiance.push_back(c ? lm.sum[size_t(v.idx())] / double(c) : Rgb(0.0));
        out.samples.push_back(c);
    }
    out.triangles.reserve(lm.mesh.n_faces());
    for (auto f : lm.mesh.faces()) {
        glm::uvec3 t;
        int k = 0;
        for (auto v : lm.mesh.fv_range(f)) t[k++] = uint32_t(v.idx());
        out.triangles.push_back(t);
    }
    return out;
}

size_t IrradianceCache::memoryBytes() const {
    size_t bytes = 0;
    for (const Impl::LightMesh& lm : impl_->lights) {
        const CacheTriMesh& m = lm.mesh;
        // Array kernel: per vertex a point, a normal, a status and an
        // outgoing halfedge; per halfedge 4 indices; per edge a status; per
        // face a halfedge and a status; plus the sample accumulators.
        bytes += m.n_vertices() * (sizeof(OpenMesh::Vec3d) * 2 + sizeof(int) * 2);
        bytes += m.n_halfedges() * sizeof(int) * 4 + m.n_edges() * sizeof(int) + m.n_faces() * sizeof(int) * 2;
        bytes += lm.sum.size() * sizeof(Rgb) + lm.count.size() * sizeof(uint32_t);
    }
    return bytes;
}

void sampleEveryVertex(IrradianceCache& cache, const DirectEstimateFn& estimate, int passes, uint32_t seed,
                       const std::function<void(size_t, size_t)>& progress) {
    size_t total = 0, done = 0;
    for (size_t l = 0; l < cache.lightCount(); ++l) total += cache.vertexCount(l);
    for (size_t l = 0; l < cache.lightCount(); ++l) {
        for (size_t v = 0; v < cache.vertexCount(l); ++v) {
            for (int p = 0; p < passes; ++p) {
                try {
                    const uint32_t s = seedFor(seed, uint32_t(v), uint32_t(l), uint32_t(p));
                    cache.addSample(l, v, estimate(l, cache.position(l, v), cache.normal(l, v), s));
                } catch (const InputError&) {
                    throw;
                } catch (const std::exception& e) {
                    throw std::runtime_error(concat("sampling failed at vertex ", v, " of light ", l, ", pass ",
                                                    p, " (point ", cache.position(l, v).x, ",",
                                                    cache.position(l, v).y, ",", cache.position(l, v).z,
                                                    "): ", e.what()));
                }
            }
            if (progress && (++done % 256 == 0 || done == total)) progress(done, total);
        }
    }
}

}  // namespace ml
