// The only translation unit that includes CGAL (see core/CMakeLists.txt).
#include "ExactIrradiance.h"

#include "core/DisjointSets.h"

#include "Lambert.h"
#include "core/Error.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_2.h>
#include <CGAL/Polygon_set_2.h>
#include <CGAL/Polygon_with_holes_2.h>
#include <CGAL/convex_hull_2.h>

#include <algorithm>
#include <initializer_list>
#include <iterator>
#include <map>
#include <stdexcept>

namespace ml {

namespace {

// Exact constructions: the union of many projected occluders creates new
// vertices whose rounding would otherwise break the arrangement.
using ExactKernel = CGAL::Exact_predicates_exact_constructions_kernel;
using ExactPolygon = CGAL::Polygon_2<ExactKernel>;
using ExactPolygonSet = CGAL::Polygon_set_2<ExactKernel>;
using ExactPolygonWithHoles = CGAL::Polygon_with_holes_2<ExactKernel>;
// Exact predicates suffice for a convex hull: it only selects input points.
using HullPoint = CGAL::Exact_predicates_inexact_constructions_kernel::Point_2;

// Lengths below are in units of the light's size (the diagonal of its
// bounding box): the computation runs relative to x in those units, so the
// answer does not depend on the scene's scale or position.

// x closer than this to a plane lies in it: a light triangle is then seen
// edge-on (contributes 0) and an occluder through x blocks nothing.
constexpr double kInPlane = 1e-12;
// Occluder parts closer to the light's plane than this fraction of the
// receiver's distance to it, plus an absolute margin for rounding, count as
// lying in it and do not block (a light's own backing surface, for one).
constexpr double kLightPlaneRelativeMargin = 1e-9;
constexpr double kLightPlaneAbsoluteMargin = 1e-13;
// A projected occluder smaller than this fraction of min(visible light area,
// height²) is dropped: its solid angle is below 1e-14 of the light's or 1e-14 sr.
constexpr double kNegligibleArea = 1e-14;
// Relative widening of the pyramid occluders are clipped to (see
// visibleFromTriangle).
constexpr double kPyramidMargin = 1e-9;
// Merging the pieces of a tessellated occluder may fill notches this deep
// (times min(1, height)) left by rounding along clipped edges: a solid angle
// of at most this times the merged outline's perimeter over the height.
constexpr double kRoundingNotch = 1e-14;

struct TriangleRange {
    const Triangle3* begin;
    const Triangle3* end;
};

// The plane of one light triangle, relative to the receiver at the origin,
// with a 2D frame whose counter-clockwise polygons have a signed Lambert sum
// that is positive (their normal u × v points away from the receiver).
struct LightPlane {
    Vec3 normal;    // unit, emitting side: towards the receiver
    double height;  // distance from the receiver to the plane, > 0
    Vec3 u, v;      // orthonormal in-plane axes, u × v = −normal

