#include "IrradianceCache.h"

#include "BackFaceReach.h"
#include "LightCoverage.h"

#include "core/Error.h"
#include "core/MeshUtil.h"
#include "core/Random.h"
#include "core/raytrace/EmbreeScene.h"
#include "detail/CacheImpl.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>
#include <queue>
#include <tuple>

namespace ml {

using detail::CacheTriMesh;
using detail::toOm;
using detail::toVec3;

void CacheSettings::validate() const {
    if (sharedRays < 0 || sharedRays > 65536)
        throw InputError(concat("shared rays ", sharedRays, ": must be 0..65536"));
    if (!(maxEdgeFraction > 1e-5 && maxEdgeFraction <= 1.0))
        throw InputError(concat("cache maximum edge fraction ", maxEdgeFraction, " is not in (1e-5, 1]"));
    if (!(minEdgeFraction > 1e-7 && minEdgeFraction <= maxEdgeFraction))
        throw InputError(concat("cache minimum edge fraction ", minEdgeFraction, " is not in (1e-7, ",
                                maxEdgeFraction, "] (the maximum edge fraction)"));
    if (!(minEdgePixels >= 0 && minEdgePixels <= 1e4))
        throw InputError(concat("cache minimum edge size ", minEdgePixels, " pixels is not in [0, 1e4]"));
    if (!(uniformEdgeFraction == 0 || (uniformEdgeFraction > 0 && uniformEdgeFraction <= maxEdgeFraction)))
        throw InputError(concat("cache uniform edge fraction ", uniformEdgeFraction, " is not 0 or in (0, ",
                                maxEdgeFraction, "] (the maximum edge fraction)"));
    if (!(splitTolerance > 0 && splitTolerance < 1))
        throw InputError(concat("cache split tolerance ", splitTolerance, " is not in (0, 1)"));
    if (!(noiseTolerance > 0 && noiseTolerance < 1))
        throw InputError(concat("cache noise tolerance ", noiseTolerance, " is not in (0, 1)"));
    if (!(sampleNoise >= 0 && sampleNoise < 1))
        throw InputError(concat("cache sample noise ", sampleNoise, " is not in [0, 1)"));
    if (maxSamplesPerVertex < 1) throw InputError("cache: at least one sample per vertex");
    if (!(singleSampleNoise >= 0 && singleSampleNoise < 1))
        throw InputError(concat("cache single-sample noise ", singleSampleNoise, " is not in [0, 1)"));
    if (!(contactCloseness >= 0 && contactCloseness <= 1))
        throw InputError(concat("cache contact closeness ", contactCloseness, " is not in [0, 1]"));
    if (maxVertices < 3) throw InputError(concat("cache vertex budget ", maxVertices, " is below 3"));
    if (maxMemoryBytes < (size_t(1) << 16))
        throw InputError(concat("cache memory budget ", maxMemoryBytes, " bytes is below 64 KiB"));
}

namespace detail {

namespace {

// FNV-1a, 64 bits: a fingerprint, not a defence against forgery.
struct Fnv64 {
    uint64_t h = 0xcbf29ce484222325ull;
    void bytes(const void* p, size_t n) {
        const auto* b = static_cast<const unsigned char*>(p);
        for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 0x100000001b3ull;
    }
    void f64(double v) { bytes(&v, sizeof v); }
    void u64(uint64_t v) { bytes(&v, sizeof v); }
    void vec(const Vec3& v) { f64(v.x), f64(v.y), f64(v.z); }
};

}  // namespace

uint64_t sceneFingerprint(const Scene& scene) {
    Fnv64 f;
    f.u64(scene.meshes.size());
    for (const Mesh& m : scene.meshes) {
        f.u64(m.positions.size());
        for (const Vec3& p : m.positions) f.vec(p);
        for (const Vec3& n : m.normals) f.vec(n);
        f.u64(m.triangles.size());
        f.bytes(m.triangles.data(), m.triangles.size() * sizeof(glm::uvec3));
        f.bytes(m.materials.data(), m.materials.size() * sizeof(uint32_t));
    }
    for (const Material& mat : scene.materials) {
        f.vec(mat.kd), f.vec(mat.ks), f.f64(mat.ns), f.vec(mat.ke);
    }
    f.u64(scene.lights.size());
    return f.h;
}

uint64_t settingsFingerprint(const CacheSettings& s) {
    Fnv64 f;
    f.f64(s.maxEdgeFraction), f.f64(s.minEdgeFraction), f.f64(s.minEdgePixels);
    f.f64(s.splitTolerance), f.f64(s.noiseTolerance);
    f.u64(s.maxSamplesPerVertex), f.u64(s.maxVertices), f.u64(s.maxMemoryBytes), f.f64(s.singleSampleNoise);
    f.f64(s.sampleNoise), f.f64(s.lightShare), f.f64(s.uniformEdgeFraction), f.f64(s.contactCloseness);
    // Only when on: a cache saved before the option existed (and with it
    // off) still loads with --light-planes off.
    if (s.lightPlaneCuts) f.u64(1);
    return f.h;
}

double edgeLength(const CacheTriMesh& mesh, CacheTriMesh::VertexHandle a, CacheTriMesh::VertexHandle b) {
    return (mesh.point(a) - mesh.point(b)).norm();
}

CacheTriMesh::VertexHandle splitAtMidpoint(CacheTriMesh& mesh, CacheTriMesh::EdgeHandle e) {
    const auto h = mesh.halfedge_handle(e, 0);
    const auto a = mesh.from_vertex_handle(h), b = mesh.to_vertex_handle(h);
    Vec3 n = toVec3(mesh.normal(a)) + toVec3(mesh.normal(b));
    // Opposite normals at the ends (a knife edge): keep one side's.
    n = glm::length(n) > 1e-9 ? glm::normalize(n) : toVec3(mesh.normal(a));
    const auto mid = mesh.split(e, 0.5 * (mesh.point(a) + mesh.point(b)));
    mesh.set_normal(mid, toOm(n));
    return mid;
}

}  // namespace detail

namespace {

using detail::CacheState;

// Copies every object into one mesh. A face OpenMesh refuses (a complex
// edge or vertex: non-manifold input) gets vertices of its own, so nothing
// is lost; the count is reported by the caller.
// Whether some light lies behind triangle t's plane and emits towards it:
// then its back is lit, and needs a cache of its own.
bool litFromBehind(const Scene& scene, const Mesh& m, size_t t) {
    const Triangle3 p = m.triangle(t);
    const Vec3 n = glm::normalize(m.areaNormal(t));
    const double eps = 1e-6 * scene.bounds.diagonal();
    
    for (const Light& light : scene.lights)
        for (const Triangle3& lt : light.geometry) {
            const Vec3 ln = glm::cross(lt[1] - lt[0], lt[2] - lt[0]);
            if (!(glm::dot(ln, n) > 0)) continue;  // emits away from the plane's back
            for (const Vec3& q : lt)
                if (glm::dot(q - p[0], n) < -eps) return true;
        }
    return false;
}

// Whether any part of the scene's bounds lies behind triangle t's plane,
// beyond a thousandth of the scene's size: a wall inside a building has
// rooms behind it, the walls of a box seen from inside have nothing.
bool sceneBehind(const Scene& scene, const Mesh& m, size_t t) {
    const Vec3 n = glm::normalize(m.areaNormal(t));
    const Vec3 p = m.positions[m.triangles[t].x];
    const double eps = 1e-3 * scene.bounds.diagonal();
    for (int c = 0; c < 8; ++c) {
        const Vec3 corner((c & 1) ? scene.bounds.hi.x : scene.bounds.lo.x, (c & 2) ? scene.bounds.hi.y : scene.bounds.lo.y,
                          (c & 4) ? scene.bounds.hi.z : scene.bounds.lo.z);
        if (glm::dot(corner - p, n) < -eps) return true;
    }
    return false;
}

size_t buildBaseMesh(const Scene& scene, const std::vector<Mesh>& meshes, const std::vector<bool>& skip,
                     CacheLayout::BackFaces rule, CacheTriMesh& mesh, size_t& backFaces) {
    // Rays only for the faces the cheap tests leave undecided, from a
    // scene built for the first of them.
    std::unique_ptr<EmbreeScene> rays;
    Bounds3 object;
    const auto needsBack = [&](const Mesh& m, size_t t) {
        if (litFromBehind(scene, m, t)) return true;
        if (rule == CacheLayout::BackFaces::LitFromBehind || !sceneBehind(scene, m, t)) return false;
        if (!rays) rays = std::make_unique<EmbreeScene>(scene);
        return backLooksOutOfObject(*rays, scene, m.triangle(t), object);
    };
    size_t detached = 0;
    backFaces = 0;
    for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
        if (skip[mi]) continue;
        const Mesh& m = meshes[mi];
        // Surfaces lit from both sides (open objects with a light behind)
        // get a reversed copy, facing the other way, with vertices of its own.
        // Closed or open as the object is: cutting it (ContactCuts.h) may
        // leave out faces too thin to draw, or put points on one side of a
        // seam's edge alone, and its inside is no more seen for that.
        if (!isClosedMesh(scene.meshes[mi])) {
            object = Bounds3();
            for (const Vec3& p : scene.meshes[mi].positions) object.extend(p);
            std::map<uint32_t, CacheTriMesh::VertexHandle> back;
            for (size_t t = 0; t < m.triangles.size(); ++t) {
                if (!needsBack(m, t) || !(m.area(t) > 0)) continue;
                CacheTriMesh::VertexHandle h[3];
                for (int k = 0; k < 3; ++k) {
                    const uint32_t v = m.triangles[t][k];
                    auto it = back.find(v);
                    if (it == back.end()) {
                        it = back.emplace(v, mesh.add_vertex(toOm(m.positions[v]))).first;
                        mesh.set_normal(it->second, toOm(-m.normals[v]));
                    }
                    h[k] = it->second;
                }
                if (mesh.add_face(h[0], h[2], h[1]).is_valid()) {
                    ++backFaces;
                    continue;
                }
                for (int k = 0; k < 3; ++k) {  // non-manifold: vertices of its own
                    const uint32_t v = m.triangles[t][k];
                    h[k] = mesh.add_vertex(toOm(m.positions[v]));
                    mesh.set_normal(h[k], toOm(-m.normals[v]));
                }
                mesh.add_face(h[0], h[2], h[1]);
                ++backFaces;
                ++detached;
            }
        }
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

// The scene's meshes cut along contacts (ContactCuts.h), or as they are;
// `gridded` meshes are left as they are.
std::vector<Mesh> cutMeshes(const Scene& scene, const std::vector<bool>& gridded, const CacheSettings& settings,
                            ContactCutReport* report = nullptr) {
    ContactCutSettings cut;
    if (settings.lightPlaneCuts) cut.planes = lightCutPlanes(scene);
    if (!(settings.contactCloseness > 0) && cut.planes.empty()) return scene.meshes;
    cut.closeness = settings.contactCloseness;
    cut.spacing = settings.maxEdgeFraction * (scene.bounds.diagonal() > 0 ? scene.bounds.diagonal() : 1.0);
    return cutAlongContacts(scene, gridded, cut, report);
}

// Longest-edge bisection until no edge exceeds maxLength. Edges are split
// longest first, so each split edge is the longest of both faces beside it
// (the bisection keeps angles bounded below) and, as splitting an edge
// splits both faces, the mesh stays conforming (no T-vertex).
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
        const auto mid = detail::splitAtMidpoint(mesh, e);
        for (auto ve : mesh.ve_range(mid)) push(ve);
        // The faces' far edges keep their lengths; only the new edges can be long.
    }
}

// The indices of the elements kept, in the order OpenMesh's
// garbage_collection leaves them once the others are deleted: it fills each
// hole, from the front, with the last element kept.
std::vector<int> compactedOrder(const std::vector<char>& keep) {
    std::vector<int> slot(keep.size());
    std::iota(slot.begin(), slot.end(), 0);
    if (slot.empty()) return slot;
    int i0 = 0, i1 = int(slot.size()) - 1;
    for (;;) {
        while (keep[size_t(slot[size_t(i0)])] && i0 < i1) ++i0;
        while (!keep[size_t(slot[size_t(i1)])] && i0 < i1) --i1;
        if (i0 >= i1) break;
        std::swap(slot[size_t(i0)], slot[size_t(i1)]);
    }
    slot.resize(keep[size_t(slot[size_t(i0)])] ? size_t(i0) + 1 : size_t(i0));
    return slot;
}

// `base`'s faces where keepFace says so, with their vertices (and any
// vertex of no face), numbered as copying `base`, deleting the other faces
// with the vertices that leaves without one and collecting the garbage
// would number them: the same cache, vertex for vertex. Built from the
// faces kept alone, it costs what they are, not the whole base: a light's
// own mesh covers 1-2% of the 192-panel office, whose 192 copies of the
// base and deletions took 2.3 s of the cache's making. False where a face
// cannot be added again (OpenMesh may refuse a complex vertex when faces
// come in some orders; not seen on the scenes measured): `out` is then to
// be ignored, and layMesh deletes from a copy as before.
bool keptFaces(const CacheTriMesh& base, const std::vector<char>& keepFace, CacheTriMesh& out) {
    std::vector<char> keepVertex(base.n_vertices(), 0);
    for (const auto vh : base.vertices()) {
        bool any = false, kept = false;
        for (const auto fh : base.vf_range(vh)) any = true, kept = kept || keepFace[size_t(fh.idx())];
        keepVertex[size_t(vh.idx())] = kept || !any;
    }
    out.clear();
    std::vector<CacheTriMesh::VertexHandle> handle(base.n_vertices());
    for (const int v : compactedOrder(keepVertex)) {
        const CacheTriMesh::VertexHandle vh(v);
        handle[size_t(v)] = out.add_vertex(base.point(vh));
        out.set_normal(handle[size_t(v)], base.normal(vh));
    }
    for (const int f : compactedOrder(keepFace)) {
        CacheTriMesh::VertexHandle corner[3];
        int k = 0;
        for (const auto vh : base.fv_range(CacheTriMesh::FaceHandle(f))) corner[k++] = handle[size_t(vh.idx())];
        if (!out.add_face(corner[0], corner[1], corner[2]).is_valid()) return false;
    }
    return true;
}

// Mesh `l` laid on `base` as the layout asks (a light's own mesh keeps the
// faces where it has weight when lights share), with no sample.
void layMesh(CacheState& s, const CacheLayout& layout, size_t l, const Scene& scene, const CacheTriMesh& base) {
    detail::LightMesh& lm = s.meshes[l];
    lm.provisional.clear();
    lm.needsGpu.clear();
    lm.gridNeedsGpu.clear();
    // A light's own mesh keeps the faces where it has weight; a gathered
    // light's keeps none (LightCoverage::gathered).
    const bool gathered =
        layout.coverage && layout.meshes == 0 && l < scene.lights.size() && layout.coverage->gathered(l);
    if ((s.sharedMesh && l < scene.lights.size()) || gathered) {
        std::vector<char> keep(base.n_faces(), 0);
        for (const auto fh : base.faces()) {
            Triangle3 t;
            int k = 0;
            for (const auto vh : base.fv_range(fh)) t[size_t(k++)] = toVec3(base.point(vh));
            keep[size_t(fh.idx())] = layout.coverage->covers(l, t);
        }
        if (!keptFaces(base, keep, lm.mesh)) {
            lm.mesh = base;
            for (const auto fh : lm.mesh.faces())
                if (!keep[size_t(fh.idx())]) lm.mesh.delete_face(fh, true);
            lm.mesh.garbage_collection();
        }
    } else {
        lm.mesh = base;
    }
    lm.stats.assign(lm.mesh.n_vertices(), {});
    lm.gridStats.assign(s.gridSamples, {});
}

}  // namespace

