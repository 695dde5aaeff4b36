// The low-resolution pass of Cochran & Steele (2007, §3.5 and §4): the
// indirect light of the camera's visible points is evaluated at 1/k of the
// resolution per axis and upsampled bilinearly, except where a pixel's
// surface differs from the low-resolution points it would be blended from
// (a discontinuity: another depth or another facing), where it is evaluated
// at full resolution. The paper builds the G-buffer (its S_cam) by a
// deferred pass on the GPU, downsamples it to S_locam, keeps a
// discontinuity buffer and redraws the flagged pixels as quads. Here both
// G-buffers are traced with Embree primary rays through the pixel centres
// (the low-resolution ones through the centres of k × k blocks: a render
// at 1/k, as the paper's downsampled buffer stands for), the discontinuity
// buffer is a flag per pixel, and the evaluation is any irradiance function
// (a VirtualPointLights estimate, typically), so the image it gives at a
// flagged pixel is the full-resolution one bit for bit.
//
// A pixel is blended when each low-resolution point with a weight in its
// bilinear blend (up to 4) sees a surface, as the pixel does, whose normal
// is within `normalCosine` of the pixel's and whose tangent plane passes
// within `planeDistance` × the pixel's depth of the pixel's point. Those
// tests, not the mesh or the triangle, decide: a floor of many triangles is
// blended across its edges, a crease or an object's outline is not.
#pragma once

#include "core/Camera.h"
#include "core/Scene.h"

#include <functional>
#include <vector>

namespace ml {

class EmbreeScene;

// What the camera sees through each sample: the paper's S_cam (or S_locam).
struct ScreenSurfaces {
    int width = 0, height = 0;
    std::vector<char> hit;        // per sample, row 0 at the top
    std::vector<Vec3> position;   // where the ray meets the scene
    std::vector<Vec3> normal;     // unit geometric normal, on the camera's side
    std::vector<double> depth;    // distance from the camera (0: nothing hit)
    size_t index(int x, int y) const { return size_t(y) * size_t(width) + size_t(x); }
};

// The surfaces of a width × height image seen through the camera with the
// path tracer's projection (square pixels, vertical field of view), sampled
// every `step` pixels at the centres of step × step blocks:
// ⌈width/step⌉ × ⌈height/step⌉ samples (step 1: the pixels themselves).
ScreenSurfaces traceScreenSurfaces(const EmbreeScene& rays, const Camera& camera, int width, int height, int step = 1);

struct UpsamplingSettings {
    int factor = 2;               // k: low resolution is 1/k per axis (the paper's 2: 1/4 of the pixels); 2..16
    double normalCosine = 0.9;    // normals further apart than this (about 25°) are a discontinuity
    double planeDistance = 0.01;  // off the tangent plane by more than this × depth: a discontinuity
    void validate() const;        // InputError unless 2 <= factor <= 16, 0 < normalCosine <= 1, planeDistance > 0
};

// The irradiance at a surface point (position, unit normal).
using IrradianceAt = std::function<Rgb(const Vec3&, const Vec3&)>;

struct UpsampledIndirect {
    int width = 0, height = 0;
    std::vector<Rgb> irradiance;  // per pixel (0 where nothing is hit)
    std::vector<char> flagged;    // per pixel: the discontinuity buffer (evaluated at full resolution)
    size_t lowEvaluations = 0;    // low-resolution points evaluated
    size_t fullEvaluations = 0;   // flagged pixels evaluated
    size_t visiblePixels = 0;     // pixels that see a surface
    // Share of the visible pixels blended from the low resolution: the
    // paper's "low resolution percentage" (Table 2).
    double lowShare() const { return visiblePixels ? 1.0 - double(fullEvaluations) / double(visiblePixels) : 0.0; }
};

// `full` at the image's resolution, `low` traced with step = settings.factor.
UpsampledIndirect upsampleIndirect(const ScreenSurfaces& full, const ScreenSurfaces& low,
                                   const UpsamplingSettings& settings, const IrradianceAt& irradiance);

// Every visible pixel evaluated: what upsampleIndirect approximates.
std::vector<Rgb> fullResolutionIndirect(const ScreenSurfaces& full, const IrradianceAt& irradiance);

}  // namespace ml
