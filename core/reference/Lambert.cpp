#include "Lambert.h"

namespace ml {

namespace {

// x counts as lying in a polygon's plane when it is closer to that plane than
// this fraction of the polygon's size: the polygon is then seen edge-on.
constexpr double kEdgeOnTolerance = 1e-12;

bool lexicographicallyLess(const Vec3& a, const Vec3& b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    return a.z < b.z;
}

// Newell's unit normal, which copes with non-convex polygons and repeated
// vertices; zero when the polygon has no area.
Vec3 unitNormal(const std::vector<Vec3>& polygon) {
    Vec3 normal(0.0);
    for (size_t i = 1; i + 1 < polygon.size(); ++i)
        normal += glm::cross(polygon[i] - polygon[0], polygon[i + 1] - polygon[0]);
    const double length = glm::length(normal);
    return length > 0 ? normal / length : Vec3(0.0);
}

// True when x lies in the polygon's plane or the polygon has no area: it is
// then seen edge-on and subtends no solid angle.
bool seenEdgeOn(const Vec3& x, const std::vector<Vec3>& polygon, const Vec3& normal) {
    if (polygon.size() < 3 || normal == Vec3(0.0)) return true;
    double size = 0;
    for (const Vec3& p : polygon) size = std::max(size, glm::length(p - polygon[0]));
    return std::abs(glm::dot(normal, polygon[0] - x)) <= kEdgeOnTolerance * size;
}

// The polygon as offsets from its first vertex, whose differences (the
// edges) keep their digits however far the polygon is from the receiver.
std::vector<Vec3> offsetsFromFirst(const std::vector<Vec3>& polygon) {
    std::vector<Vec3> local;
    local.reserve(polygon.size());
    for (const Vec3& p : polygon) local.push_back(p - polygon[0]);
    return local;
}

}  // namespace

double signedCosineSolidAngle(const Vec3& n, const Vec3& base, const std::vector<Vec3>& local) {
    double sum = 0;
    const size_t count = local.size();
    for (size_t i = 0; i < count; ++i) {
        const Vec3 a = base + local[i];
        const Vec3 edge = local[(i + 1) % count] - local[i];
        // a × b = a × edge and a·b = a·a + a·edge keep their relative
        // precision when a and b are long and nearly parallel.
        const Vec3 axb = glm::cross(a, edge);
        const double axbLength = glm::length(axb);
        // A zero cross product is a zero-length edge (no contribution) or an
        // edge through the receiver, which only happens for polygons seen
        // edge-on, excluded by the callers.
        if (!(axbLength > 0)) continue;
        // atan2 stays accurate for the tiny and near-π angles where acos of
        // the normalised dot product loses half of the digits; it is also
        // independent of the scene's scale.
        const double angle = std::atan2(axbLength, glm::dot(a, a) + glm::dot(a, edge));
        sum += angle * glm::dot(n, axb) / axbLength;
    }
    return 0.5 * sum;
}

std::vector<Vec3> clipToHalfSpace(const std::vector<Vec3>& polygon, const Vec3& m, double c) {
    std::vector<Vec3> clipped;
    const size_t count = polygon.size();
    clipped.reserve(count + 1);
    for (size_t i = 0; i < count; ++i) {
        const Vec3& a = polygon[i];
        const Vec3& b = polygon[(i + 1) % count];
        const double da = glm::dot(m, a) - c;
        const double db = glm::dot(m, b) - c;
        if (da >= 0) clipped.push_back(a);
        if ((da >= 0) != (db >= 0)) {
            // Interpolate from the same end whichever way the edge is walked.
            const bool fromA = lexicographicallyLess(a, b);
            const Vec3& p = fromA ? a : b;
            const Vec3& q = fromA ? b : a;
            const double dp = fromA ? da : db;
            const double dq = fromA ? db : da;
            clipped.push_back(p + (q - p) * (dp / (dp - dq)));
        }
    }
    return clipped;
}

double cosineSolidAngle(const Vec3& x, const Vec3& n, const std::vector<Vec3>& polygon) {
    if (seenEdgeOn(x, polygon, unitNormal(polygon))) return 0;
    const Vec3 unitN = glm::normalize(n);
    // The horizon n·(base + local) ≥ 0 is clipped in offset coordinates.
    // Clipping a non-convex polygon may leave pairs of edges running back
    // and forth along the horizon; their terms cancel.
    const Vec3 base = polygon[0] - x;
    const std::vector<Vec3> visible =
        clipToHalfSpace(offsetsFromFirst(polygon), unitN, -glm::dot(unitN, base));
    if (visible.size() < 3) return 0;
    return std::abs(signedCosineSolidAngle(unitN, base, visible));
}

double solidAngle(const Vec3& x, const std::vector<Vec3>& polygon) {
    const Vec3 normal = unitNormal(polygon);
    if (seenEdgeOn(x, polygon, normal)) return 0;
    // Van Oosterom & Strackee (1983) per triangle (A, B, C) of a fan from
    // the foot of the perpendicular from x, A = height × f:
    //   tan(Ω/2) = A·(B×C) / (abc (1 + â·b̂ + b̂·ĉ + ĉ·â)).
    // From the foot, the bracket ½|b̂ + ĉ|² + f·(b̂ + ĉ) is a sum of
    // non-negative terms (a fan from a vertex cancels 1 against â·ĉ ≈ −1
    // when a large polygon is seen from close by), and A·(B×C) = A·(B'×C')
    // with B', C' offsets from the foot keeps its digits for a small polygon
    // far away. The signed fan sum is exact for any simple polygon.
    const Vec3 base = polygon[0] - x;
    const double distance = glm::dot(normal, base);
    const Vec3 f = distance > 0 ? normal : -normal;
    const double height = std::abs(distance);
    const Vec3 apex = height * f;
    const Vec3 footFromFirst = distance * normal - base;
    std::vector<Vec3> fromFoot = offsetsFromFirst(polygon);
    for (Vec3& p : fromFoot) p -= footFromFirst;
    double sum = 0;
    for (size_t i = 0; i < fromFoot.size(); ++i) {
        const Vec3& bOffset = fromFoot[i];
        const Vec3& cOffset = fromFoot[(i + 1) % fromFoot.size()];
        const Vec3 bVec = apex + bOffset, cVec = apex + cOffset;
        const double b = glm::length(bVec), c = glm::length(cVec);
        const Vec3 unitBPlusC = bVec / b + cVec / c;
        const double numerator = glm::dot(apex, glm::cross(bOffset, cOffset));
        const double bracket = 0.5 * glm::dot(unitBPlusC, unitBPlusC) + glm::dot(f, unitBPlusC);
        sum += 2 * std::atan2(numerator, height * b * c * bracket);
    }
    return std::abs(sum);
}

double unoccludedCosineSolidAngle(const Light& light, const Vec3& x, const Vec3& n) {
    double csa = 0;
    for (const Triangle3& t : light.geometry)
        if (glm::dot(glm::cross(t[1] - t[0], t[2] - t[0]), x - t[0]) > 0) csa += cosineSolidAngle(x, n, {t[0], t[1], t[2]});
    return csa;
}

}  // namespace ml