std::vector<Mesh> cacheSurfaces(const Scene& scene, const CacheSettings& settings, ContactCutReport* report) {
    const double maxEdge = settings.maxEdgeFraction * (scene.bounds.diagonal() > 0 ? scene.bounds.diagonal() : 1.0);
    std::vector<bool> gridded;
    for (const Mesh& m : scene.meshes) gridded.push_back(decideGridCache(m, maxEdge).useGrid);
    return cutMeshes(scene, gridded, settings, report);
}

IrradianceCache::IrradianceCache(const Scene& scene, const CacheSettings& settings, const CacheLayout& layout)
    : impl_(std::make_unique<Impl>()) {
    settings.validate();
    CacheState& s = impl_->state;
    s.settings = settings;
    s.diagonal = scene.bounds.diagonal() > 0 ? scene.bounds.diagonal() : 1.0;
    s.sceneFingerprint = detail::sceneFingerprint(scene);
    s.insetBorders = layout.insetBorders;
    s.borderInset = layout.borderInset;
    if (layout.coverage)
        for (size_t l = 0; l < scene.lights.size(); ++l)
            if (layout.coverage->gathered(l)) s.gatheredSalt = (s.gatheredSalt ^ (l + 1)) * 0x100000001b3ull;
    s.edgeOn = EdgeOnSurfaces::forScene(scene, s.sceneFingerprint);
    // Every light's mesh starts as the same refined copy of the scene; they
    // part ways once refinement follows each light's own shadows.
    const double maxEdge = settings.maxEdgeFraction * s.diagonal;
    std::vector<bool> gridded(scene.meshes.size(), false);
    for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
        const Mesh& m = scene.meshes[mi];
        if (!decideGridCache(m, maxEdge).useGrid) continue;
        gridded[mi] = true;
        detail::GridObject g;
        g.mesh = uint32_t(mi);
        g.positions = m.positions;
        g.normals = m.normals;
        g.triangles = m.triangles;
        for (size_t t = 0; t < m.triangles.size(); ++t) g.area += m.area(t);
        GridCacheSettings gs;
        gs.cellSize = maxEdge;
        g.grid = std::make_shared<const GridCache>(m, gs);
        g.firstSample = uint32_t(s.gridSamples);
        s.gridSamples += g.grid->sampleCount();
        s.grids.push_back(std::move(g));
    }
    CacheTriMesh base;
    const std::vector<Mesh> cut = layout.surfaces ? std::vector<Mesh>() : cutMeshes(scene, gridded, settings);
    const std::vector<Mesh>& surfaces = layout.surfaces ? *layout.surfaces : cut;
    ML_ASSERT(surfaces.size() == scene.meshes.size(), "the cache's surfaces are the scene's meshes");
    s.detachedFaces = buildBaseMesh(scene, surfaces, gridded, layout.backFaces, base, s.backFaces);
    bisectLongEdges(base, maxEdge);
    const bool share = layout.coverage && layout.coverage->sharing() && layout.meshes == 0;
    s.sharedMesh = share;
    s.meshes.resize(share ? scene.lights.size() + 1 : layout.meshes ? layout.meshes : scene.lights.size());
    impl_->layout = layout;
    for (size_t l = 0; l < s.meshes.size(); ++l) layMesh(s, layout, l, scene, base);
}

