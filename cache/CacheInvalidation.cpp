#include "CacheInvalidation.h"

#include "core/Error.h"
#include "detail/CacheImpl.h"

#include <algorithm>
#include <cmath>

namespace ml {

using detail::CacheTriMesh;
using detail::toOm;
using detail::toVec3;

namespace {

// A vertex forgotten: no samples, no kept mean, asked again whether it
// needs the GPU.
void forgetStats(std::vector<detail::VertexStats>& stats, std::vector<Rgb>& provisional, std::vector<char>& needsGpu,
                 size_t i) {
    stats[i] = {};
    if (i < provisional.size()) provisional[i] = Rgb(-1.0);
    if (i < needsGpu.size()) needsGpu[i] = 0;
}

// Point p lies on triangle t: within `eps` of its plane and inside its
// edges (barycentric coordinates ≥ −1e-9).
bool onTriangle(const Vec3& p, const Triangle3& t, double eps) {
    const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0], n = glm::cross(e1, e2);
    const double n2 = glm::dot(n, n);
    if (!(n2 > 0)) return false;
    const Vec3 d = p - t[0];
    if (std::abs(glm::dot(d, n)) > eps * std::sqrt(n2)) return false;
    const double b1 = glm::dot(glm::cross(d, e2), n) / n2, b2 = glm::dot(glm::cross(e1, d), n) / n2;
    return b1 >= -1e-9 && b2 >= -1e-9 && b1 + b2 <= 1 + 1e-9;
}

}  // namespace

size_t IrradianceCache::forget(size_t mesh, const std::function<bool(const Vec3&, const Vec3&)>& which) {
    detail::CacheState& s = impl_->state;
    detail::LightMesh& lm = s.meshes.at(mesh);
    size_t n = 0;
    for (auto v : lm.mesh.vertices()) {
        const size_t i = size_t(v.idx());
        if (!which(detail::samplePoint(s, lm.mesh, v), toVec3(lm.mesh.normal(v)))) continue;
        n += lm.stats[i].count > 0;
        forgetStats(lm.stats, lm.provisional, lm.needsGpu, i);
    }
    std::vector<Rgb> noProvisional;  // grid samples keep no mean
    for (const detail::GridObject& g : s.grids)
        for (size_t k = 0; k < g.grid->sampleCount(); ++k) {
            const size_t i = g.firstSample + k;
            if (!which(g.grid->samplePosition(k), g.grid->sampleNormal(k))) continue;
            n += lm.gridStats[i].count > 0;
            forgetStats(lm.gridStats, noProvisional, lm.gridNeedsGpu, i);
        }
    return n;
}

