// The cache's one CGAL translation unit (10-20 s and over 1 GB to compile),
// alone in the library meshlight_contact_cuts.
#include "ContactCuts.h"

#include "core/BoundsGrid.h"
#include "core/MeshUtil.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Constrained_triangulation_face_base_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <tuple>

namespace ml {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, Kernel>;
using FaceBase = CGAL::Constrained_triangulation_face_base_2<Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
// Exact_predicates_tag: constraints may cross (two objects' outlines); the
// crossings are constructed in doubles.
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, CGAL::Exact_predicates_tag>;

// Edges hanging over a gap narrower than this fraction of the scene's size
// cut nothing: a penumbra that narrow is under a pixel in a view of the
// whole scene, and the cache's hidden-vertex rule (IndirectSolver.h) already
// keeps what is boxed in from darkening its neighbours.
constexpr double kLeastGap = 1e-3;

// Faces of a cut triangle thinner than this fraction of the scene's size are
// dropped (a hole too thin for any pixel): the GPU gets positions in floats,
// 6e-8 of their size, and a face that thin is degenerate there.
constexpr double kThinnest = 1e-6;

// A hanging surface's face is parallel to the receiver when their normals'
// cosine is at least this (within 2.6°), and a line lies in a face's plane
// within this fraction of the scene's size.
constexpr double kParallel = 0.999;
constexpr double kCoplanar = 1e-7;

// The depths (in units of the gap h) of the lines inside a hanging face
// parallel to the receiver: where the light through the gap, 1/2 · h²/(h² +
// d²) of the open value, is 0.1 and 0.014, read linearly in between within
// 0.015 of the open value. The receiver has vertices of its own under the
// face (its base mesh's); a panel's back, none but its corners.
constexpr double kInside[] = {2, 6};

// The depths (in units of h) of the receiver's lines under such a face,
// where the light through the gap is convex (ContactCuts.h says why).
constexpr double kUnder[] = {1, 3};

// An edge of some surface, welded by position, with the triangles beside it.
struct SceneEdge {
    Vec3 a, b;
    std::vector<std::pair<uint32_t, uint32_t>> faces;  // (mesh, triangle)
};

using PositionPair = std::array<double, 6>;

PositionPair keyOf(const Vec3& p, const Vec3& q) {
    const bool swap = std::tie(q.x, q.y, q.z) < std::tie(p.x, p.y, p.z);
    const Vec3& a = swap ? q : p;
    const Vec3& b = swap ? p : q;
    return {a.x, a.y, a.z, b.x, b.y, b.z};
}

Vec3 unitNormal(const Mesh& m, size_t t) { return glm::normalize(m.areaNormal(t)); }

// The unit vector, in face `face` of `hanging` and square to `edge`, from
// the edge into the face, where that face is parallel to a receiver of
// normal n (kParallel); false where it is not, or too thin to say.
bool inwardInto(const SceneEdge& edge, const Mesh& hanging, uint32_t face, const Vec3& n, double touch,
                Vec3& inward) {
    if (std::abs(glm::dot(unitNormal(hanging, face), n)) < kParallel) return false;
    const Vec3 edgeDir = glm::normalize(edge.b - edge.a);
    const auto away = [&](const Vec3& c) { return glm::length(glm::cross(c - edge.a, edgeDir)); };
    const Triangle3 q = hanging.triangle(face);
    Vec3 off = q[0];
    for (const Vec3& c : q)
        if (away(c) > away(off)) off = c;
    const Vec3 in = (off - edge.a) - glm::dot(off - edge.a, edgeDir) * edgeDir;
    if (!(glm::length(in) > touch)) return false;
    inward = glm::normalize(in);
    return true;
}

// The edges' bounds, padded by how far in front of a receiver an edge may
// hang, in a grid: the edges near a receiver.
BoundsGrid edgeGrid(const Bounds3& bounds, const std::vector<SceneEdge>& edges, double closeness) {
    const double cell = BoundsGrid::cellSize(bounds, edges.size());
    std::vector<Bounds3> boxes(edges.size());
    for (size_t e = 0; e < edges.size(); ++e) {
        boxes[e].extend(edges[e].a);
        boxes[e].extend(edges[e].b);
        const double pad = closeness * glm::length(edges[e].b - edges[e].a) + 1e-9 * cell;
        boxes[e].lo -= Vec3(pad);
        boxes[e].hi += Vec3(pad);
    }
    return BoundsGrid(bounds, boxes);
}

// A point of a cut, in the receiver's barycentric coordinates (x along
// corner 0 → 1, y along 0 → 2): a corner, a point on an edge, or inside.
struct CutPoint {
    enum Kind { Corner, OnEdge, Inside } kind = Inside;
    int index = 0;   // the corner, or the edge (0: corners 0-1, 1: 1-2, 2: 0-2)
    double t = 0;    // on an edge: from its lower corner to its higher
    double x = 0, y = 0;
};

// The corners an edge joins, lower first.
constexpr int kEdgeCorners[3][2] = {{0, 1}, {1, 2}, {0, 2}};

// The barycentric coordinates of a point on edge e at parameter t.
std::pair<double, double> onEdge(int e, double t) {
    if (e == 0) return {t, 0.0};
    if (e == 2) return {0.0, t};
    return {1.0 - t, t};
}

// Snaps a clipped end onto the receiver's boundary where it lies within
// `tol` (barycentric) of it.
CutPoint classify(double x, double y, double tol) {
    const bool onX = std::abs(x) <= tol, onY = std::abs(y) <= tol, onZ = std::abs(1.0 - x - y) <= tol;
    CutPoint p;
    p.x = x, p.y = y;
    if (onX && onY) return {CutPoint::Corner, 0, 0, 0.0, 0.0};
    if (onY && onZ) return {CutPoint::Corner, 1, 0, 1.0, 0.0};
    if (onX && onZ) return {CutPoint::Corner, 2, 0, 0.0, 1.0};
    if (onY) p.kind = CutPoint::OnEdge, p.index = 0, p.t = std::clamp(x, 0.0, 1.0);
    else if (onZ) p.kind = CutPoint::OnEdge, p.index = 1, p.t = std::clamp(y, 0.0, 1.0);
    else if (onX) p.kind = CutPoint::OnEdge, p.index = 2, p.t = std::clamp(y, 0.0, 1.0);
    return p;
}

// Whether two clipped ends lie on one side of the receiver (the cut runs
// along its boundary and cuts nothing).
bool alongBoundary(const CutPoint& a, const CutPoint& b) {
    auto sides = [](const CutPoint& p) {
        if (p.kind == CutPoint::Corner) return p.index == 0 ? 0b101 : p.index == 1 ? 0b011 : 0b110;
        if (p.kind == CutPoint::OnEdge) return 1 << p.index;
        return 0;
    };
    return (sides(a) & sides(b)) != 0;
}

struct Receiver {
    Vec3 p0, e1, e2, n;
    double g11, g12, g22, det;
    // Barycentric (x, y) of the projection of q onto the plane.
    std::pair<double, double> local(const Vec3& q) const {
        const Vec3 d = q - p0;
        const double b1 = glm::dot(d, e1), b2 = glm::dot(d, e2);
        return {(g22 * b1 - g12 * b2) / det, (g11 * b2 - g12 * b1) / det};
    }
};

// Clips segment (a, b), given in barycentric coordinates, to the triangle
// x >= 0, y >= 0, x + y <= 1 (Liang-Barsky); false when nothing is left.
bool clip(std::pair<double, double>& a, std::pair<double, double>& b) {
    double s0 = 0, s1 = 1;
    const double dx = b.first - a.first, dy = b.second - a.second;
    // Each side as p·s <= q.
    const double p[3] = {-dx, -dy, dx + dy};
    const double q[3] = {a.first, a.second, 1.0 - a.first - a.second};
    for (int k = 0; k < 3; ++k) {
        if (p[k] == 0) {
            if (q[k] < 0) return false;
            continue;
        }
        const double r = q[k] / p[k];
        if (p[k] < 0) s0 = std::max(s0, r);
        else s1 = std::min(s1, r);
        if (s0 > s1) return false;
    }
    const auto at = [&](double s) { return std::make_pair(a.first + s * dx, a.second + s * dy); };
    const auto na = at(s0), nb = at(s1);
    a = na, b = nb;
    return true;
}

// Whether boxes x and y share a point.
bool overlaps(const Bounds3& x, const Bounds3& y) {
    for (int k = 0; k < 3; ++k)
        if (x.hi[k] < y.lo[k] || x.lo[k] > y.hi[k]) return false;
    return true;
}

// Where triangle p (bounds b) crosses `plane` inside its region: the
// segment (a, b3) of the line they share, clipped to the region. False when
// the triangle lies within `least` of the plane on either side (it touches
// the plane or barely crosses it) or the line misses the region.
bool planeCrossing(const Triangle3& p, const Bounds3& b, const CutPlane& plane, double least, Vec3& a, Vec3& b3) {
    if (!overlaps(b, plane.region)) return false;
    double d[3];
    for (int k = 0; k < 3; ++k) d[k] = glm::dot(p[size_t(k)] - plane.point, plane.normal);
    if (!(std::max({d[0], d[1], d[2]}) > least && std::min({d[0], d[1], d[2]}) < -least)) return false;
    // The line meets two edges whose ends lie on either side (or an edge
    // and the corner the plane passes through).
    Vec3 ends[2];
    int found = 0;
    for (int k = 0; k < 3 && found < 2; ++k)
        if (d[k] == 0) ends[found++] = p[size_t(k)];
    for (int e = 0; e < 3 && found < 2; ++e) {
        const int i = kEdgeCorners[e][0], j = kEdgeCorners[e][1];
        if (!((d[i] < 0 && d[j] > 0) || (d[i] > 0 && d[j] < 0))) continue;
        ends[found++] = p[size_t(i)] + (d[i] / (d[i] - d[j])) * (p[size_t(j)] - p[size_t(i)]);
    }
    if (found < 2) return false;
    // Clipped to the region's slabs.
    double s0 = 0, s1 = 1;
    const Vec3 dir = ends[1] - ends[0];
    for (int k = 0; k < 3; ++k) {
        if (dir[k] == 0) {
            if (ends[0][k] < plane.region.lo[k] || ends[0][k] > plane.region.hi[k]) return false;
            continue;
        }
        double u = (plane.region.lo[k] - ends[0][k]) / dir[k], v = (plane.region.hi[k] - ends[0][k]) / dir[k];
        if (u > v) std::swap(u, v);
        s0 = std::max(s0, u), s1 = std::min(s1, v);
        if (!(s0 < s1)) return false;
    }
    a = ends[0] + s0 * dir;
    b3 = ends[0] + s1 * dir;
    return true;
}

// About the distance from segment (a, b) to the nearest of `boxes`: from
// the point of the segment nearest each box's centre. Infinity with none.
double nearestLight(const Vec3& a, const Vec3& b, const std::vector<Bounds3>& boxes) {
    double best = std::numeric_limits<double>::infinity();
    const Vec3 d = b - a;
    const double dd = glm::dot(d, d);
    for (const Bounds3& box : boxes) {
        const double t = dd > 0 ? std::clamp(glm::dot(box.center() - a, d) / dd, 0.0, 1.0) : 0.0;
        const Vec3 q = a + t * d;
        best = std::min(best, glm::length(q - glm::clamp(q, box.lo, box.hi)));
    }
    return best;
}

// Whether triangle p (bounds b) reaches the band in front of `plane` where
// its lines go: within its region, not wholly behind the plane (by more
// than `least`), and not wholly further in front than `depth`.
bool inPlaneBand(const Triangle3& p, const Bounds3& b, const CutPlane& plane, double least, double depth) {
    if (!overlaps(b, plane.region)) return false;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3& q : p) {
        const double d = glm::dot(q - plane.point, plane.normal);
        lo = std::min(lo, d), hi = std::max(hi, d);
    }
    return hi > least && lo < depth;
}