size_t IrradianceCache::rebuildKeepingBase(size_t l, const Scene& scene) {
    CacheState& s = impl_->state;
    const detail::LightMesh old = s.meshes.at(l);
    rebuildMesh(l, scene);
    // A base vertex keeps the samples of the vertex that was at its very
    // place, facing its very way (the base is built the same way each time,
    // to the bit; moved parts were forgotten already).
    using Key = std::array<double, 6>;
    std::map<Key, size_t> sampled;
    for (auto v : old.mesh.vertices()) {
        const size_t i = size_t(v.idx());
        if (old.stats[i].count == 0) continue;
        const auto p = old.mesh.point(v), n = old.mesh.normal(v);
        sampled.emplace(Key{p[0], p[1], p[2], n[0], n[1], n[2]}, i);
    }
    detail::LightMesh& lm = s.meshes[l];
    size_t kept = 0;
    for (auto v : lm.mesh.vertices()) {
        const auto p = lm.mesh.point(v), n = lm.mesh.normal(v);
        const auto it = sampled.find(Key{p[0], p[1], p[2], n[0], n[1], n[2]});
        if (it == sampled.end()) continue;
        lm.stats[size_t(v.idx())] = old.stats[it->second];
        ++kept;
    }
    lm.gridStats = old.gridStats;
    return kept;
}