size_t IrradianceCache::moveFaces(const Scene& before, const AppliedChange& change) {
    if (change.mesh < 0) return 0;
    detail::CacheState& s = impl_->state;
    const Mesh& old = before.meshes.at(size_t(change.mesh));
    std::vector<Triangle3> faces;
    Bounds3 box;
    for (uint32_t t : change.triangles) {
        faces.push_back(old.triangle(t));
        for (const Vec3& p : faces.back()) box.extend(p);
    }
    // Split vertices sit on their faces to rounding; 1e-7 of the scene
    // keeps a floor a hair below a block's base apart from it.
    const double eps = 1e-7 * s.diagonal;
    box.lo -= Vec3(eps), box.hi += Vec3(eps);
    const auto onFaces = [&](const Vec3& p) {
        if (glm::any(glm::lessThan(p, box.lo)) || glm::any(glm::greaterThan(p, box.hi))) return false;
        return std::any_of(faces.begin(), faces.end(), [&](const Triangle3& t) { return onTriangle(p, t, eps); });
    };
    size_t moved = 0;
    for (detail::LightMesh& lm : s.meshes) {
        CacheTriMesh& m = lm.mesh;
        // Parts of the mesh by connection; a part moves when every vertex of
        // it lies on the moved faces (a floor under a block's base does not).
        std::vector<int> part(m.n_vertices(), -1);
        std::vector<char> whole;
        std::vector<CacheTriMesh::VertexHandle> stack;
        for (auto seed : m.vertices()) {
            if (part[size_t(seed.idx())] >= 0) continue;
            const int id = int(whole.size());
            whole.push_back(1);
            part[size_t(seed.idx())] = id;
            stack.assign(1, seed);
            while (!stack.empty()) {
                const auto v = stack.back();
                stack.pop_back();
                if (whole[size_t(id)] && !onFaces(toVec3(m.point(v)))) whole[size_t(id)] = 0;
                for (auto u : m.vv_range(v))
                    if (part[size_t(u.idx())] < 0) part[size_t(u.idx())] = id, stack.push_back(u);
            }
        }
        for (auto v : m.vertices()) {
            const size_t i = size_t(v.idx());
            if (!whole[size_t(part[i])]) continue;
            m.set_point(v, toOm(change.transform(toVec3(m.point(v)))));
            m.set_normal(v, toOm(glm::normalize(change.rotation * toVec3(m.normal(v)))));
            forgetStats(lm.stats, lm.provisional, lm.needsGpu, i);
            ++moved;
        }
    }
    // A grid-cached object is laid on its moved mesh again; the grid hangs
    // from the object's bounding-box corner, so a move keeps its samples'
    // number (a rotation may not: then the cache must be made again).
    const Mesh& now = change.scene.meshes.at(size_t(change.mesh));
    for (detail::GridObject& g : s.grids) {
        if (g.mesh != uint32_t(change.mesh)) continue;
        GridCacheSettings gs;
        gs.cellSize = s.settings.maxEdgeFraction * s.diagonal;
        auto grid = std::make_shared<const GridCache>(now, gs);
        if (grid->sampleCount() != g.grid->sampleCount())
            throw InputError(concat("object '", now.name, "' is cached on a grid that its rotation changes (",
                                    g.grid->sampleCount(), " samples before, ", grid->sampleCount(),
                                    " after): the cache must be made again"));
        g.grid = std::move(grid);
        g.positions = now.positions;
        g.normals = now.normals;
        for (detail::LightMesh& lm : s.meshes) {
            std::vector<Rgb> none;
            for (size_t k = 0; k < g.grid->sampleCount(); ++k)
                forgetStats(lm.gridStats, none, lm.gridNeedsGpu, g.firstSample + k);
        }
        moved += g.positions.size();
    }
    return moved;
}

void IrradianceCache::sceneChanged(const Scene& after) {
    detail::CacheState& s = impl_->state;
    s.sceneFingerprint = detail::sceneFingerprint(after);
    s.edgeOn = EdgeOnSurfaces::forScene(after, s.sceneFingerprint);
}

std::string InvalidationReport::describe() const {
    return concat(lightVertices, " vertices of the moved light, ", shadowVertices, " in its shadow's reach, ",
                  movedVertices, " moved, forgotten; ", keptVertices, " kept; ", indirectVertices,
                  " indirect vertices stale",
                  oldIndirectKept ? concat(" (the old indirect light shown until gathered again: ",
                                           std::lround(1000 * movedLightShare) / 10.0, "% of the light moved)")
                                  : std::string());
}

Bounds3 lightVolume(const Scene& scene, size_t l, const Vec3& x) {
    const Light& light = scene.lights.at(l);
    Bounds3 b;
    if (light.kind == LightKind::Directional) {
        b.extend(x - 2 * std::max(scene.bounds.diagonal(), 1e-30) * light.emission.axis);
    } else if (light.kind == LightKind::Point) {
        b.extend(light.emission.position);
    } else {
        b = light.bounds;
    }
    return b;
}

bool hullMeets(const Vec3& x, const Bounds3& light, const Bounds3& box) {
    // The box at t is [x + t (lo − x), x + t (hi − x)]; per axis it meets
    // `box` while x + t (lo − x) ≤ box.hi and x + t (hi − x) ≥ box.lo, each
    // a half-line of t.
    double t0 = 0, t1 = 1;
    for (int a = 0; a < 3; ++a) {
        const auto clip = [&](double slope, double rest) {  // keeps t with slope·t ≤ rest
            if (slope > 0) t1 = std::min(t1, rest / slope);
            else if (slope < 0) t0 = std::max(t0, rest / slope);
            else if (rest < 0) t1 = -1;
        };
        clip(light.lo[a] - x[a], box.hi[a] - x[a]);
        clip(-(light.hi[a] - x[a]), x[a] - box.lo[a]);
    }
    return t0 <= t1;
}

