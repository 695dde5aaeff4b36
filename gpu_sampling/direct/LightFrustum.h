// Where the sampling camera looks: frusta from a shading point fitted to an
// area light (§4: "a small frustum that fully includes the light source").
#pragma once

#include "core/Scene.h"

#include <vector>

namespace ml {

// An off-axis pinhole frustum. Camera coordinates of a point p are
// (x, y, d) = ((p−eye)·right, (p−eye)·up, (p−eye)·forward); the image is the
// window [left, right] × [bottom, top] on the plane d = 1.
//
// The basis is left-handed (right × up = −forward, OpenGL's camera
// convention), which makes a triangle that is counter-clockwise seen from the
// eye have a positive clip-space determinant in direct_coverage.vert.
struct SamplingFrustum {
    Vec3 eye{0.0};
    Vec3 forward{0.0, 0.0, 1.0};
    Vec3 right{1.0, 0.0, 0.0};
    Vec3 up{0.0, 1.0, 0.0};
    double left = -1, rightEdge = 1, bottom = -1, top = 1;

    // Camera-space position of a world point.
    Vec3 toCamera(const Vec3& p) const {
        const Vec3 v = p - eye;
        return {glm::dot(v, right), glm::dot(v, up), glm::dot(v, forward)};
    }
    // World direction (not normalised) through the window point (u, v).
    Vec3 direction(double u, double v) const { return forward + u * right + v * up; }
};

// A convex polygon in 3D and the clipping it needs.
using Polygon3 = std::vector<Vec3>;
// Keeps the part of `poly` where n·p + d >= 0 (Sutherland–Hodgman).
Polygon3 clipPolygon(const Polygon3& poly, const Vec3& n, double d);

// The parts of the light that can send light to a receiver at `eye` with
// normal `n`: front-facing triangles, each clipped to the receiver's upper
// half-space (any part below its horizon contributes nothing).
std::vector<Polygon3> visibleLightPieces(const Light& light, const Vec3& eye, const Vec3& n);

// Frusta covering `pieces` as seen from `eye`. One frustum when every piece is
// within `maxHalfAngleDegrees` of their mean direction; otherwise the light is
// split among the faces of a cube around that direction, each face's frustum
// fitted to the part of the light it sees (a point right next to a large light
// sees nearly a hemisphere, which no single perspective frustum holds).
// The frusta never overlap, so their estimates add. `alignTo` (a light edge)
// orients the single frustum's rows, as in the paper's bench.
std::vector<SamplingFrustum> fitFrusta(const std::vector<Polygon3>& pieces, const Vec3& eye,
                                       const Vec3& alignTo, double maxHalfAngleDegrees);

// The frusta a sampler renders for a light seen from `eye` (its visible
// pieces): rows follow the edge of the light's first triangle that is most
// across the line of sight, as in the paper's bench (an edge seen end-on
// would leave a thin diagonal sliver of used pixels); for a long thin light
// seen obliquely, another edge of that triangle if it at least halves the
// window. The raster sampler and its ray-traced peer both use this, so they
// test the same points.
std::vector<SamplingFrustum> samplingFrusta(const Light& light, const std::vector<Polygon3>& pieces,
                                            const Vec3& eye, double maxHalfAngleDegrees);

// A convex piece of the light on a frustum's window plane (depth 1), as
// edge functions a·u + b·v + c ≥ 0 inside; `reach` is how much an edge
// function can change within half a pixel (pixel size pw × ph).
struct WindowPiece {
    struct Edge {
        double a, b, c, reach;
    };
    std::vector<Edge> edges;
    bool contains(double u, double v) const {
        for (const Edge& e : edges)
            if (e.a * u + e.b * v + e.c < 0) return false;
        return true;
    }

    // Pixel columns of one row of a size × size image whose pixels lie
    // wholly inside the piece, [fullLo, fullHi], and those that touch it,
    // [anyLo, anyHi] (empty when lo > hi). Pixel i's centre is at
    // (left + (i + ½)·pw, vc); the edges' reach must be for that pixel
    // size. Along a row the edge functions are linear in the column, so
    // each is two spans.
    struct Span {
        int fullLo, fullHi, anyLo, anyHi;
    };
    Span rowSpan(double left, double pw, double vc, int size) const;
};

// The light's pieces clipped to the frustum's pyramid and projected onto
// its window (in double): where the control-variate estimator decides
// which jittered samples lie on the light.
std::vector<WindowPiece> windowPieces(const SamplingFrustum& f, const std::vector<Polygon3>& pieces, double pw = 0,
                                      double ph = 0);

// (u, v) on the window lies on one of the light's pieces.
inline bool onAnyPiece(const std::vector<WindowPiece>& pieces, double u, double v) {
    for (const WindowPiece& p : pieces)
        if (p.contains(u, v)) return true;
    return false;
}

}  // namespace ml
