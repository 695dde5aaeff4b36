// A punctual light's direct irradiance at a receiver: the unoccluded
// irradiance of punctualIncidence() (core/PunctualLight.h) times one shadow
// ray's verdict. A point has no extent, so visibility is all or nothing and
// one ray is the exact answer: no jitter, no raster, no penumbra. Used by the
// cache's direct samplers (every method), the path tracer's next-event
// estimation and the bounce count, so all of them agree on what a point
// light gives, singularity included.
#pragma once

#include "EmbreeScene.h"

namespace ml {

struct PunctualSample {
    Rgb irradiance{0.0};  // W·m⁻²
    Vec3 toLight{0.0};    // unit direction of the shadow ray (zero where the light cannot reach x)
    bool lit = false;     // the light faces x's side and is not at x
    bool visible = false; // lit, and nothing lies between
};

// Light `light` (punctual) at x, unit normal n. The shadow ray leaves from x
// lifted along n by the scene's ray offset (EmbreeScene::spawnPoint) and
// stops the same offset short of the light, so a light lying on a wall is
// not hidden by that wall; hits nearer than the offset are ignored, so a
// receiver on an edge or touching an occluder is not hidden by the surface
// it touches (the raster sampler's near plane does the same).
PunctualSample punctualIrradiance(const EmbreeScene& rays, size_t light, const Vec3& x, const Vec3& n);
// The same with the cosine taken against a shading normal `n` and the
// horizon and the ray's lift against the geometric normal `ng` (the path
// tracer's vertices).
PunctualSample punctualIrradiance(const EmbreeScene& rays, size_t light, const Vec3& x, const Vec3& n,
                                  const Vec3& ng);

}  // namespace ml
