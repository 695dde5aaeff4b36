// Which area lights reach the scene through the indirect gather rather than
// through the direct sampler: the dim, broad emitters of real scenes (a
// wall texture's faint glow, a backlit ceiling), as a path tracer would
// find them by sampling directions rather than lights.
//
// The direct sampler rasterises a light and its occluders from each point:
// its cost grows with the light's solid angle (pixels) and with the
// occluders in its frustum. For a luminaire that is a few pixels and a few
// triangles; for a glowing wall it is the whole sampling image and every
// triangle of the room (the back rooms' six emissive walls, 2% of the
// light, took 98% of direct sampling: 16 ms a pair against 1.7 ms for a
// ceiling panel, 64×64 image, llvmpipe). And a gather sees such an emitter
// as it sees any lit wall: its radiance is of the order of the reflected
// radiance the gather reads anyway, so adding it costs the gather nothing
// and adds little noise. So a light whose radiance is below `ratio` of the
// brightest area light's is gathered: bounce 1's gather adds its emitted
// radiance where its rays land on it (RayGather), its own direct mesh is
// empty and the shared mesh leaves it out (LightCoverage). Its light is
// then counted once, in the indirect meshes, with the noise tolerance of
// indirect light. Only with a gather that reads emission (the ray gather)
// and with indirect light on; direct-only runs sample every light.
// What is approximate: the viewer's per-light relighting does not reach a
// gathered light's light (it is in the indirect meshes), and its light.NAME
// layer is empty; the plan says which lights these are.
#pragma once

#include "core/Scene.h"

#include <string>
#include <vector>

namespace ml {

struct GatheredLights {
    std::vector<char> gathered;  // per scene light: 1 = gathered (empty: none)
    std::string reason;          // for the plan: which and why, or why none

    bool any() const;
    bool operator()(size_t light) const { return light < gathered.size() && gathered[light]; }
};

// `ratio` in [0, 1): a light is gathered when the luminance of its radiance
// (Ke, the mean of a textured one) is below `ratio` × the brightest area
// light's; 0 gathers none. Punctual lights are never gathered, and at least
// one area light is always sampled (the brightest).
GatheredLights chooseGatheredLights(const Scene& scene, double ratio);

}  // namespace ml