size_t IrradianceCache::rebuildMesh(size_t l, const Scene& scene) {
    CacheState& s = impl_->state;
    const size_t before = s.meshes.at(l).mesh.n_vertices();
    std::vector<bool> gridded(scene.meshes.size(), false);
    for (const detail::GridObject& g : s.grids) gridded[g.mesh] = true;
    CacheTriMesh base;
    size_t backFaces = 0;
    buildBaseMesh(scene, cutMeshes(scene, gridded, s.settings), gridded, impl_->layout.backFaces, base, backFaces);
    bisectLongEdges(base, s.settings.maxEdgeFraction * s.diagonal);
    layMesh(s, impl_->layout, l, scene, base);
    return before;
}

IrradianceCache::~IrradianceCache() = default;

const CacheSettings& IrradianceCache::settings() const { return impl_->state.settings; }

bool IrradianceCache::tighten() {
    if (impl_->state.level >= kMaxRefinementLevel) return false;
    ++impl_->state.level;
    return true;
}

int IrradianceCache::level() const { return impl_->state.level; }

double IrradianceCache::sampleNoise() const { return detail::effectiveSettings(impl_->state).sampleNoise; }

namespace detail {

namespace {

// The sums behind MeasuredNoise and NoiseModel, over every vertex and grid
// sample.
struct NoiseSums {
    double spread = 0, level = 0, freedom = 0;  // the resampled ones
    double ownSpread = 0, ownExpected = 0, ownFreedom = 0;  // ...of them, those whose samples measured their own
    double ownLevel = 0, ownVariance = 0;  // every sampled one whose samples measured their own
};

NoiseSums noiseSums(const CacheState& s, size_t firstMesh = 0) {
    // Pooled as a ratio of sums, Σ (n−1)·s² / Σ (n−1)·mean²: each vertex's
    // spread counts by its degrees of freedom and by its light, so the dark
    // vertices, whose relative spread is large and shown faint, do not
    // decide it. The own variances' scale likewise, Σ (n−1)·s² over
    // Σ (n−1)·own.
    // The spreads are of a unit of work (VertexStats): the noise of a full
    // estimate, of s.fullWork, is theirs over √fullWork.
    NoiseSums sums;
    const auto add = [&](const VertexStats& st) {
        if (st.count == 0) return;
        const double n = st.count, mean = st.meanLuminance(), own = st.ownUnitVariance();
        if (own >= 0) sums.ownLevel += mean * mean, sums.ownVariance += own;
        if (st.count < 2) return;
        sums.spread += st.spread();  // (n−1)·s²
        sums.level += (n - 1) * mean * mean;
        sums.freedom += n - 1;
        if (own < 0) return;
        sums.ownSpread += st.spread();
        sums.ownExpected += (n - 1) * own;
        sums.ownFreedom += n - 1;
    };
    for (size_t l = firstMesh; l < s.meshes.size(); ++l) {
        for (const VertexStats& st : s.meshes[l].stats) add(st);
        for (const VertexStats& st : s.meshes[l].gridStats) add(st);
    }
    return sums;
}

MeasuredNoise measured(const NoiseSums& sums, double fullWork) {
    MeasuredNoise m;
    if (sums.freedom >= kMeasuredNoiseFreedom && sums.level > 0)
        m.relative = std::sqrt(sums.spread / sums.level / std::max(fullWork, 1e-300));
    if (sums.ownFreedom >= kMeasuredNoiseFreedom && sums.ownExpected > 0) m.ownScale = sums.ownSpread / sums.ownExpected;
    return m;
}

double effectiveSampleNoise(const CacheSettings& settings, const MeasuredNoise& m) {
    return settings.sampleNoise > 0 && m.relative > 0 ? std::min(m.relative, 0.99) : settings.sampleNoise;
}

}  // namespace

MeasuredNoise measureNoise(const CacheState& s) { return measured(noiseSums(s), s.fullWork); }

NoiseModel noiseModel(const CacheState& s) {
    NoiseModel model;
    model.singleSampleNoise = s.settings.singleSampleNoise;
    model.fullWork = s.fullWork;
    // Exact samplers (direct light's) measure nothing of their own but for
    // the mesh many lights share, whose draws among the lights scatter
    // (SharedLightSampler): only its vertices are passed over, and none
    // without it.
    const bool exact = !(s.settings.sampleNoise > 0);
    if (exact && (!s.sharedMesh || s.meshes.empty())) return model;
    const NoiseSums sums = noiseSums(s, exact ? s.meshes.size() - 1 : 0);
    const MeasuredNoise m = measured(sums, s.fullWork);
    model.sampleNoise = effectiveSampleNoise(s.settings, m);  // 0 for exact samplers
    if (m.ownScale >= 0)
        model.ownScale = m.ownScale;
    else if (sums.ownVariance > 0)
        // Until measured: for an exact sampler's draws, taken as
        // independent (scale 1: stratified, they scatter less, so the noise
        // is overestimated, never hidden); otherwise unit variance
        // sampleNoise²·mean²·fullWork on the mean, as the settings assume of
        // every vertex.
        model.ownScale = exact ? 1.0
                               : model.sampleNoise * model.sampleNoise * s.fullWork * sums.ownLevel / sums.ownVariance;
    return model;
}

CacheSettings effectiveSettings(const CacheState& s) {
    CacheSettings c = s.settings;
    if (c.sampleNoise > 0) c.sampleNoise = effectiveSampleNoise(c, measureNoise(s));
    if (s.level == 0) return c;
    const double f = std::ldexp(1.0, -s.level);
    c.splitTolerance *= f;
    c.noiseTolerance *= f;
    // The smallest edge stays: the estimate sums the predicted error of the
    // edges that may still be split, and letting shorter ones in would make
    // it jump at each level (by the error of detail no pixel shows, or of a
    // later bounce's edges not yet refined again) rather than fall.
    c.maxSamplesPerVertex = uint32_t(std::min<double>(4096, std::ldexp(double(c.maxSamplesPerVertex), s.level)));
    return c;
}

}  // namespace detail
size_t IrradianceCache::meshCount() const { return impl_->state.meshes.size(); }
size_t IrradianceCache::lightCount() const { return impl_->state.meshes.size() - (impl_->state.sharedMesh ? 1 : 0); }
bool IrradianceCache::hasSharedMesh() const { return impl_->state.sharedMesh; }
size_t IrradianceCache::unsampledCount() const { return detail::unsampledCount(impl_->state); }
size_t IrradianceCache::vertexCount(size_t l) const { return impl_->state.meshes.at(l).mesh.n_vertices(); }
size_t IrradianceCache::triangleCount(size_t l) const { return impl_->state.meshes.at(l).mesh.n_faces(); }
uint64_t IrradianceCache::totalSamples() const { return impl_->state.samples; }
uint64_t IrradianceCache::rounds() const { return impl_->state.rounds; }

size_t IrradianceCache::backFaceCount() const { return impl_->state.backFaces; }
size_t IrradianceCache::gridObjectCount() const { return impl_->state.grids.size(); }

