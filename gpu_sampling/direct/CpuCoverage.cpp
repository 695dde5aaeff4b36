#include "CpuCoverage.h"

#include "OccluderPolygons.h"  // kHoled

#include <algorithm>

namespace ml {

CpuCoverage::CpuCoverage(const std::vector<Triangle3>& triangles, const std::vector<uint32_t>& lightId)
    : triangles_(triangles), lightId_(lightId) {}

bool CpuCoverage::prepare(const SamplingFrustum& f, const std::vector<OccluderBvh::Range>& ranges,
                          const Rules& rules, double pw, double ph, size_t maxTriangles) {
    pieces_.clear();
    triangleCount_ = 0;
    // The part of an occluder that can hide a sample: at least the near
    // distance in front of the eye (what the shader's 1/w <= 1/near keeps)
    // and at least the tolerance on the eye's side of the light's plane.
    // Both keep a convex polygon convex, and every point of it is in front
    // of the eye, so its projection onto the window is a convex polygon
    // too. (The shader also drops triangles wholly below the receiver's
    // horizon; such a triangle meets no ray towards the light's pieces,
    // which lie above it, so it would cover no sample here either.)
    const Vec3 nearNormal = f.forward, lightNormal = rules.lightNormal;
    const double nearD = -(glm::dot(f.forward, f.eye) + rules.nearDistance);
    const double lightD = -(glm::dot(lightNormal, rules.lightPoint) + rules.planeTolerance);
    std::vector<Polygon3> one(1);
    for (const OccluderBvh::Range& r : ranges)
        for (uint32_t i = r.first; i < r.first + r.count; ++i) {
            if (lightId_[i] == rules.skipLightId) continue;
            const Triangle3& t = triangles_[i];
            auto below = [&](const Vec3& n, double d) {
                return glm::dot(n, t[0]) + d < 0 && glm::dot(n, t[1]) + d < 0 && glm::dot(n, t[2]) + d < 0;
            };
            if (below(nearNormal, nearD) || below(lightNormal, lightD)) continue;
            Polygon3& poly = one[0];
            poly = clipPolygon({t[0], t[1], t[2]}, nearNormal, nearD);
            if (!poly.empty()) poly = clipPolygon(poly, lightNormal, lightD);
            if (poly.size() < 3) continue;
            std::vector<WindowPiece> w = windowPieces(f, one, pw, ph);
            if (w.empty()) continue;
            if (lightId_[i] == OccluderPolygons::kHoled || ++triangleCount_ > maxTriangles) {
                pieces_.clear();
                triangleCount_ = 0;
                return false;
            }
            pieces_.push_back(std::move(w[0]));
        }
    return true;
}

void CpuCoverage::draw(const SamplingFrustum& f, int size, int bits, double pw, double ph, const Points& points,
                       uint32_t* visible) const {
    std::fill(visible, visible + size_t(size) * size, ~0u);
    // A pixel wholly on an occluder: every sample's bit cleared, the bits
    // above `bits` left set, as the shader's `outside = unused` leaves them.
    const uint32_t unused = bits >= 32 ? 0u : (~0u << bits);
    double u[32], v[32];
    for (const WindowPiece& piece : pieces_)
        for (int j = 0; j < size; ++j) {
            const WindowPiece::Span sp = piece.rowSpan(f.left, pw, f.bottom + (j + 0.5) * ph, size);
            uint32_t* row = visible + size_t(j) * size;
            for (int i = sp.anyLo; i <= sp.anyHi; ++i) {
                if (row[i] == unused) continue;  // hidden already
                if (i >= sp.fullLo && i <= sp.fullHi) {
                    row[i] = unused;
                    continue;
                }
                const uint32_t pixel = uint32_t(j * size + i);
                points(i, j, pixel, u, v);
                for (int k = 0; k < bits; ++k)
                    if (piece.contains(u[k], v[k])) row[i] &= ~(1u << k);
            }
        }
}

}  // namespace ml
