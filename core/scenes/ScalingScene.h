// Scenes for measuring how cost grows: the same geometry in more triangles,
// the same light power in more lights, and receivers spread over surfaces.
#pragma once

#include "core/Scene.h"
#include "core/scenes/BenchScene.h"

#include <cstdint>
#include <vector>

namespace ml {

// A finalized copy of `base` in which every non-emissive triangle is split
// into 4 by its edge midpoints, `levels` times over (×4^levels triangles).
// The surfaces do not move: each new vertex is the midpoint of an edge of a
// planar triangle, so receivers on the base scene lie on the subdivided one,
// and its shadows are unchanged. Midpoints are shared by the two triangles of
// an edge (the mesh stays connected); their normal is the normalised mean of
// the edge's two end normals. Emissive triangles are kept whole, so the
// lights stay the same lights: an edge shared by an emissive and a
// non-emissive triangle of one mesh then gets a T-vertex (no built-in scene
// has one: their lights are meshes of their own).
//   levels  0..12; 0 returns a copy. The name becomes "<base>-x4^<levels>".
Scene subdivideScene(const Scene& base, int levels);

// The measured Cornell box (makeCornellBox) with its light replaced by
// `lights` square lights, 40 mm a side, at the centres of the first `lights`
// cells of a ceil(√n) × ceil(n / ceil(√n)) grid over a 400 × 400 mm square
// centred under the ceiling, 0.5 mm below it, facing down. Their total power
// equals the original light's (each radiance is Ke × A₀ / (n × 40²)), so
// images differ by the shape of the light only. One mesh "light" holds them
// all; the quads do not touch, so finalize() makes `lights` AreaLights.
//   lights  1..1024 (64 fills an 8 × 8 grid of 50 mm cells)
Scene makeCornellLightGrid(int lights);

// `count` receivers spread uniformly (by area) over the scene's non-emissive
// triangles, each with its triangle's front-face normal, as an irradiance
// cache vertex would have: the same `seed` and scene give the same points.
// Empty when the scene has no non-emissive area or count is 0.
std::vector<ReceiverPoint> surfaceReceivers(const Scene& scene, size_t count, uint32_t seed);

}  // namespace ml