size_t IrradianceCache::totalVertices() const {
    size_t n = 0;
    for (const detail::LightMesh& lm : impl_->state.meshes) n += lm.mesh.n_vertices();
    return n;
}

Vec3 IrradianceCache::position(size_t l, size_t v) const {
    return detail::samplePoint(impl_->state, impl_->state.meshes.at(l).mesh, CacheTriMesh::VertexHandle(int(v)));
}
Vec3 IrradianceCache::normal(size_t l, size_t v) const {
    return toVec3(impl_->state.meshes.at(l).mesh.normal(CacheTriMesh::VertexHandle(int(v))));
}

void IrradianceCache::addSample(size_t l, size_t v, const VertexSample& sample) {
    ML_ASSERT(l < impl_->state.meshes.size() && v < impl_->state.meshes[l].stats.size(), "vertex ", v, " of light ", l);
    detail::addVertexSample(impl_->state, l, v, sample);
}

void IrradianceCache::resetSamples() {
    for (detail::LightMesh& lm : impl_->state.meshes) {
        // A negative red marks a vertex that had no mean to keep.
        lm.provisional.assign(lm.stats.size(), Rgb(-1.0));
        for (size_t v = 0; v < lm.stats.size(); ++v) {
            if (lm.stats[v].count) lm.provisional[v] = lm.stats[v].mean();
            lm.stats[v] = {};
        }
        for (detail::VertexStats& st : lm.gridStats) st = {};
        lm.needsGpu.clear();
        lm.gridNeedsGpu.clear();
    }
}

std::vector<IrradianceMeshCopy> IrradianceCache::copyMeshes() const {
    const detail::NoiseModel noise = detail::noiseModel(impl_->state);
    std::vector<IrradianceMeshCopy> meshes;
    for (size_t l = 0; l < meshCount(); ++l) meshes.push_back(copyMesh(l, noise));
    return meshes;
}

namespace {

// One of six orientations: the axis of the normal's largest component and its sign.
int orientation(const Vec3& n) {
    const Vec3 a = glm::abs(n);
    const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
    return 2 * axis + (n[axis] < 0);
}

// Unknown vertices of `out` take the mean of the known ones of their
// orientation, or of all known ones where none faces their way.
void fillByOrientation(IrradianceMeshCopy& out, const std::vector<char>& known) {
    std::array<Rgb, 6> sum{};
    std::array<size_t, 6> count{};
    Rgb all(0.0);
    size_t allCount = 0;
    for (size_t v = 0; v < known.size(); ++v) {
        if (!known[v]) continue;
        const int o = orientation(out.normals[v]);
        sum[size_t(o)] += out.irradiance[v], ++count[size_t(o)];
        all += out.irradiance[v], ++allCount;
    }
    for (size_t v = 0; v < known.size(); ++v) {
        if (known[v]) continue;
        const size_t o = size_t(orientation(out.normals[v]));
        out.irradiance[v] = count[o] ? sum[o] / double(count[o]) : all / double(allCount);
    }
}

// Unknown vertices in `kind` take their known neighbours' mean in `kind`,
// ring after ring (at most 64); returns how many became known.
template <class Kind>
size_t fillRings(const detail::CacheTriMesh& mesh, IrradianceMeshCopy& out, std::vector<char>& known, size_t unknown,
                 const Kind& kind) {
    std::vector<std::pair<size_t, Rgb>> filled;
    size_t done = 0;
    for (int ring = 0; ring < 64 && done < unknown && unknown < known.size(); ++ring) {
        filled.clear();
        for (auto v : mesh.vertices()) {
            if (known[size_t(v.idx())] || !kind(size_t(v.idx()))) continue;
            Rgb sum(0.0);
            int count = 0;
            for (auto u : mesh.vv_range(v))
                if (known[size_t(u.idx())] && kind(size_t(u.idx()))) sum += out.irradiance[size_t(u.idx())], ++count;
            if (count) filled.emplace_back(size_t(v.idx()), sum / double(count));
        }
        if (filled.empty()) break;
        for (const auto& [v, e] : filled) out.irradiance[v] = e, known[v] = 1;
        done += filled.size();
    }
    return done;
}

// The vertex's noise is measured, not assumed: by its samples' spread (two
// or more) or by their own variance (VertexSample::ownVariance).
bool measuredNoise(const detail::VertexStats& st) { return st.count >= 2 || st.ownUnitVariance() >= 0; }

// A luminance `value` (an error, W·m⁻²) as RGB in the colour of `mean`,
// whose luminance is `lum`; grey where the mean is black.
Rgb colourOf(const Rgb& mean, double lum, double value) { return lum > 0 ? mean * (value / lum) : Rgb(value); }

}  // namespace

IrradianceMeshCopy IrradianceCache::copyMesh(size_t l) const { return copyMesh(l, detail::noiseModel(impl_->state)); }