    LightPlane(const Vec3& unitNormal, double h) : normal(unitNormal), height(h) {
        Vec3 unused;
        orthonormalBasis(-normal, u, unused);
        v = glm::cross(-normal, u);
    }
    // Central projection from the receiver; p must lie in front of it
    // (normal·p < 0), which the pyramid clipping guarantees.
    Vec2 project(const Vec3& p) const {
        const double scale = height / -glm::dot(normal, p);
        return scale * Vec2(glm::dot(p, u), glm::dot(p, v));
    }
    // Lifting back to 3D: foot() + inPlane(p), kept apart so that Lambert's
    // formula gets exact edge vectors (signedCosineSolidAngle).
    Vec3 foot() const { return -height * normal; }
    Vec3 inPlane(const Vec2& p) const { return p.x * u + p.y * v; }
};

// Convex hull, counter-clockwise, without repeated or collinear points: a
// valid simple polygon for CGAL even when rounding has made the projection
// of a convex piece slightly non-convex.
std::vector<Vec2> convexHull(const std::vector<Vec2>& points) {
    std::vector<HullPoint> in, out;
    in.reserve(points.size());
    for (const Vec2& p : points) in.emplace_back(p.x, p.y);
    CGAL::convex_hull_2(in.begin(), in.end(), std::back_inserter(out));
    std::vector<Vec2> hull;
    hull.reserve(out.size());
    for (const HullPoint& p : out) hull.emplace_back(p.x(), p.y());
    return hull;
}

double area(const std::vector<Vec2>& polygon) {
    double twice = 0;
    for (size_t i = 0; i < polygon.size(); ++i) {
        const Vec2& a = polygon[i];
        const Vec2& b = polygon[(i + 1) % polygon.size()];
        twice += a.x * b.y - a.y * b.x;
    }
    return 0.5 * twice;
}

bool lexicographicallyLess(const Vec2& a, const Vec2& b) {
    return a.x < b.x || (a.x == b.x && a.y < b.y);
}

// At q, does the boundary p → q → r of a counter-clockwise polygon turn left
// or go straight on, q lying at most `tolerance` inside the segment p–r,
// rather than turn right or double back? Points clipped along one plane are
// collinear only up to rounding, hence the tolerance.
bool convexTurn(const Vec2& p, const Vec2& q, const Vec2& r, double tolerance) {
    const HullPoint hp(p.x, p.y), hq(q.x, q.y), hr(r.x, r.y);
    if (CGAL::orientation(hp, hq, hr) == CGAL::LEFT_TURN) return true;
    const Vec2 in = q - p, out = r - q;
    return glm::dot(in, out) > 0 && std::abs(in.x * out.y - in.y * out.x) <= tolerance * glm::length(r - p);
}

// The vertices of `edges` as one closed loop that turns left (or goes
// straight, see convexTurn) at every vertex and winds once: a convex polygon
// up to notches `tolerance` deep. Empty when the edges form anything else.
std::vector<Vec2> convexLoop(const std::vector<std::pair<Vec2, Vec2>>& edges, double tolerance) {
    std::map<Vec2, size_t, decltype(&lexicographicallyLess)> startingAt(&lexicographicallyLess);
    for (size_t e = 0; e < edges.size(); ++e)
        if (!startingAt.emplace(edges[e].first, e).second) return {};
    std::vector<Vec2> loop;
    double turning = 0;
    size_t e = 0;
    do {
        const auto next = startingAt.find(edges[e].second);
        if (next == startingAt.end()) return {};
        const Vec2 &p = edges[e].first, &q = edges[e].second, &r = edges[next->second].second;
        if (!convexTurn(p, q, r, tolerance)) return {};
        const Vec2 in = q - p, out = r - q;
        turning += std::atan2(in.x * out.y - in.y * out.x, glm::dot(in, out));
        loop.push_back(p);
        e = next->second;
    } while (e != 0 && loop.size() <= edges.size());
    // Left turns only, so the total turning is 2π times the number of windings.
    if (loop.size() != edges.size() || std::abs(turning - 2 * kPi) > 1.0) return {};
    return loop;
}

// A finely tessellated flat occluder (a refined wall) would cost the Boolean
// union one triangle at a time; its pieces are merged first. Pieces of
// neighbouring triangles share edges exactly (clipToHalfSpace and the
// projection are deterministic), so edges present in both directions cancel
// and join their polygons into groups. A group whose remaining edges form
// one convex loop has, as the sum of its polygons' indicators, exactly that
// loop's indicator: their union is that loop, whose convex hull replaces
// them. This holds whatever overlaps the group has; other groups are kept.
//   polygons   counter-clockwise convex polygons without repeated vertices
//   tolerance  depth of the rounding notches the hull may fill (light sizes)
std::vector<std::vector<Vec2>> mergeTiles(const std::vector<std::vector<Vec2>>& polygons,
                                          double tolerance) {
    struct Edge {
        Vec2 lo, hi;  // end points, lexicographically ordered
        bool forward; // runs from lo to hi
        uint32_t polygon;
    };
    std::vector<Edge> edges;
    for (uint32_t i = 0; i < polygons.size(); ++i)
        for (size_t k = 0; k < polygons[i].size(); ++k) {
            const Vec2& a = polygons[i][k];
            const Vec2& b = polygons[i][(k + 1) % polygons[i].size()];
            const bool forward = lexicographicallyLess(a, b);
            edges.push_back({forward ? a : b, forward ? b : a, forward, i});
        }
    std::sort(edges.begin(), edges.end(), [](const Edge& a, const Edge& b) {
        if (a.lo != b.lo) return lexicographicallyLess(a.lo, b.lo);
        if (a.hi != b.hi) return lexicographicallyLess(a.hi, b.hi);
        return a.forward < b.forward;
    });

    // Within each run of equal segments, backward copies come first: pair
    // them with forward ones, the unpaired rest remains as boundary.
    DisjointSets groups(polygons.size());
    std::vector<const Edge*> remaining;
    for (size_t begin = 0, end; begin < edges.size(); begin = end) {
        end = begin;
        while (end < edges.size() && edges[end].lo == edges[begin].lo && edges[end].hi == edges[begin].hi)
            ++end;
        size_t firstForward = begin;
        while (firstForward < end && !edges[firstForward].forward) ++firstForward;
        const size_t backwardCount = firstForward - begin, forwardCount = end - firstForward;
        const size_t pairs = std::min(backwardCount, forwardCount);
        for (size_t k = 0; k < pairs; ++k)
            groups.unite(edges[begin + k].polygon, edges[firstForward + k].polygon);
        for (size_t k = begin + pairs; k < firstForward; ++k) remaining.push_back(&edges[k]);
        for (size_t k = firstForward + pairs; k < end; ++k) remaining.push_back(&edges[k]);
    }

    std::map<uint32_t, std::vector<std::pair<Vec2, Vec2>>> boundaries;  // group -> directed edges
    for (const Edge* e : remaining)
        boundaries[groups.find(e->polygon)].push_back(e->forward ? std::make_pair(e->lo, e->hi)
                                                                 : std::make_pair(e->hi, e->lo));
    std::vector<std::vector<Vec2>> merged;
    std::vector<bool> replaced(polygons.size(), false);
    for (const auto& [group, boundary] : boundaries) {
        std::vector<Vec2> loop = convexLoop(boundary, tolerance);
        if (loop.empty()) continue;
        merged.push_back(convexHull(loop));  // also drops the vertices where it goes straight on
        replaced[group] = true;
    }
    for (uint32_t i = 0; i < polygons.size(); ++i)
        if (!replaced[groups.find(i)]) merged.push_back(polygons[i]);
    return merged;
}

ExactPolygon toExact(const std::vector<Vec2>& polygon) {
    ExactPolygon exact;
    for (const Vec2& p : polygon) exact.push_back(ExactKernel::Point_2(p.x, p.y));
    return exact;
}

double signedLambert(const Vec3& n, const LightPlane& plane, const std::vector<Vec2>& boundary) {
    std::vector<Vec3> local;
    local.reserve(boundary.size());
    for (const Vec2& p : boundary) local.push_back(plane.inPlane(p));
    return signedCosineSolidAngle(n, plane.foot(), local);
}

double signedLambert(const Vec3& n, const LightPlane& plane, const ExactPolygon& boundary) {
    std::vector<Vec2> approximate;
    approximate.reserve(boundary.size());
    for (auto it = boundary.vertices_begin(); it != boundary.vertices_end(); ++it)
        approximate.emplace_back(CGAL::to_double(it->x()), CGAL::to_double(it->y()));
    return signedLambert(n, plane, approximate);
}

// The diagonal of the light's bounding box: the unit of length inside.
double lightSize(const std::vector<Triangle3>& light) {
    Bounds3 bounds;
    for (const Triangle3& t : light)
        for (const Vec3& p : t) bounds.extend(p);
    return bounds.diagonal();
}

void requirePlanar(const std::vector<Triangle3>& light) {
    const double size = lightSize(light);
    Vec3 weightedNormal(0.0), weightedCentroid(0.0);
    double totalArea = 0;
    for (const Triangle3& t : light) {
        const Vec3 areaNormal = glm::cross(t[1] - t[0], t[2] - t[0]);
        const double a = 0.5 * glm::length(areaNormal);
        weightedNormal += 0.5 * areaNormal;
        weightedCentroid += a * (t[0] + t[1] + t[2]) / 3.0;
        totalArea += a;
    }
    if (!(totalArea > 0)) return;  // no area: nothing to see, nothing to check
    const Vec3 normal = glm::normalize(weightedNormal);
    const Vec3 centroid = weightedCentroid / totalArea;
    for (size_t k = 0; k < light.size(); ++k)
        for (const Vec3& p : light[k]) {
            const double distance = std::abs(glm::dot(p - centroid, normal));
            if (distance > kLightPlanarTolerance * size)
                throw std::invalid_argument(concat("exactVisibleCosineSolidAngle: light triangle ", k,
                                                   " has a vertex ", distance,
                                                   " away from the light's plane (light size ", size,
                                                   "): the light is not planar"));
        }
}

// Lengths in light sizes; occluder vertices are mapped by `toLocal`.
template <typename ToLocal>
double visibleFromTriangle(const Triangle3& triangle, const Vec3& n,
                           std::initializer_list<TriangleRange> occluders, const ToLocal& toLocal) {
    const Vec3 areaNormal = glm::cross(triangle[1] - triangle[0], triangle[2] - triangle[0]);
    const double twiceArea = glm::length(areaNormal);
    if (!(twiceArea > 0)) return 0;
    const Vec3 normal = areaNormal / twiceArea;
    const double height = -glm::dot(normal, (triangle[0] + triangle[1] + triangle[2]) / 3.0);
    if (height <= kInPlane) return 0;  // behind the light or in its plane
    const LightPlane plane(normal, height);

    const std::vector<Vec3> aboveHorizon =
        clipToHalfSpace({triangle[0], triangle[1], triangle[2]}, n, 0.0);
    std::vector<Vec2> lit;
    for (const Vec3& p : aboveHorizon) lit.push_back(plane.project(p));
    lit = convexHull(lit);
    if (lit.size() < 3) return 0;

    // The pyramid from the receiver through the visible triangle, widened by
    // kPyramidMargin so that an occluder covering an edge of the light still
    // covers it after rounding (the Boolean difference discards the excess
    // exactly): inward normals of its sides, as counter-clockwise corners
    // give inward cross products.
    Vec2 centroid(0.0);
    for (const Vec2& p : lit) centroid += p / double(lit.size());
    std::vector<Vec3> corners;
    for (const Vec2& p : lit)
        corners.push_back(plane.foot() + plane.inPlane(centroid + (1 + kPyramidMargin) * (p - centroid)));
    std::vector<Vec3> sides;
    for (size_t i = 0; i < corners.size(); ++i)
        sides.push_back(glm::cross(corners[i], corners[(i + 1) % corners.size()]));
    const double nearLight = -height + kLightPlaneRelativeMargin * height + kLightPlaneAbsoluteMargin;
    const double negligibleArea = kNegligibleArea * std::min(area(lit), height * height);

    std::vector<std::vector<Vec2>> shadows;
    for (const TriangleRange& range : occluders)
        for (const Triangle3* it = range.begin; it != range.end; ++it) {
            const Triangle3 q = {toLocal((*it)[0]), toLocal((*it)[1]), toLocal((*it)[2])};
            const auto allBelow = [&](const Vec3& m, double c) {
                return glm::dot(m, q[0]) < c && glm::dot(m, q[1]) < c && glm::dot(m, q[2]) < c;
            };
            bool outside = allBelow(normal, nearLight) || allBelow(-normal, 0.0);
            for (size_t i = 0; i < sides.size() && !outside; ++i) outside = allBelow(sides[i], 0.0);
            if (outside) continue;

            // An occluder whose plane contains the receiver is seen edge-on;
            // its projection would also divide 0 by 0 at the receiver.
            const Vec3 occluderNormal = glm::cross(q[1] - q[0], q[2] - q[0]);
            const double occluderNormalLength = glm::length(occluderNormal);
            const double reach = std::max({glm::length(q[0]), glm::length(q[1]), glm::length(q[2])});
            if (!(occluderNormalLength > 0) ||
                std::abs(glm::dot(occluderNormal, q[0])) <= kInPlane * reach * occluderNormalLength)
                continue;

            std::vector<Vec3> piece = {q[0], q[1], q[2]};
            for (size_t i = 0; i < sides.size() && piece.size() >= 3; ++i)
                piece = clipToHalfSpace(piece, sides[i], 0.0);
            if (piece.size() >= 3) piece = clipToHalfSpace(piece, normal, nearLight);
            if (piece.size() < 3) continue;

            std::vector<Vec2> shadow;
            for (const Vec3& p : piece) {
                if (!(glm::dot(normal, p) < 0)) break;  // rounding put it at the receiver
                shadow.push_back(plane.project(p));
            }
            if (shadow.size() != piece.size()) continue;
            shadow = convexHull(shadow);
            if (shadow.size() >= 3) shadows.push_back(std::move(shadow));
        }

    // Slivers are dropped only now: dropping them before merging would leave
    // gaps that stop their neighbours from merging.
    std::vector<ExactPolygon> exactShadows;
    for (const std::vector<Vec2>& shadow : mergeTiles(shadows, kRoundingNotch * std::min(1.0, height)))
        if (area(shadow) > negligibleArea) exactShadows.push_back(toExact(shadow));
    if (exactShadows.empty()) return signedLambert(n, plane, lit);

    ExactPolygonSet occluded;
    occluded.join(exactShadows.begin(), exactShadows.end());
    ExactPolygonSet visible(toExact(lit));
    visible.difference(occluded);
    std::vector<ExactPolygonWithHoles> pieces;
    visible.polygons_with_holes(std::back_inserter(pieces));
    // Outer boundaries are counter-clockwise and holes clockwise, so the
    // signed sums add up to the visible part.
    double sum = 0;
    for (const ExactPolygonWithHoles& piece : pieces) {
        sum += signedLambert(n, plane, piece.outer_boundary());
        for (auto hole = piece.holes_begin(); hole != piece.holes_end(); ++hole)
            sum += signedLambert(n, plane, *hole);
    }
    return sum;
}

// exactVisibleCosineSolidAngle for a light known to be planar.
double visibleCosineSolidAngle(const Vec3& x, const Vec3& n, const std::vector<Triangle3>& light,
                               std::initializer_list<TriangleRange> occluders) {
    const double size = lightSize(light);
    if (!(size > 0)) return 0;
    const double invSize = 1.0 / size;
    const auto toLocal = [&](const Vec3& p) { return (p - x) * invSize; };
    const Vec3 unitN = glm::normalize(n);
    double sum = 0;
    for (const Triangle3& t : light)
        sum += visibleFromTriangle({toLocal(t[0]), toLocal(t[1]), toLocal(t[2])}, unitN, occluders, toLocal);
    // Rounding may leave -1e-17 where everything is hidden.
    return std::max(0.0, sum);
}

}  // namespace

double exactVisibleCosineSolidAngle(const Vec3& x, const Vec3& n, const std::vector<Triangle3>& light,
                                    const std::vector<Triangle3>& occluders) {
    requirePlanar(light);
    const Triangle3* first = occluders.data();
    return visibleCosineSolidAngle(x, n, light, {{first, first + occluders.size()}});
}

// ExactDirect

ExactDirect::ExactDirect(const Scene& scene) : lights_(scene.lights) {
    std::vector<std::vector<bool>> isLight(scene.meshes.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m) isLight[m].resize(scene.meshes[m].triangles.size());
    for (const Light& light : lights_)
        for (uint32_t t : light.triangles) isLight[light.mesh][t] = true;

    triangles_.reserve(scene.triangleCount());
    for (size_t m = 0; m < scene.meshes.size(); ++m)
        for (size_t t = 0; t < scene.meshes[m].triangles.size(); ++t)
            if (!isLight[m][t]) triangles_.push_back(scene.meshes[m].triangle(t));
    for (const Light& light : lights_) {
        lightBegin_.push_back(triangles_.size());
        triangles_.insert(triangles_.end(), light.geometry.begin(), light.geometry.end());
        lightEnd_.push_back(triangles_.size());
    }
}

const Light& ExactDirect::planarLight(size_t lightIndex) const {
    if (lightIndex >= lights_.size())
        throw std::out_of_range(concat("ExactDirect: light ", lightIndex, " requested, the scene has ",
                                       lights_.size()));
    const Light& light = lights_[lightIndex];
    if (!light.planar)
        throw InputError(
            concat("light '", light.name, "' is not planar: the exact method needs planar lights"));
    return light;
}

Rgb ExactDirect::irradiance(size_t lightIndex, const Vec3& x, const Vec3& n) const {
    return planarLight(lightIndex).radiance * cosineSolidAngle(lightIndex, x, n);
}

double ExactDirect::cosineSolidAngle(size_t lightIndex, const Vec3& x, const Vec3& n) const {
    const Light& light = planarLight(lightIndex);
    const Triangle3* all = triangles_.data();
    return visibleCosineSolidAngle(x, n, light.geometry,
                                   {{all, all + lightBegin_[lightIndex]},
                                    {all + lightEnd_[lightIndex], all + triangles_.size()}});
}

double ExactDirect::unoccludedCosineSolidAngle(size_t lightIndex, const Vec3& x, const Vec3& n) const {
    return visibleCosineSolidAngle(x, n, planarLight(lightIndex).geometry, {});
}

}  // namespace ml
