#include "OccluderPolygons.h"

#include "core/Error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

namespace ml {

namespace {

// An edge by its two end points, in a fixed order, to find a triangle's
// neighbours (triangles of one mesh share corners bit for bit).
using EdgeKey = std::pair<std::array<double, 3>, std::array<double, 3>>;

std::array<double, 3> key(const Vec3& p) { return {p.x, p.y, p.z}; }

EdgeKey edgeKey(const Vec3& a, const Vec3& b) {
    const auto ka = key(a), kb = key(b);
    return ka < kb ? EdgeKey{ka, kb} : EdgeKey{kb, ka};
}

// Whether a → b → c turns left about `n` by a clear margin.
bool turnsLeft(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n) {
    const Vec3 u = b - a, v = c - b;
    return glm::dot(glm::cross(u, v), n) > 1e-9 * glm::length(u) * glm::length(v);
}

}  // namespace

OccluderPolygons::OccluderPolygons(const std::vector<Triangle3>& triangles, const std::vector<uint32_t>& lightId)
    : triangles_(triangles), lightId_(lightId), quadCorner_(triangles.size(), Vec3(0.0)),
      quadAfter_(triangles.size(), int8_t(-1)) {
    ML_ASSERT(lightId.size() == triangles.size(), "a light id per triangle");
    // Every triangle's edges, sorted so that the uses of one edge are
    // neighbours (in triangle order); run[3i + k]: the uses of triangle i's
    // edge k. A sorted array rather than a map: one allocation, for scenes of
    // millions of triangles.
    struct EdgeUse {
        EdgeKey key;
        uint32_t tri;
        int edge;
    };
    std::vector<EdgeUse> uses;
    uses.reserve(3 * triangles.size());
    for (uint32_t i = 0; i < triangles.size(); ++i)
        for (int k = 0; k < 3; ++k)
            uses.push_back({edgeKey(triangles[i][size_t(k)], triangles[i][size_t((k + 1) % 3)]), i, k});
    std::sort(uses.begin(), uses.end(), [](const EdgeUse& a, const EdgeUse& b) {
        return std::tie(a.key, a.tri, a.edge) < std::tie(b.key, b.tri, b.edge);
    });
    std::vector<std::pair<uint32_t, uint32_t>> run(uses.size());  // [begin, end) in `uses`
    for (size_t begin = 0, end; begin < uses.size(); begin = end) {
        for (end = begin + 1; end < uses.size() && uses[end].key == uses[begin].key;) ++end;
        for (size_t u = begin; u < end; ++u) run[3 * size_t(uses[u].tri) + size_t(uses[u].edge)] = {uint32_t(begin), uint32_t(end)};
    }
    for (uint32_t i = 0; i < triangles.size(); ++i) {
        const Triangle3& t = triangles[i];
        const Vec3 area = glm::cross(t[1] - t[0], t[2] - t[0]);
        const double len = glm::length(area);
        if (!(len > 0)) continue;
        const Vec3 n = area / len;
        const double size = std::sqrt(len);
        for (int k = 0; k < 3 && quadAfter_[i] < 0; ++k) {
            // The edge from corner k to k + 1; the neighbour's far corner d
            // goes between them: t[k], d, t[k+1], t[k+2].
            const Vec3 &a = t[size_t(k)], &b = t[size_t((k + 1) % 3)], &c = t[size_t((k + 2) % 3)];
            const auto [begin, end] = run[3 * size_t(i) + size_t(k)];
            for (uint32_t u = begin; u < end; ++u) {
                const uint32_t j = uses[u].tri;
                if (j == i || lightId[j] != lightId[i]) continue;
                const Vec3 d = triangles[j][size_t((uses[u].edge + 2) % 3)];  // the corner opposite the edge
                if (std::abs(glm::dot(d - a, n)) > 1e-9 * size) continue;  // not in the plane
                if (!(turnsLeft(c, a, d, n) && turnsLeft(a, d, b, n) && turnsLeft(d, b, c, n) && turnsLeft(b, c, a, n)))
                    continue;  // the union is not convex
                quadCorner_[i] = d;
                quadAfter_[i] = int8_t(k);
                break;
            }
        }
    }
}

size_t OccluderPolygons::quadCount() const {
    return size_t(std::count_if(quadAfter_.begin(), quadAfter_.end(), [](int8_t k) { return k >= 0; }));
}

bool OccluderPolygons::hideAll(const std::vector<Polygon3>& pieces, const std::vector<OccluderBvh::Range>& ranges,
                               const Rules& rules) const {
    if (pieces.empty()) return false;
    for (const OccluderBvh::Range& r : ranges)
        for (uint32_t i = r.first; i < r.first + r.count; ++i) {
            if ((lightId_[i] == rules.skipLightId && rules.skipLightId != 0) || lightId_[i] == kHoled) continue;
            const Triangle3& t = triangles_[i];
            Vec3 corners[4];
            int count = 0;
            for (int k = 0; k < 3; ++k) {
                corners[count++] = t[size_t(k)];
                if (quadAfter_[i] == k) corners[count++] = quadCorner_[i];
            }
            if (hides(corners, count, pieces, rules)) return true;
        }
    return false;
}

bool OccluderPolygons::hides(const Vec3* corners, int count, const std::vector<Polygon3>& pieces,
                             const Rules& rules) const {
    const Vec3 area = glm::cross(corners[1] - corners[0], corners[count - 1] - corners[0]);
    const double len = glm::length(area);
    if (!(len > 0)) return false;
    const Vec3 n = area / len;
    const double d = -glm::dot(n, corners[0]);
    // The eye well away from the polygon's plane: the sampler ignores what
    // is nearer than nearDistance (and the plane is the nearest any of the
    // polygon can be).
    const double eyeSide = glm::dot(n, rules.eye) + d;
    if (!(std::abs(eyeSide) > 16 * rules.nearDistance)) return false;
    const double lightEye = glm::dot(rules.lightNormal, rules.eye - rules.lightPoint);
    // Corners counter-clockwise about n (corners 0, 1, last make the normal).
    double edgeLength[4];
    for (int k = 0; k < count; ++k) edgeLength[k] = glm::length(corners[(k + 1) % count] - corners[k]);
    for (const Polygon3& piece : pieces)
        for (const Vec3& q : piece) {
            const double qSide = glm::dot(n, q) + d;
            // q strictly beyond the plane, seen from the eye.
            if (!(qSide * eyeSide < 0) || !(std::abs(qSide) > 1e-9 * glm::length(q - rules.eye))) return false;
            const double s = eyeSide / (eyeSide - qSide);  // in (0, 1)
            const Vec3 x = rules.eye + s * (q - rules.eye);
            // In front of the light's plane by more than the sampler's
            // tolerance (affine along the polygon: its corners decide).
            const double h = (1 - s) * lightEye + s * glm::dot(rules.lightNormal, q - rules.lightPoint);
            if (!(h > 2 * rules.planeTolerance + 1e-9 * std::abs(lightEye))) return false;
            // Inside every edge by a margin of a millionth of the edge.
            for (int k = 0; k < count; ++k) {
                const Vec3& a = corners[k];
                const Vec3& b = corners[(k + 1) % count];
                if (!(glm::dot(glm::cross(b - a, x - a), n) > 1e-6 * edgeLength[k] * edgeLength[k])) return false;
            }
        }
    return true;
}

}  // namespace ml