IrradianceMeshCopy IrradianceCache::copyMesh(size_t l, const detail::NoiseModel& noise) const {
    const detail::LightMesh& lm = impl_->state.meshes.at(l);
    const std::vector<double> own = detail::ringOwnVariances(lm);
    IrradianceMeshCopy out;
    const size_t n = lm.mesh.n_vertices();
    out.positions.reserve(n);
    out.normals.reserve(n);
    out.irradiance.reserve(n);
    out.samples.reserve(n);
    for (auto v : lm.mesh.vertices()) {
        out.positions.push_back(toVec3(lm.mesh.point(v)));
        out.normals.push_back(toVec3(lm.mesh.normal(v)));
        const detail::VertexStats& st = lm.stats[size_t(v.idx())];
        out.irradiance.push_back(st.mean());
        out.samples.push_back(st.count);
        const double mean = st.meanLuminance();
        out.standardError.push_back(mean > 0 && measuredNoise(st)
                                        ? st.mean() * (detail::meanNoise(st, noise, own[size_t(v.idx())]) / mean)
                                        : Rgb(0.0));
    }
    // While the first pass runs, vertices without a sample take their
    // sampled neighbours' mean, ring after ring: a copy is a complete image,
    // never a checkerboard of black holes. (The first pass samples vertices
    // in a scattered order, so a few rings reach every hole.) They keep a
    // sample count of 0.
    std::vector<char> known(n);
    size_t unknown = 0;
    for (size_t v = 0; v < n; ++v) {
        const bool kept = out.samples[v] == 0 && v < lm.provisional.size() && lm.provisional[v].r >= 0;
        if (kept) out.irradiance[v] = lm.provisional[v];
        unknown += !(known[v] = out.samples[v] > 0 || kept);
    }
    // Vertices the sampler could not answer without the GPU (something may
    // stand between them and the light: under a table, beside a cabinet)
    // first take what their kind of neighbours saw, ring after ring through
    // their kind only: the unoccluded light around a shadow would fill it.
    const auto needsGpu = [&](size_t v) { return v < lm.needsGpu.size() && lm.needsGpu[v]; };
    if (!lm.needsGpu.empty()) unknown -= fillRings(lm.mesh, out, known, unknown, needsGpu);
    unknown -= fillRings(lm.mesh, out, known, unknown, [](size_t) { return true; });
    // What no ring reaches (a part of the mesh, such as a box's face or a
    // table leg, none of whose vertices has a sample yet) takes the mean of
    // the known vertices facing the same way (by the sign of the normal's
    // largest component): a floor's, a ceiling's, a wall's light, rather
    // than black.
    if (unknown > 0 && unknown < n) fillByOrientation(out, known);
    {
        std::vector<double> lum(n);
        for (size_t v = 0; v < n; ++v) lum[v] = luminance(out.irradiance[v]);
        std::vector<double> vertexNoise;
        const std::vector<double> predicted = detail::predictedErrors(impl_->state, l, lum, noise, own, &vertexNoise);
        out.predictedError.reserve(n);
        out.predictedNoise.reserve(n);
        for (size_t v = 0; v < n; ++v) {
            out.predictedError.push_back(colourOf(out.irradiance[v], lum[v], predicted[v]));
            out.predictedNoise.push_back(colourOf(out.irradiance[v], lum[v], vertexNoise[v]));
        }
    }
    out.triangles.reserve(lm.mesh.n_faces());
    for (auto f : lm.mesh.faces()) {
        glm::uvec3 t;
        int k = 0;
        for (auto v : lm.mesh.fv_range(f)) t[k++] = uint32_t(v.idx());
        out.triangles.push_back(t);
    }
    // Grid-cached objects: their own triangles, irradiance interpolated from
    // the grid's samples; a vertex counts the samples of its heaviest one.
    std::vector<Rgb> sampleMeans, vertexValues;
    for (const detail::GridObject& g : impl_->state.grids) {
        const uint32_t first = uint32_t(out.positions.size());
        sampleMeans.clear();
        for (size_t k = 0; k < g.grid->sampleCount(); ++k) sampleMeans.push_back(lm.gridStats[g.firstSample + k].mean());
        g.grid->interpolate(sampleMeans, vertexValues);
        const auto& offsets = g.grid->weightOffsets();
        for (size_t v = 0; v < g.positions.size(); ++v) {
            out.positions.push_back(g.positions[v]);
            out.normals.push_back(g.normals[v]);
            out.irradiance.push_back(vertexValues[v]);
            size_t heaviest = offsets[v];
            for (size_t k = offsets[v]; k < offsets[v + 1]; ++k)
                if (g.grid->weights()[k] > g.grid->weights()[heaviest]) heaviest = k;
            const detail::VertexStats& st = lm.gridStats[g.firstSample + g.grid->weightSamples()[heaviest]];
            out.samples.push_back(st.count);
            // A grid object's light is its samples' interpolant: its error is
            // its heaviest sample's noise (the grid is fine where it is
            // used), or a guess's while that sample has none.
            const double lum = luminance(vertexValues[v]);
            const Rgb se =
                colourOf(vertexValues[v], lum, st.count ? detail::meanNoise(st, noise) : kGuessedLightError * lum);
            out.standardError.push_back(measuredNoise(st) ? se : Rgb(0.0));
            out.predictedError.push_back(se);
            out.predictedNoise.push_back(st.count ? se : Rgb(0.0));
        }
        for (const glm::uvec3& t : g.triangles) out.triangles.push_back(t + glm::uvec3(first));
    }
    return out;
}

size_t IrradianceCache::bytesPerVertex() {
    // Array kernel, per vertex: a point, a normal, a status and an outgoing
    // halfedge; a triangle mesh has about 3 edges (6 halfedges of 4 indices,
    // an edge status) and 2 faces (a halfedge and a status) per vertex; plus
    // the sample sums.
    return sizeof(OpenMesh::Vec3d) * 2 + sizeof(int) * 2 + 6 * 4 * sizeof(int) + 3 * sizeof(int) +
           2 * 2 * sizeof(int) + sizeof(detail::VertexStats);
}

size_t IrradianceCache::memoryBytes() const {
    size_t bytes = 0;
    for (const detail::LightMesh& lm : impl_->state.meshes) {
        const CacheTriMesh& m = lm.mesh;
        bytes += m.n_vertices() * (sizeof(OpenMesh::Vec3d) * 2 + sizeof(int) * 2);
        bytes += m.n_halfedges() * sizeof(int) * 4 + m.n_edges() * sizeof(int) + m.n_faces() * sizeof(int) * 2;
        bytes += lm.stats.capacity() * sizeof(detail::VertexStats);
        bytes += lm.gridStats.capacity() * sizeof(detail::VertexStats);
    }
    for (const detail::GridObject& g : impl_->state.grids) bytes += g.grid->memoryBytes();
    return bytes;
}