InvalidationReport invalidateCache(IrradianceCache& direct, IndirectSolver* indirect, const LightCoverage* coverage,
                                   const Scene& before, const AppliedChange& change) {
    const Scene& after = change.scene;
    if (change.detached)
        throw InputError(concat("the faces that moved in '", before.meshes.at(size_t(change.mesh)).name,
                                "' shared vertices with faces that stay: the cache cannot follow them, it must be "
                                "made again"));
    InvalidationReport r;
    const size_t lights = direct.lightCount();
    const bool shared = direct.hasSharedMesh();
    // The object's own faces first: they move in every mesh.
    r.movedVertices = direct.moveFaces(before, change);
    direct.sceneChanged(after);
    // A moved light: its own mesh whole, and the shared mesh where it has weight there.
    for (size_t l : change.lights) {
        if (l < lights) r.lightVertices += direct.rebuildMesh(l, after);
        if (shared && coverage)
            r.lightVertices += direct.forget(lights, [&](const Vec3& x, const Vec3&) { return coverage->weight(l, x) < 1; });
    }
    // A moved object: what any light's view may have changed through its
    // old or new box. The shared mesh holds every light's share, so any
    // light's test forgets its vertex.
    const bool object = change.mesh >= 0 && !change.before.empty();
    if (object && !after.lights.empty()) {
        for (size_t mesh = 0; mesh < direct.meshCount(); ++mesh) {
            const bool isShared = shared && mesh == lights;
            const size_t forgotten = direct.forget(mesh, [&](const Vec3& x, const Vec3&) {
                for (size_t l = 0; l < after.lights.size(); ++l) {
                    if (!isShared && l != mesh) continue;
                    if (std::find(change.lights.begin(), change.lights.end(), l) != change.lights.end()) continue;
                    for (const Scene* s : {&before, &after}) {
                        const Bounds3 v = lightVolume(*s, l, x);
                        if (hullMeets(x, v, change.before) || hullMeets(x, v, change.after)) return true;
                    }
                }
                return false;
            });
            r.shadowVertices += forgotten;
            // Where shadows moved, the mesh's refinement followed them: laid
            // again on the base, keeping the base's valid samples, it is
            // back sooner than by sampling those refined vertices again
            // (bench dynamic).
            if (forgotten > 0) direct.rebuildKeepingBase(mesh, after);
        }
    }
    const size_t total = direct.totalVertices();
    const size_t forgotten = direct.unsampledCount();
    r.keptVertices = total > forgotten ? total - forgotten : 0;
    double moved = 0, all = 0;
    for (size_t l = 0; l < after.lights.size(); ++l) {
        const double p = luminance(after.lights[l].power());
        all += p;
        if (std::find(change.lights.begin(), change.lights.end(), l) != change.lights.end()) moved += p;
    }
    r.movedLightShare = all > 0 ? moved / all : 0;
    if (indirect) {
        r.indirectVertices = indirect->totalVertices();
        // Only emitters moved: a punctual light, or an area light's own faces.
        bool emittersOnly = !change.lights.empty();
        if (emittersOnly && change.mesh >= 0) {
            const Mesh& m = after.meshes.at(size_t(change.mesh));
            for (uint32_t t : change.triangles) emittersOnly = emittersOnly && after.materials.at(m.materials.at(t)).emissive();
        }
        r.oldIndirectKept = emittersOnly && r.movedLightShare <= kKeepOldLightShare;
        indirect->sceneChanged(r.oldIndirectKept);
        r.oldIndirectKept = r.oldIndirectKept && indirect->keepingStale();
    }
    return r;
}

}  // namespace ml
