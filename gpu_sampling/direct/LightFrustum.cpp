#include "LightFrustum.h"

#include <algorithm>
#include <cmath>

namespace ml {

Polygon3 clipPolygon(const Polygon3& poly, const Vec3& n, double d) {
    Polygon3 out;
    out.reserve(poly.size() + 1);
    for (size_t i = 0; i < poly.size(); ++i) {
        const Vec3& a = poly[i];
        const Vec3& b = poly[(i + 1) % poly.size()];
        const double fa = glm::dot(n, a) + d;
        const double fb = glm::dot(n, b) + d;
        if (fa >= 0) out.push_back(a);
        if ((fa >= 0) != (fb >= 0)) out.push_back(a + (b - a) * (fa / (fa - fb)));
    }
    return out.size() >= 3 ? out : Polygon3{};
}

std::vector<Polygon3> visibleLightPieces(const Light& light, const Vec3& eye, const Vec3& n) {
    std::vector<Polygon3> pieces;
    for (const Triangle3& t : light.geometry) {
        const Vec3 an = glm::cross(t[1] - t[0], t[2] - t[0]);
        if (!(glm::dot(an, eye - t[0]) > 0)) continue;  // seen from behind: emits nothing this way
        Polygon3 p = clipPolygon({t[0], t[1], t[2]}, n, -glm::dot(n, eye));
        if (!p.empty()) pieces.push_back(std::move(p));
    }
    return pieces;
}

namespace {

// Basis with the given forward and rows along `align` where possible.
void makeBasis(const Vec3& forward, const Vec3& align, SamplingFrustum& f) {
    f.forward = forward;
    Vec3 r = align - glm::dot(align, forward) * forward;
    if (glm::length(r) < 1e-6 * std::max(glm::length(align), 1e-300)) {
        Vec3 t, b;
        orthonormalBasis(forward, t, b);
        r = t;
    }
    f.right = glm::normalize(r);
    f.up = glm::cross(f.right, f.forward);  // left-handed: right × up = −forward
}

// Fits the window of `f` (basis set) to the pieces, clipped to `planes`
// (camera-space half-spaces a·(x,y,d) >= 0). Returns false if nothing is left.
bool fitWindow(const std::vector<Polygon3>& pieces, const std::vector<Vec3>& planes, double limit,
               SamplingFrustum& f) {
    double lo[2] = {kInf, kInf}, hi[2] = {-kInf, -kInf};
    bool any = false;
    for (const Polygon3& piece : pieces) {
        Polygon3 cam;
        for (const Vec3& p : piece) cam.push_back(f.toCamera(p));
        for (const Vec3& a : planes) {
            cam = clipPolygon(cam, a, 0.0);
            if (cam.empty()) break;
        }
        for (const Vec3& c : cam) {
            if (!(c.z > 0)) continue;  // on the eye itself: no direction
            for (int k = 0; k < 2; ++k) {
                const double s = c[k] / c.z;
                lo[k] = std::min(lo[k], s);
                hi[k] = std::max(hi[k], s);
            }
            any = true;
        }
    }
    if (!any || !(hi[0] > lo[0]) || !(hi[1] > lo[1])) return false;
    // A hair of margin so the light's own edges never sit on the window's.
    const double mx = 1e-7 * (hi[0] - lo[0]), my = 1e-7 * (hi[1] - lo[1]);
    // Cube faces keep to their own face (limit 1): frusta never overlap.
    f.left = std::max(lo[0] - mx, -limit);
    f.rightEdge = std::min(hi[0] + mx, limit);
    f.bottom = std::max(lo[1] - my, -limit);
    f.top = std::min(hi[1] + my, limit);
    return true;
}

}  // namespace

std::vector<SamplingFrustum> fitFrusta(const std::vector<Polygon3>& pieces, const Vec3& eye,
                                       const Vec3& alignTo, double maxHalfAngleDegrees) {
    // Mean direction of the light's corners as seen from the eye.
    Vec3 sum(0.0);
    for (const Polygon3& piece : pieces)
        for (const Vec3& p : piece) {
            const double len = glm::length(p - eye);
            if (len > 0) sum += (p - eye) / len;
        }
    const double sumLen = glm::length(sum);
    if (!(sumLen > 0)) return {};
    const Vec3 axis = sum / sumLen;

    double minCos = 1.0;
    for (const Polygon3& piece : pieces)
        for (const Vec3& p : piece) {
            const double len = glm::length(p - eye);
            if (len > 0) minCos = std::min(minCos, glm::dot(p - eye, axis) / len);
        }

    SamplingFrustum f;
    f.eye = eye;
    makeBasis(axis, alignTo, f);
    // Convex pieces inside a cap of half-angle < 90° stay inside it, so the
    // corners decide.
    if (minCos > std::cos(glm::radians(maxHalfAngleDegrees))) {
        const std::vector<Vec3> inFront = {Vec3(0.0, 0.0, 1.0)};
        if (fitWindow(pieces, inFront, kInf, f)) return {f};
        return {};
    }

    // Split among the six faces of a cube around the axis; each face is the
    // pyramid |x| <= d, |y| <= d of its own basis.
    const SamplingFrustum base = f;
    const Vec3 dirs[6][2] = {{base.forward, base.right},  {-base.forward, base.right},
                             {base.right, base.up},       {-base.right, base.up},
                             {base.up, base.right},       {-base.up, base.right}};
    const std::vector<Vec3> face = {Vec3(-1, 0, 1), Vec3(1, 0, 1), Vec3(0, -1, 1), Vec3(0, 1, 1)};
    std::vector<SamplingFrustum> frusta;
    for (const auto& d : dirs) {
        SamplingFrustum g;
        g.eye = eye;
        makeBasis(d[0], d[1], g);
        if (fitWindow(pieces, face, 1.0, g)) frusta.push_back(g);
    }
    return frusta;
}

std::vector<SamplingFrustum> samplingFrusta(const Light& light, const std::vector<Polygon3>& pieces,
                                            const Vec3& eye, double maxHalfAngleDegrees) {
    const Triangle3& first = light.geometry[0];
    const Vec3 towards = glm::normalize(light.centroid - eye);
    Vec3 align = first[1] - first[0];
    double best = -1;
    for (int k = 0; k < 3; ++k) {
        const Vec3 e = glm::normalize(first[(k + 1) % 3] - first[k]);
        const double across = glm::length(e - glm::dot(e, towards) * towards);
        if (across > best + 1e-6) {  // a clear margin: ties resolve the same at any scale
            best = across;
            align = e;
        }
    }
    std::vector<SamplingFrustum> frusta = fitFrusta(pieces, eye, align, maxHalfAngleDegrees);
    // Along a long thin light's width (its edge most across the line of
    // sight when seen obliquely), its length runs diagonally through the
    // window: a thin sliver of used pixels again, ~1/64 of them for a light
    // 1e-4 wide. Rows follow another edge of the triangle if that at least
    // halves the window (a clear margin: the bench's square light keeps its
    // rows).
    auto windowArea = [](const SamplingFrustum& f) { return (f.rightEdge - f.left) * (f.top - f.bottom); };
    for (int k = 0; k < 3 && frusta.size() == 1; ++k) {
        const Vec3 e = glm::normalize(first[(k + 1) % 3] - first[k]);
        if (e == align) continue;
        std::vector<SamplingFrustum> other = fitFrusta(pieces, eye, e, maxHalfAngleDegrees);
        if (other.size() == 1 && windowArea(other[0]) < 0.5 * windowArea(frusta[0])) frusta = std::move(other);
    }
    return frusta;
}

namespace {

// Narrows [lo, hi] to the columns i in [0, size) where at0 + slope·i >= 0.
void columnsWhere(double at0, double slope, int size, int& lo, int& hi) {
    if (slope == 0) {
        if (at0 < 0) hi = -1;
        return;
    }
    const double root = -at0 / slope;  // where the edge function crosses zero
    if (slope > 0)
        lo = std::max(lo, int(std::clamp(std::ceil(root), -1.0, double(size))));
    else
        hi = std::min(hi, int(std::clamp(std::floor(root), -1.0, double(size))));
}

}  // namespace

WindowPiece::Span WindowPiece::rowSpan(double left, double pw, double vc, int size) const {
    Span sp{0, size - 1, 0, size - 1};
    for (const Edge& e : edges) {
        // e(i) = e.a·(left + (i + ½)·pw) + e.b·vc + e.c, linear in i.
        const double at0 = e.a * (left + 0.5 * pw) + e.b * vc + e.c, slope = e.a * pw;
        columnsWhere(at0 - e.reach, slope, size, sp.fullLo, sp.fullHi);
        columnsWhere(at0 + e.reach, slope, size, sp.anyLo, sp.anyHi);
    }
    return sp;
}

std::vector<WindowPiece> windowPieces(const SamplingFrustum& f, const std::vector<Polygon3>& pieces, double pw,
                                      double ph) {
    // The frustum's pyramid in camera space: l <= x/d <= r, b <= y/d <= t.
    const Vec3 sides[4] = {Vec3(1, 0, -f.left), Vec3(-1, 0, f.rightEdge), Vec3(0, 1, -f.bottom), Vec3(0, -1, f.top)};
    std::vector<WindowPiece> out;
    for (const Polygon3& piece : pieces) {
        Polygon3 cam;
        for (const Vec3& p : piece) cam.push_back(f.toCamera(p));
        for (const Vec3& plane : sides)
            if (!cam.empty()) cam = clipPolygon(cam, plane, 0.0);
        if (cam.size() < 3) continue;
        std::vector<Vec2> q;
        for (const Vec3& c : cam) q.push_back(Vec2(c.x / c.z, c.y / c.z));
        double area2 = 0;
        for (size_t k = 0; k < q.size(); ++k) {
            const Vec2& a = q[k];
            const Vec2& b = q[(k + 1) % q.size()];
            area2 += a.x * b.y - a.y * b.x;
        }
        if (area2 == 0) continue;
        const double sigma = area2 > 0 ? 1.0 : -1.0;
        WindowPiece wp;
        for (size_t k = 0; k < q.size(); ++k) {
            const Vec2& a = q[k];
            const Vec2 e = q[(k + 1) % q.size()] - a;
            WindowPiece::Edge edge{-sigma * e.y, sigma * e.x, sigma * (e.y * a.x - e.x * a.y), 0};
            edge.reach = 0.5 * (std::abs(edge.a) * pw + std::abs(edge.b) * ph);
            wp.edges.push_back(edge);
        }
        out.push_back(std::move(wp));
    }
    return out;
}

}  // namespace ml