namespace detail {

namespace {
// Whether every face around a vertex lies within 2.6 degrees of the plane
// facing `n` (cos 0.999, EdgeOnSurfaces' parallel test).
bool flatAround(const CacheTriMesh& mesh, CacheTriMesh::VertexHandle vh, const Vec3& n) {
    for (auto f : mesh.vf_range(vh)) {
        Vec3 p[3];
        int i = 0;
        for (auto u : mesh.fv_range(f)) p[i++] = toVec3(mesh.point(u));
        const Vec3 c = glm::cross(p[1] - p[0], p[2] - p[0]);
        const double len = glm::length(c);
        if (!(len > 0) || glm::dot(c, n) < 0.999 * len) return false;
    }
    return true;
}
}  // namespace

Vec3 samplePoint(const CacheState& s, const CacheTriMesh& mesh, CacheTriMesh::VertexHandle vh) {
    const Vec3 x = toVec3(mesh.point(vh));
    if (!mesh.is_boundary(vh)) return x;
    // A vertex on an object's border that lies in the plane of a surface
    // meeting it there (a wall's top under a ceiling, a floor's edge
    // against a wall) is sampled a thousandth of its shortest edge inside
    // its own faces (EdgeOnSurfaces.h); with CacheLayout::insetBorders every
    // border vertex is, by CacheLayout::borderInset of it (a floor's edge
    // under a wall, which would otherwise see both rooms). Only where its
    // faces are flat: at a fold (pages bound at a spine, fins on a hinge) a
    // point moved in the tangent plane leaves every face, and the vertex
    // itself is the only point they share.
    const Vec3 n = toVec3(mesh.normal(vh));
    if (!s.insetBorders && !(flatAround(mesh, vh, n) && s.edgeOn && s.edgeOn->through(x, n))) return x;
    Vec3 inward(0.0);
    double shortest = kInf;
    for (auto f : mesh.vf_range(vh)) {
        Vec3 c(0.0);
        for (auto u : mesh.fv_range(f)) c += toVec3(mesh.point(u));
        inward += c / 3.0 - x;
    }
    for (auto u : mesh.vv_range(vh)) shortest = std::min(shortest, glm::length(toVec3(mesh.point(u)) - x));
    inward -= glm::dot(inward, n) * n;
    if (!(glm::length(inward) > 0) || !(shortest < kInf)) return x;
    return x + (s.insetBorders ? s.borderInset : CacheLayout::kDefaultInset) * shortest * glm::normalize(inward);
}

SampleRequest requestFor(const CacheState& s, const PendingSample& p, uint32_t seed) {
    SampleRequest r;
    r.mesh = p.mesh;
    r.numbered = true;
    if (!p.grid) {
        const LightMesh& lm = s.meshes[p.mesh];
        const auto vh = CacheTriMesh::VertexHandle(int(p.index));
        r.x = samplePoint(s, lm.mesh, vh);
        r.n = toVec3(lm.mesh.normal(vh));
        r.index = uint32_t(lm.stats[p.index].count);
        r.seed = seedFor(seed, p.index, p.mesh, r.index);
        r.stream = seedFor(seed ^ 0x5eed5eedu, p.index, p.mesh);
    } else {
        const GridObject& o = gridOf(s, p.index);
        const size_t k = p.index - o.firstSample;
        r.x = o.grid->samplePosition(k);
        r.n = o.grid->sampleNormal(k);
        r.index = uint32_t(s.meshes[p.mesh].gridStats[p.index].count);
        r.seed = seedFor(seed, kGridSeedBase + p.index, p.mesh, r.index);
        r.stream = seedFor(seed ^ 0x5eed5eedu, kGridSeedBase + p.index, p.mesh);
    }
    return r;
}

// Where a sample failed, for the message: "vertex 1834 of light 2's cache
// mesh, sample 7 (point x,y,z; normal x,y,z)".
std::string whereSampled(const CacheState& s, const PendingSample& p, const SampleRequest& r) {
    if (!p.grid)
        return concat("vertex ", p.index, " of light ", p.mesh, "'s cache mesh, sample ",
                      s.meshes[p.mesh].stats[p.index].count, " (point ", r.x.x, ",", r.x.y, ",", r.x.z, "; normal ",
                      r.n.x, ",", r.n.y, ",", r.n.z, ")");
    const GridObject& o = gridOf(s, p.index);
    return concat("grid sample ", p.index - o.firstSample, " of object ", o.mesh, " for light ", p.mesh, ", sample ",
                  s.meshes[p.mesh].gridStats[p.index].count, " (point ", r.x.x, ",", r.x.y, ",", r.x.z, ")");
}

// A batch's failure, with the mesh, vertex and point of the request it names.
[[noreturn]] void throwWhereSampled(const CacheState& s, const std::vector<PendingSample>& pending,
                                    const std::vector<SampleRequest>& requests, const SampleBatchError& e) {
    const size_t i = e.index() < pending.size() ? e.index() : 0;
    throw std::runtime_error(concat("sampling failed at ", whereSampled(s, pending[i], requests[i]), ": ", e.what()));
}

namespace {

// One batch: pending[first, first + count).
void takeBatch(CacheState& s, VertexSampler& sampler, uint32_t seed, const std::vector<PendingSample>& pending,
               size_t first, size_t count) {
    const auto begin = pending.begin() + std::ptrdiff_t(first), end = begin + std::ptrdiff_t(count);
    std::vector<SampleRequest> requests;
    requests.reserve(count);
    for (auto p = begin; p != end; ++p) requests.push_back(requestFor(s, *p, seed));
    std::vector<VertexSample> results;
    try {
        sampler.sampleBatch(requests, results);
    } catch (const SampleBatchError& e) {
        throwWhereSampled(s, std::vector<PendingSample>(begin, end), requests, e);
    }
    ML_ASSERT(results.size() == count, "the sampler returned ", results.size(), " of ", count, " samples");
    for (size_t i = 0; i < count; ++i) {
        const PendingSample& p = pending[first + i];
        p.grid ? addGridSample(s, p.mesh, p.index, results[i]) : addVertexSample(s, p.mesh, p.index, results[i]);
    }
}

}  // namespace

size_t takeSamples(CacheState& s, VertexSampler& sampler, uint32_t seed, const std::vector<PendingSample>& pending,
                   const std::function<bool()>& interrupt) {
    if (pending.empty()) return 0;
    if (!interrupt) {
        takeBatch(s, sampler, seed, pending, 0, pending.size());
        return pending.size();
    }
    // Batches of about kInterruptBatchSeconds at the last one's rate (a
    // sample costs microseconds to tens of milliseconds by the scene), each
    // at least kFirstBatch (a batch is spread over the threads).
    constexpr size_t kFirstBatch = 32;
    size_t done = 0, size = kFirstBatch;
    while (done < pending.size()) {
        if (interrupt()) break;
        const size_t count = std::min(size, pending.size() - done);
        const auto start = std::chrono::steady_clock::now();
        takeBatch(s, sampler, seed, pending, done, count);
        done += count;
        const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const double next = took > 0 ? double(count) * kInterruptBatchSeconds / took : 4.0 * double(count);
        size = size_t(std::clamp(next, double(kFirstBatch), 4.0 * double(count)));
    }
    return done;
}

}  // namespace detail

size_t IrradianceCache::sampleUnsampled(VertexSampler& sampler, uint32_t seed,
                                        const std::function<void(size_t, size_t)>& progress) {
    const size_t todo = detail::unsampledCount(impl_->state);
    const FirstSamples first(sampler);
    // In batches, so that progress is told now and then.
    for (size_t left = todo; left > 0;) {
        detail::sampleUnsampled(impl_->state, sampler, seed, 4096);
        left = detail::unsampledCount(impl_->state);
        if (progress) progress(todo - left, todo);
    }
    return todo;
}

