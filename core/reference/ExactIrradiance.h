// Exact direct irradiance from planar polygonal lights with occlusion: the
// ground truth the GPU light samplers are measured against (the solid-angle
// bench of Fournier & Péroche §6.1 and the direct-lighting tests).
//
// Method, per light triangle: clip it to the receiver's horizon; clip every
// occluder to the pyramid from the receiver through it, strictly between the
// receiver and the light's plane; project the pieces centrally onto that
// plane; merge pieces that tile a convex polygon (a finely tessellated flat
// occluder); subtract their union from the triangle with exact 2D Boolean
// operations (CGAL); apply Lambert's formula to every boundary left.
// Cost, one core of an AMD EPYC virtual machine, 10,000 bench receivers
// (§6.1): 16,000 receivers/s with the 2-triangle occluder, 530/s with the
// 7,200-triangle one (merged; preparing its pieces dominates). Occluders that
// do not merge cost CGAL's union, ~10 µs per triangle inside the pyramid.
// Calls share no state and may run in parallel.
#pragma once

#include "core/Scene.h"

#include <vector>

namespace ml {

// ∫ V(x, ω) max(0, cos θ) dω over the directions ω from x that reach
// `light` unblocked by `occluders`; dimensionless, in [0, π]. Irradiance is
// the light's radiance times this.
//   x          receiver position (scene units)
//   n          receiver normal (normalised here)
//   light      coplanar triangles (within 1e-6 of the light's size) of
//              uniform radiance, counter-clockwise = emitting side; when x is
//              behind or in the light's plane the result is 0
//   occluders  every triangle that may block the light, either orientation;
//              parts behind x, behind the light or in the light's plane do
//              not block
// Accurate to about 1e-12 relative, or 1e-15 absolute where the value is
// tiny (a light seen at grazing incidence), for receivers from 1e-4 of the
// light's size up to far away, at any scene scale (it works relative to x,
// in units of the light's size). Occluder parts closer to the light's plane
// than 1e-9 of the receiver's distance to it count as lying in it.
// Throws std::invalid_argument for a non-planar light.
double exactVisibleCosineSolidAngle(const Vec3& x, const Vec3& n, const std::vector<Triangle3>& light,
                                    const std::vector<Triangle3>& occluders);

// The exact reference for a whole scene: each light is occluded by every
// other triangle of the scene, other lights included. Every query throws
// InputError when its light is not planar (so a scene with a curved emitter
// can still be measured light by light) and std::out_of_range for an index
// past Scene::lights.
class ExactDirect {
public:
    // Keeps a copy of the scene's triangles; `scene` must be finalized.
    explicit ExactDirect(const Scene& scene);

    // Irradiance at x from light `lightIndex` (index into Scene::lights),
    // W·m⁻² per channel.
    Rgb irradiance(size_t lightIndex, const Vec3& x, const Vec3& n) const;
    // The visible cosine-weighted solid angle of the light (see above).
    double cosineSolidAngle(size_t lightIndex, const Vec3& x, const Vec3& n) const;
    // The same ignoring every occluder: Lambert's formula for the light.
    double unoccludedCosineSolidAngle(size_t lightIndex, const Vec3& x, const Vec3& n) const;

private:
    const Light& planarLight(size_t lightIndex) const;

    std::vector<Light> lights_;
    // Every scene triangle, those of light k at [lightBegin_[k], lightEnd_[k]),
    // so that light k's occluders are the two ranges around its own.
    std::vector<Triangle3> triangles_;
    std::vector<size_t> lightBegin_, lightEnd_;
};

}  // namespace ml
