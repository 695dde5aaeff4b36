// Whether indirect light can reach the back of an open object's face, so
// that the bounce meshes need a reversed copy of it (CacheLayout::BackFaces).
//
// Direct light reaches a back only from a light behind the face's plane
// (litFromBehind in IrradianceCache.cpp). Indirect light reaches every back
// that looks out at the scene: a luminaire hung under a ceiling has the
// ceiling a few centimetres behind it, and between the two light comes in
// from the room, bounces and goes out again. Without a copy that back reads
// black to every gather, as if its albedo were 0: 192 panels of 0.4 m under
// the office's ceiling (64% of it) left the office's indirect light 2% too
// dark, the top quarter of its image 4% (cache/README.md).
//
// The back of a face that sees only its own object is that object's
// inside: an open box (the Cornell box's blocks have no bottom) is closed
// by the floor it stands on. A copy there would be gathered and refined for
// nothing any camera sees.
//
// The object is a scene mesh: where a file merges a luminaire and the
// ceiling it hangs from into one mesh, the luminaire's back sees only that
// mesh, and gets no copy (as before this rule).
//
// Only for gathers that keep a thin surface's two sides apart
// (IndirectEstimator::separatesSides: the ray gather): through voxels, a
// partition's back would gather the light leaking through it.
#pragma once

#include "core/Math.h"
#include "core/Scene.h"

namespace ml {

class EmbreeScene;

// How far out the back of a face is tested to look: the hits of
// kBackReachRays fixed cosine-distributed rays from its centroid, on its
// back side. It looks out when one of them lands outside `object` (the
// bounds of the face's own scene mesh) grown by kBackReachSlack of the
// scene's diagonal: the floor under a block lies on the block's bounds, a
// ceiling 2 cm above a panel 2 cm outside the panels' bounds (a thousandth
// of the office's diagonal is 1 cm: so the slack is a tenth of that).
constexpr int kBackReachRays = 16;
constexpr double kBackReachSlack = 1e-4;

bool backLooksOutOfObject(const EmbreeScene& rays, const Scene& scene, const Triangle3& face,
                          const Bounds3& object);

}  // namespace ml