namespace detail {

size_t unsampledCount(const CacheState& s) {
    size_t n = 0;
    for (const LightMesh& lm : s.meshes) {
        for (const VertexStats& st : lm.stats) n += st.count == 0;
        for (const VertexStats& st : lm.gridStats) n += st.count == 0;
    }
    return n;
}

namespace {

bool flagged(const std::vector<char>& flags, size_t i) { return i < flags.size() && flags[i]; }

void flag(std::vector<char>& flags, size_t i, size_t size) {
    if (flags.size() < size) flags.resize(size, 0);
    flags[i] = 1;
}

// The pairs of `ranked` (in order) that the sampler answers without the GPU,
// until `budget` are taken: each asked once (LightMesh::needsGpu remembers
// the ones declined). Returns how many were taken.
size_t takeSamplesWithoutGpu(CacheState& s, VertexSampler& sampler, uint32_t seed,
                             const std::vector<PendingSample>& ranked, size_t budget,
                             const std::function<bool()>& interrupt) {
    std::vector<PendingSample> ask;
    std::vector<SampleRequest> requests;
    std::vector<VertexSample> results;
    std::vector<char> answered;
    size_t taken = 0, next = 0;
    while (taken < budget && next < ranked.size() && !(interrupt && interrupt())) {
        ask.clear();
        for (; next < ranked.size() && ask.size() < budget - taken; ++next) {
            const PendingSample& p = ranked[next];
            const LightMesh& lm = s.meshes[p.mesh];
            if (!flagged(p.grid ? lm.gridNeedsGpu : lm.needsGpu, p.index)) ask.push_back(p);
        }
        if (ask.empty()) break;
        requests.clear();
        for (const PendingSample& p : ask) requests.push_back(requestFor(s, p, seed));
        try {
            sampler.sampleBatchWithoutGpu(requests, results, answered);
        } catch (const SampleBatchError& e) {
            throwWhereSampled(s, ask, requests, e);
        }
        for (size_t i = 0; i < ask.size(); ++i) {
            const PendingSample& p = ask[i];
            LightMesh& lm = s.meshes[p.mesh];
            if (!answered[i]) {
                p.grid ? flag(lm.gridNeedsGpu, p.index, lm.gridStats.size()) : flag(lm.needsGpu, p.index, lm.stats.size());
                continue;
            }
            p.grid ? addGridSample(s, p.mesh, p.index, results[i]) : addVertexSample(s, p.mesh, p.index, results[i]);
            ++taken;
        }
    }
    return taken;
}

}  // namespace

size_t sampleUnsampled(CacheState& s, VertexSampler& sampler, uint32_t seed, size_t budget,
                       const std::function<bool()>& interrupt) {
    // Every mesh's first vertices before any mesh's later ones: base
    // vertices (numbered first) of every light before the vertices that
    // refinement added, so that all the light is in the image early; grid
    // samples after the mesh vertices of the same rank.
    // Within a rank, vertices in a scattered (hashed) order, so that a
    // partial first pass covers every object evenly (IrradianceCache::
    // copyMesh fills the rest from sampled neighbours).
    // In that order, first the pairs the sampler answers without the GPU
    // (a light below the horizon, nothing in the way: microseconds each),
    // then the others: in a room lit by many lights most of the light is
    // in the image after a fraction of a second.
    std::vector<std::pair<uint64_t, PendingSample>> ranked;
    for (size_t l = 0; l < s.meshes.size(); ++l) {
        const LightMesh& lm = s.meshes[l];
        for (size_t i = 0; i < lm.stats.size(); ++i)
            if (lm.stats[i].count == 0)
                ranked.push_back({(uint64_t(hash32(uint32_t(i))) << 32) | (uint64_t(l) << 1), {uint32_t(l), uint32_t(i), false}});
        for (size_t g = 0; g < lm.gridStats.size(); ++g)
            if (lm.gridStats[g].count == 0)
                ranked.push_back({(uint64_t(hash32(kGridSeedBase + uint32_t(g))) << 32) | (uint64_t(l) << 1) | 1u,
                                  {uint32_t(l), uint32_t(g), true}});
    }
    std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
        return a.first != b.first ? a.first < b.first
                                  : std::tie(a.second.mesh, a.second.index) < std::tie(b.second.mesh, b.second.index);
    });
    std::vector<PendingSample> order;
    order.reserve(ranked.size());
    for (const auto& r : ranked) order.push_back(r.second);
    const size_t cheap = takeSamplesWithoutGpu(s, sampler, seed, order, budget, interrupt);
    std::vector<PendingSample> pending;
    for (const PendingSample& p : order) {
        if (pending.size() + cheap >= budget) break;
        const LightMesh& lm = s.meshes[p.mesh];
        if ((p.grid ? lm.gridStats[p.index] : lm.stats[p.index]).count == 0) pending.push_back(p);
    }
    const size_t taken = takeSamples(s, sampler, seed, pending, interrupt);
    // Noise probes (IrradianceCache::setNoiseProbes): a second sample for
    // the picked vertices among those just sampled, drawn as a resample is
    // (its own index in the vertex's stream).
    std::vector<PendingSample> probes;
    if (s.noiseProbeEvery > 0)
        for (size_t i = 0; i < taken; ++i) {
            const PendingSample& p = pending[i];
            const uint32_t key = p.grid ? kGridSeedBase + p.index : p.index;
            if (hash32(key ^ 0x9e3779b9u) % s.noiseProbeEvery == 0) probes.push_back(p);
        }
    return cheap + taken + takeSamples(s, sampler, seed, probes, interrupt);
}

void addVertexSample(CacheState& s, size_t l, size_t v, const VertexSample& sample) {
    ML_ASSERT(isFinite(sample.irradiance), "non-finite irradiance at vertex ", v, " of light ", l);
    ML_ASSERT(sample.visibility >= 0 && sample.visibility <= 1, "visibility ", sample.visibility, " at vertex ",
              v, " of light ", l);
    ML_ASSERT(sample.work > 0 && std::isfinite(sample.work), "work ", sample.work, " at vertex ", v, " of light ", l);
    s.meshes[l].stats.at(v).add(sample);
    s.fullWork = std::max(s.fullWork, sample.work);
    s.samples += 1;
}

void addGridSample(CacheState& s, size_t l, size_t g, const VertexSample& sample) {
    ML_ASSERT(isFinite(sample.irradiance), "non-finite irradiance at grid sample ", g, " of light ", l);
    ML_ASSERT(sample.visibility >= 0 && sample.visibility <= 1, "visibility ", sample.visibility,
              " at grid sample ", g, " of light ", l);
    ML_ASSERT(sample.work > 0 && std::isfinite(sample.work), "work ", sample.work, " at grid sample ", g, " of light ", l);
    s.meshes[l].gridStats.at(g).add(sample);
    s.fullWork = std::max(s.fullWork, sample.work);
    s.samples += 1;
}

const GridObject& gridOf(const CacheState& s, size_t g) {
    for (const GridObject& o : s.grids)
        if (g >= o.firstSample && g < o.firstSample + o.grid->sampleCount()) return o;
    ML_ASSERT(false, "grid sample ", g, " of ", s.gridSamples);
    return s.grids.front();
}

}  // namespace detail

void sampleEveryVertex(IrradianceCache& cache, VertexSampler& sampler, int passes, uint32_t seed,
                       const std::function<void(size_t, size_t)>& progress) {
    size_t total = 0, done = 0;
    for (size_t l = 0; l < cache.lightCount(); ++l) total += cache.vertexCount(l);
    for (size_t l = 0; l < cache.lightCount(); ++l) {
        for (size_t v = 0; v < cache.vertexCount(l); ++v) {
            for (int p = 0; p < passes; ++p) {
                try {
                    const uint32_t s = seedFor(seed, uint32_t(v), uint32_t(l), uint32_t(p));
                    cache.addSample(l, v, sampler.sample(l, cache.position(l, v), cache.normal(l, v), s));
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
