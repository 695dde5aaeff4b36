// The coverage pass of a sampling image (direct_coverage.*) computed on the
// CPU, for a frustum holding few occluder triangles.
//
// In a furnished room the pairs that still reach the rasteriser after the
// cheap tests (nothing in the way, OccluderPolygons' umbra) see the light
// past a desk's edge or a cabinet: a handful of triangles. On llvmpipe each
// costs a sampling image, 300-600 us, mostly waiting for the rasteriser
// (office, 12 panels: 17.6 s of a 31 s run went to reading images back).
// The control variate needs only which jittered samples on the light are
// occluded, and where an occluder's part that can hide the light lies is
// known exactly: the triangle clipped to the sampler's near plane and to
// the eye's side of the light's plane, projected onto the window, is a
// convex polygon, and a sample is occluded exactly when its window point
// lies in one of them. So the bits the GPU would write are computed here
// from the same jittered points, whole pixels decided at once from their
// centre and reach as the light's own outline is (WindowPiece::rowSpan),
// only pixels on an occluder's outline testing single samples.
//
// Decided in double where the GPU decides in float: a sample within float
// rounding of an occluder's edge (about 1e-7 of the window) may fall the
// other way. Each is a sample of the same jittered estimator, so the
// estimate stays unbiased; tests compare it with the GPU's on the office.
#pragma once

#include "LightFrustum.h"
#include "OccluderBvh.h"
#include "core/Math.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace ml {

class CpuCoverage {
public:
    // `triangles` in the BVH's leaf order, `lightId[i]` 1 + the light
    // triangle i belongs to (0: none) or OccluderPolygons::kHoled (a face
    // with a cut-out, which only the GPU's per-sample texture test decides).
    CpuCoverage(const std::vector<Triangle3>& triangles, const std::vector<uint32_t>& lightId);

    // What the sampler ignores of an occluder (as direct_coverage.* does):
    // parts nearer the eye than `nearDistance` along the frustum's axis,
    // parts within `planeTolerance` of a planar light's plane or beyond it
    // (`lightNormal` faces the eye, `lightPoint` lies on the plane), and the
    // sampled light's own triangles.
    struct Rules {
        double nearDistance = 0;
        Vec3 lightNormal{0.0}, lightPoint{0.0};
        double planeTolerance = 0;
        uint32_t skipLightId = 0;  // 1 + the sampled light
    };

    // The occluders of `ranges` that can hide a sample in frustum `f` (pixel
    // size pw × ph on its window), as window polygons. False, with nothing
    // prepared, when a face with a cut-out is among them or more than
    // `maxTriangles` are: the GPU then draws the image.
    bool prepare(const SamplingFrustum& f, const std::vector<OccluderBvh::Range>& ranges, const Rules& rules,
                 double pw, double ph, size_t maxTriangles);
    // Triangles prepare() kept (those with a part in the frustum).
    size_t triangleCount() const { return triangleCount_; }

    // Where sample k of pixel (i, j) (`pixel` = j·size + i) lies on the
    // window: u[k], v[k] for every k < bits (the sampler's SampleGrid::points).
    using Points = std::function<void(int i, int j, uint32_t pixel, double* u, double* v)>;

    // The prepared occluders' bits into `visible` (size² words, row by row
    // from the window's bottom): bit k of a pixel is cleared where sample k
    // lies on an occluder, as the GPU's AND of each triangle's bits leaves
    // it; the other bits (and bits >= `bits`) set. `f`, pw and ph as given
    // to prepare().
    void draw(const SamplingFrustum& f, int size, int bits, double pw, double ph, const Points& points,
              uint32_t* visible) const;

private:
    std::vector<Triangle3> triangles_;
    std::vector<uint32_t> lightId_;
    std::vector<WindowPiece> pieces_;  // prepared
    size_t triangleCount_ = 0;
};

}  // namespace ml
