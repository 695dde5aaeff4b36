// The plane that fits values at a vertex's neighbours best (least squares,
// in the vertex's tangent plane), shared by the cache's refinement (a
// vertex's residual against it: cache/Refine.cpp) and the ray gather's
// curvature (gpu_sampling/indirect/RadianceProxy.h).
#pragma once

#include "Math.h"

#include <vector>

namespace ml {

// min Σ (c + gx·x + gy·y − f_u)² over the neighbours u at offsets (x, y) in
// the tangent plane, offsets over the ring's size so that the test for a
// singular system is scale-free. The fit's value at the vertex is
// c = (inverse · Σ row_u f_u).x = Σ (inverse · row_u).x f_u: equal to the
// vertex's own value for any linear signal, whatever the ring's shape, also
// at a border where every neighbour lies on one side.
struct TangentPlaneFit {
    glm::dmat3 inverse{1.0};            // of the normal equations' matrix Σ row rowᵀ
    std::vector<glm::dvec3> rows;       // per neighbour: (1, x, y), in ring units
};

// Fits the plane at p (normal n, any length over 0.5; (0, 0, 1) otherwise)
// to `neighbours`, in `fit` (its rows reused). False with fewer than three
// neighbours or all on one line: the determinant is about k³/64 or more for
// k unit offsets spread in two directions, and under 1e-6·k³ counts as one.
inline bool fitTangentPlane(const Vec3& p, Vec3 n, const std::vector<Vec3>& neighbours, TangentPlaneFit& fit) {
    fit.rows.clear();
    if (!(glm::length(n) > 0.5)) n = Vec3(0, 0, 1);
    Vec3 tx, ty;
    orthonormalBasis(glm::normalize(n), tx, ty);
    double scale = 0;
    for (const Vec3& q : neighbours) scale = std::max(scale, glm::length(q - p));
    if (!(scale > 0)) scale = 1;
    glm::dmat3 a(0.0);
    for (const Vec3& q : neighbours) {
        const Vec3 d = (q - p) / scale;
        fit.rows.emplace_back(1.0, glm::dot(d, tx), glm::dot(d, ty));
        a += glm::outerProduct(fit.rows.back(), fit.rows.back());
    }
    const double det = glm::determinant(a);
    if (neighbours.size() < 3 || !(std::abs(det) > 1e-6 * std::pow(double(neighbours.size()), 3))) return false;
    fit.inverse = glm::inverse(a);
    return true;
}

}  // namespace ml