// The two corners of triangle p farthest apart once projected onto
// `plane`, projected: the extent of the triangle's shadow on it.
void shadowOnPlane(const Triangle3& p, const CutPlane& plane, Vec3& a, Vec3& b) {
    Vec3 q[3];
    for (int k = 0; k < 3; ++k) q[k] = p[size_t(k)] - glm::dot(p[size_t(k)] - plane.point, plane.normal) * plane.normal;
    int best = 0;
    double longest = -1;
    for (int e = 0; e < 3; ++e) {
        const double l = glm::length(q[kEdgeCorners[e][1]] - q[kEdgeCorners[e][0]]);
        if (l > longest) longest = l, best = e;
    }
    a = q[kEdgeCorners[best][0]];
    b = q[kEdgeCorners[best][1]];
}

struct CutMesh {
    std::vector<Vec3> positions, normals;
    std::vector<Vec2> texcoords;
    // Points put on an edge (v0 < v1, the mesh's vertex indices): its
    // parameter from v0 and the vertex index it got.
    std::map<std::pair<uint32_t, uint32_t>, std::vector<std::pair<double, uint32_t>>> onEdges;
    std::vector<std::vector<std::pair<CutPoint, CutPoint>>> segments;  // per triangle
};

}  // namespace

std::vector<CutPlane> lightCutPlanes(const Scene& scene) {
    const double diagonal = scene.bounds.diagonal() > 0 ? scene.bounds.diagonal() : 1.0;
    std::vector<std::pair<double, CutPlane>> planes;  // (power, plane)
    for (const Light& l : scene.lights) {
        if (l.punctual() || !l.planar || !(l.area > 0) || !(glm::length(l.normal) > 0.5) || l.bounds.empty())
            continue;
        const Vec3 n = glm::normalize(l.normal);
        const Vec3 grow(2 * l.bounds.diagonal());
        Bounds3 region;
        region.lo = l.bounds.lo - grow, region.hi = l.bounds.hi + grow;
        // The plane it lies in, if an earlier light made it (either facing).
        size_t at = 0;
        while (at < planes.size() &&
               !(std::abs(glm::dot(planes[at].second.normal, n)) >= 1.0 - 1e-9 &&
                 std::abs(glm::dot(l.centroid - planes[at].second.point, planes[at].second.normal)) <=
                     1e-6 * diagonal))
            ++at;
        if (at == planes.size()) planes.push_back({0.0, CutPlane{l.centroid, n, region, {}}});
        auto& [power, plane] = planes[at];
        power += luminance(l.power());
        plane.region.extend(region);
        plane.lights.push_back(l.bounds);
    }
    std::stable_sort(planes.begin(), planes.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    std::vector<CutPlane> out;
    for (size_t i = 0; i < planes.size() && i < kMaxLightPlanes; ++i) out.push_back(planes[i].second);
    return out;
}

std::vector<Mesh> cutAlongContacts(const Scene& scene, const std::vector<bool>& skip,
                                   const ContactCutSettings& settings, ContactCutReport* report) {
    ContactCutReport rep;
    rep.planes = settings.planes.size();
    const double diagonal = scene.bounds.diagonal() > 0 ? scene.bounds.diagonal() : 1.0;
    const double touch = 1e-7 * diagonal;
    // The receivers near a light's plane are bisected to the base's spacing
    // first, and cut after (ContactCutSettings::planes).
    std::vector<Mesh> bisected;
    if (!settings.planes.empty() && settings.spacing > 0) {
        bisected = scene.meshes;
        for (size_t mi = 0; mi < bisected.size(); ++mi) {
            const Mesh& m = scene.meshes[mi];
            if (mi < skip.size() && skip[mi]) continue;
            bool nearPlane = false;
            for (size_t t = 0; t < m.triangles.size() && !nearPlane; ++t) {
                const Triangle3 p = m.triangle(t);
                Bounds3 b;
                for (const Vec3& q : p) b.extend(q);
                for (const CutPlane& plane : settings.planes)
                    nearPlane = nearPlane || inPlaneBand(p, b, plane, kLeastGap * diagonal, 0.5 * settings.spacing);
            }
            if (nearPlane) bisectLongEdges(bisected[mi], settings.spacing);
        }
    }
    const std::vector<Mesh>& meshes = bisected.empty() ? scene.meshes : bisected;
    std::vector<Mesh> out = meshes;

    // Every edge of the scene, welded by position, with the faces beside it.
    std::vector<SceneEdge> edges;
    {
        std::map<PositionPair, uint32_t> index;
        for (size_t mi = 0; mi < meshes.size(); ++mi) {
            const Mesh& m = meshes[mi];
            for (size_t t = 0; t < m.triangles.size(); ++t) {
                if (!(m.area(t) > 0)) continue;
                const Triangle3 p = m.triangle(t);
                for (int k = 0; k < 3; ++k) {
                    const Vec3& a = p[size_t(k)];
                    const Vec3& b = p[size_t((k + 1) % 3)];
                    const auto [it, added] = index.emplace(keyOf(a, b), uint32_t(edges.size()));
                    if (added) edges.push_back({a, b, {}});
                    edges[it->second].faces.emplace_back(uint32_t(mi), uint32_t(t));
                }
            }
        }
    }
    // An edge inside a flat surface (two coplanar faces facing one way) cuts nothing.
    std::vector<char> flat(edges.size(), 0);
    for (size_t e = 0; e < edges.size(); ++e) {
        const auto& f = edges[e].faces;
        if (f.size() != 2) continue;
        const double c = glm::dot(unitNormal(meshes[f[0].first], f[0].second),
                                  unitNormal(meshes[f[1].first], f[1].second));
        flat[e] = c > 1.0 - 1e-6;
    }
    const BoundsGrid grid = edgeGrid(scene.bounds, edges, settings.closeness);

    std::vector<CutMesh> cuts(meshes.size());
    std::vector<uint32_t> near, lines;  // scratch: the edges and the hanging faces' lines near a receiver
    // Registers an end on the receiver's edge, once: a new vertex there.
    const auto registerOnEdge = [&](CutMesh& cm, const Mesh& m, const glm::uvec3& tri, CutPoint& p) {
        const uint32_t va = tri[kEdgeCorners[p.index][0]], vb = tri[kEdgeCorners[p.index][1]];
        const bool flip = vb < va;
        const std::pair<uint32_t, uint32_t> key = flip ? std::make_pair(vb, va) : std::make_pair(va, vb);
        const double t = flip ? 1.0 - p.t : p.t;
        auto& list = cm.onEdges[key];
        const double length = glm::length(m.positions[key.second] - m.positions[key.first]);
        const double tol = length > 0 ? touch / length : 1e-12;
        for (const auto& [s, v] : list)
            if (std::abs(s - t) <= tol) return;
        const uint32_t v = uint32_t(m.positions.size() + cm.positions.size());
        cm.positions.push_back((1.0 - t) * m.positions[key.first] + t * m.positions[key.second]);
        const Vec3 n = (1.0 - t) * m.normals[key.first] + t * m.normals[key.second];
        cm.normals.push_back(glm::length(n) > 1e-12 ? glm::normalize(n) : m.normals[key.first]);
        if (!m.texcoords.empty())
            cm.texcoords.push_back(Vec2((1.0 - t) * m.texcoords[key.first] + t * m.texcoords[key.second]));
        list.emplace_back(t, v);
    };

    // Two passes over the receivers. The first finds the hanging surfaces'
    // own lines (the header's paragraph on the hanging face's side): for
    // each (edge, face of the hanging surface beside it), lines in that face
    // kInside·h inside the edge, each kept as an edge with that face as its
    // one entry, so that the edges' grid finds it near every triangle of that mesh
    // it may cross (a quad's line crosses both halves). The second cuts.
    std::vector<SceneEdge> inner;
    std::set<std::pair<uint32_t, std::pair<uint32_t, uint32_t>>> innerDone;
    std::unique_ptr<BoundsGrid> innerGrid;
    for (int pass = 0; pass < 2; ++pass) {
        if (pass == 1 && !inner.empty()) innerGrid = std::make_unique<BoundsGrid>(edgeGrid(scene.bounds, inner, 0.0));
        for (size_t mi = 0; mi < meshes.size(); ++mi) {
            // A skipped receiver is not cut, but what hangs over it still
            // gets its own lines.
            if (pass == 1 && mi < skip.size() && skip[mi]) continue;
            const Mesh& m = meshes[mi];
            CutMesh& cm = cuts[mi];
            if (pass == 1) cm.segments.resize(m.triangles.size());
            for (size_t t = 0; t < m.triangles.size(); ++t) {
                if (!(m.area(t) > 0)) continue;
                const Triangle3 p = m.triangle(t);
                Receiver r;
                r.p0 = p[0], r.e1 = p[1] - p[0], r.e2 = p[2] - p[0];
                r.n = unitNormal(m, t);
                r.g11 = glm::dot(r.e1, r.e1), r.g12 = glm::dot(r.e1, r.e2), r.g22 = glm::dot(r.e2, r.e2);
                r.det = r.g11 * r.g22 - r.g12 * r.g12;
                if (!(r.det > 0)) continue;
                const double scale = std::sqrt(std::max({r.g11, r.g22, glm::dot(p[2] - p[1], p[2] - p[1])}));
                const double tol = touch / scale;  // barycentric snapping
                Bounds3 b;
                for (const Vec3& q : p) b.extend(q);
                grid.query(b, near);
                // Adds the part of segment (a3, b3) that crosses R, projected,
                // unless it misses R or runs along R's boundary.
                const auto addSegment = [&](const Vec3& a3, const Vec3& b3) {
                    auto a = r.local(a3), bb = r.local(b3);
                    if (!clip(a, bb)) return false;
                    CutPoint ca = classify(a.first, a.second, tol), cb = classify(bb.first, bb.second, tol);
                    if (alongBoundary(ca, cb)) return false;
                    const Vec3 d = (bb.first - a.first) * r.e1 + (bb.second - a.second) * r.e2;
                    if (glm::length(d) <= touch) return false;
                    for (CutPoint* c : {&ca, &cb})
                        if (c->kind == CutPoint::OnEdge) registerOnEdge(cm, m, m.triangles[t], *c);
                    cm.segments[t].emplace_back(ca, cb);
                    ++rep.segments;
                    return true;
                };
                if (pass == 1)
                    for (const CutPlane& plane : settings.planes) {
                        Vec3 a, bb;
                        if (planeCrossing(p, b, plane, kLeastGap * diagonal, a, bb) && addSegment(a, bb))
                            ++rep.planeSegments;
                        // The ramp's bend, δ in front (CutPlane::lights), from
                        // the triangle's shadow on the plane: a triangle that
                        // the bend's line crosses need not cross the plane.
                        if (!inPlaneBand(p, b, plane, kLeastGap * diagonal, 0.5 * settings.spacing)) continue;
                        shadowOnPlane(p, plane, a, bb);
                        const double bend = nearestLight(a, bb, plane.lights);
                        if (!(bend > kLeastGap * diagonal && bend < 0.5 * settings.spacing)) continue;
                        // (The lights' list is not needed to cross it: not copied per triangle.)
                        const CutPlane ahead{plane.point + bend * plane.normal, plane.normal, plane.region, {}};
                        if (planeCrossing(p, b, ahead, kLeastGap * diagonal, a, bb) && addSegment(a, bb))
                            ++rep.planeSegments;
                    }
                if (pass == 1 && innerGrid) {
                    // This mesh's own lines that lie in this triangle's plane.
                    innerGrid->query(b, lines);
                    for (uint32_t l : lines) {
                        const SceneEdge& line = inner[l];
                        if (line.faces.front().first != mi) continue;
                        const double da = glm::dot(line.a - r.p0, r.n), db = glm::dot(line.b - r.p0, r.n);
                        if (std::abs(da) <= kCoplanar * diagonal && std::abs(db) <= kCoplanar * diagonal)
                            addSegment(line.a, line.b);
                    }
                }
                for (uint32_t e : near) {
                    const SceneEdge& edge = edges[e];
                    if (flat[e]) continue;
                    bool own = false;
                    for (const auto& f : edge.faces) own = own || (f.first == mi && f.second == t);
                    if (own) continue;
                    const double length = glm::length(edge.b - edge.a);
                    const double da = glm::dot(edge.a - r.p0, r.n), db = glm::dot(edge.b - r.p0, r.n);
                    const double limit = settings.closeness * length + touch;
                    if (da < -touch || db < -touch || da > limit || db > limit) continue;
                    // Only an edge hanging over a gap wider than a thousandth of
                    // the scene is cut along: see the header for why touching
                    // ones are not.
                    const double h = 0.5 * (da + db);
                    if (!(h > kLeastGap * diagonal)) continue;
                    if (pass == 1) addSegment(edge.a, edge.b);
                    if (!(2 * h < 0.5 * settings.spacing)) continue;
                    if (pass == 0) {
                        // The hanging surface's faces beside the edge that
                        // are parallel to R (and not skipped), each with the
                        // unit vector from the edge into it, within its
                        // plane; lines kInside·h inside each, drawn 3h past
                        // the edge's ends (as the receiver's below).
                        const Vec3 edgeDir = glm::normalize(edge.b - edge.a);
                        for (const auto& f : edge.faces) {
                            if (f.first < skip.size() && skip[f.first]) continue;
                            Vec3 inward;
                            if (!inwardInto(edge, meshes[f.first], f.second, r.n, touch, inward)) continue;
                            if (!innerDone.insert({e, f}).second) continue;
                            for (const double depth : kInside)
                                inner.push_back({edge.a + depth * h * inward - 3 * h * edgeDir,
                                                 edge.b + depth * h * inward + 3 * h * edgeDir, {f}});
                        }
                        continue;
                    }
                    // Penumbra lines where the mesh is coarser than the penumbra:
                    // parallel to the edge at 2h either side, drawn 3h past its
                    // ends so that two edges' lines cross rather than meet end to
                    // end (an end that misses a line by a rounding makes slivers).
                    const Vec3 a = edge.a - da * r.n, bp = edge.b - db * r.n;
                    const Vec3 along = bp - a;
                    if (!(glm::length(along) > touch)) continue;
                    const Vec3 dir = glm::normalize(along);
                    const Vec3 side = glm::cross(r.n, dir);
                    for (double sign : {1.0, -1.0})
                        addSegment(a + 2 * sign * h * side - 3 * h * dir, bp + 2 * sign * h * side + 3 * h * dir);
                    // Under a hanging face parallel to R, where the profile is
                    // convex (kUnder).
                    for (const auto& f : edge.faces) {
                        Vec3 inward;
                        if (!inwardInto(edge, meshes[f.first], f.second, r.n, touch, inward)) continue;
                        for (const double depth : kUnder)
                            addSegment(a + depth * h * inward + 0.5 * h * dir, bp + depth * h * inward - 0.5 * h * dir);
                    }
                }
            }
        }
    }

    // Re-triangulate every triangle with a cut or a point on its edges.
    for (size_t mi = 0; mi < meshes.size(); ++mi) {
        if (mi < skip.size() && skip[mi]) continue;
        const Mesh& m = meshes[mi];
        CutMesh& cm = cuts[mi];
        if (cm.onEdges.empty() &&
            std::all_of(cm.segments.begin(), cm.segments.end(), [](const auto& s) { return s.empty(); }))
            continue;
        Mesh& o = out[mi];
        o.triangles.clear();
        o.materials.clear();
        o.sourceLines.clear();
        o.albedo.clear();
        const auto keep = [&](size_t t, const glm::uvec3& tri) {
            o.triangles.push_back(tri);
            if (!m.materials.empty()) o.materials.push_back(m.materials[t]);
            if (!m.sourceLines.empty()) o.sourceLines.push_back(m.sourceLines[t]);
            if (!m.albedo.empty()) o.albedo.push_back(m.albedo[t]);
        };
        for (size_t t = 0; t < m.triangles.size(); ++t) {
            const glm::uvec3 tri = m.triangles[t];
            std::vector<std::pair<double, uint32_t>> sides[3];
            bool touched = !cm.segments[t].empty();
            for (int e = 0; e < 3; ++e) {
                const uint32_t va = tri[kEdgeCorners[e][0]], vb = tri[kEdgeCorners[e][1]];
                const auto it = cm.onEdges.find(va < vb ? std::make_pair(va, vb) : std::make_pair(vb, va));
                if (it == cm.onEdges.end()) continue;
                for (const auto& [s, v] : it->second) sides[e].emplace_back(va < vb ? s : 1.0 - s, v);
                std::sort(sides[e].begin(), sides[e].end());
                touched = touched || !sides[e].empty();
            }
            if (!touched) {
                keep(t, tri);
                continue;
            }
            // The triangulation runs in the triangle's own plane, in lengths
            // (corner 0 at the origin, edge 0-1 along x), so that Delaunay's
            // criterion shapes faces as they are: in barycentric coordinates
            // a long wall triangle would be cut into slivers across it.
            const Triangle3 p = m.triangle(t);
            const Vec3 e1 = p[1] - p[0], e2 = p[2] - p[0];
            const double l1 = glm::length(e1);
            const Vec3 ux = e1 / l1, uy = glm::cross(unitNormal(m, t), ux);
            const double ax = glm::dot(e2, ux), ay = glm::dot(e2, uy);  // corner 2
            const auto toPlane = [&](double bx, double by) { return Cdt::Point(bx * l1 + by * ax, by * ay); };
            const auto toBarycentric = [&](const Cdt::Point& q) {
                const double by = q.y() / ay;
                return std::make_pair((q.x() - by * ax) / l1, by);
            };
            Cdt cdt;
            // Each vertex placed: its index in the mesh and the triangle's
            // edges it lies on (bit e). The others (cut ends inside,
            // crossings of two cuts) get new indices below.
            std::map<const void*, std::pair<uint32_t, int>> known;
            Cdt::Vertex_handle corner[3];
            const int cornerEdges[3] = {0b101, 0b011, 0b110};
            for (int k = 0; k < 3; ++k) {
                corner[k] = cdt.insert(k == 0 ? Cdt::Point(0, 0) : k == 1 ? Cdt::Point(l1, 0) : Cdt::Point(ax, ay));
                known.emplace(&*corner[k], std::make_pair(tri[k], cornerEdges[k]));
            }
            std::map<uint32_t, Cdt::Vertex_handle> placed;
            for (int e = 0; e < 3; ++e) {
                Cdt::Vertex_handle prev = corner[kEdgeCorners[e][0]];
                for (const auto& [s, v] : sides[e]) {
                    const auto [x, y] = onEdge(e, s);
                    const Cdt::Vertex_handle h = cdt.insert(toPlane(x, y));
                    known.emplace(&*h, std::make_pair(v, 1 << e));
                    placed[v] = h;
                    if (h != prev) cdt.insert_constraint(prev, h);
                    prev = h;
                }
                if (prev != corner[kEdgeCorners[e][1]]) cdt.insert_constraint(prev, corner[kEdgeCorners[e][1]]);
            }
            // Ends inside that coincide but for rounding (one corner of an
            // object reached along two of its edges, each end computed from
            // its own edge) become one vertex.
            std::vector<Cdt::Vertex_handle> inside;
            const auto handleOf = [&](const CutPoint& c) -> Cdt::Vertex_handle {
                if (c.kind == CutPoint::Corner) return corner[c.index];
                if (c.kind == CutPoint::OnEdge) {
                    // The registered point nearest the end's parameter.
                    const auto& list = sides[c.index];
                    size_t best = 0;
                    for (size_t i = 1; i < list.size(); ++i)
                        if (std::abs(list[i].first - c.t) < std::abs(list[best].first - c.t)) best = i;
                    return placed.at(list[best].second);
                }
                const Cdt::Point q = toPlane(c.x, c.y);
                for (const Cdt::Vertex_handle& v : inside)
                    if (std::hypot(v->point().x() - q.x(), v->point().y() - q.y()) <= touch) return v;
                inside.push_back(cdt.insert(q));
                return inside.back();
            };
            for (const auto& [a, b] : cm.segments[t]) {
                const Cdt::Vertex_handle ha = handleOf(a), hb = handleOf(b);
                if (ha != hb) cdt.insert_constraint(ha, hb);
            }
            std::map<const void*, int> onEdges;
            for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v) {
                const auto it = known.find(&*v);
                if (it != known.end()) {
                    v->info() = it->second.first;
                    onEdges[&*v] = it->second.second;
                    continue;
                }
                const auto [x, y] = toBarycentric(v->point());
                const double w = 1.0 - x - y;
                v->info() = uint32_t(m.positions.size() + cm.positions.size());
                cm.positions.push_back(w * p[0] + x * p[1] + y * p[2]);
                const Vec3 n = w * m.normals[tri.x] + x * m.normals[tri.y] + y * m.normals[tri.z];
                cm.normals.push_back(glm::length(n) > 1e-12 ? glm::normalize(n) : unitNormal(m, t));
                if (!m.texcoords.empty())
                    cm.texcoords.push_back(Vec2(w * m.texcoords[tri.x] + x * m.texcoords[tri.y] +
                                                y * m.texcoords[tri.z]));
            }
            for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
                if (CGAL::orientation(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point()) !=
                    CGAL::LEFT_TURN)
                    continue;
                // A face whose corners all lie on one edge of the triangle is
                // the sliver between that edge's points (not exactly on its
                // line once in lengths) and the hull: not part of the surface.
                int common = 0b111;
                for (int k = 0; k < 3; ++k) {
                    const auto it = onEdges.find(&*f->vertex(k));
                    common &= it == onEdges.end() ? 0 : it->second;
                }
                if (common) continue;
                // So is a face thinner than the float precision positions
                // reach the GPU with (a crossing rounded next to a vertex):
                // rasterised, its attributes' gradients overflow.
                const Cdt::Point& q0 = f->vertex(0)->point();
                const Cdt::Point& q1 = f->vertex(1)->point();
                const Cdt::Point& q2 = f->vertex(2)->point();
                const double area2 = std::abs((q1.x() - q0.x()) * (q2.y() - q0.y()) - (q2.x() - q0.x()) * (q1.y() - q0.y()));
                const double longest = std::sqrt(std::max({CGAL::squared_distance(q0, q1), CGAL::squared_distance(q1, q2),
                                                           CGAL::squared_distance(q2, q0)}));
                if (area2 < kThinnest * diagonal * longest) {
                    ++rep.dropped;
                    continue;
                }
                keep(t, glm::uvec3(f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()));
                ++rep.triangles;
            }
            ++rep.receivers;
        }
        // Added vertices no triangle took (a point on an edge that fell on
        // a corner) are dropped; the mesh's own keep their indices.
        const size_t base = m.positions.size();
        std::vector<uint32_t> remap(cm.positions.size(), UINT32_MAX);
        for (glm::uvec3& tri : o.triangles)
            for (int k = 0; k < 3; ++k)
                if (tri[k] >= base) {
                    uint32_t& r = remap[tri[k] - base];
                    if (r == UINT32_MAX) r = 0;
                }
        uint32_t next = uint32_t(base);
        for (size_t v = 0; v < remap.size(); ++v) {
            if (remap[v] == UINT32_MAX) continue;
            remap[v] = next++;
            o.positions.push_back(cm.positions[v]);
            o.normals.push_back(cm.normals[v]);
            if (!cm.texcoords.empty()) o.texcoords.push_back(cm.texcoords[v]);
        }
        for (glm::uvec3& tri : o.triangles)
            for (int k = 0; k < 3; ++k)
                if (tri[k] >= base) tri[k] = remap[tri[k] - base];
        rep.vertices += next - base;
    }
    if (report) *report = rep;
    return out;
}

}  // namespace ml
