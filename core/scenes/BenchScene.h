// The direct-lighting bench of Fournier & Péroche §6.1: one square light
// partly hidden by one square occluder, measured at 10,000 points of a floor.
//
// Geometry (y up, scene units):
//   light     1 × 1 square, x, z ∈ [−0.5, 0.5], y = 1, emitting downwards,
//             Ke = 1 (so irradiance equals the cosine-weighted solid angle)
//   occluder  0.5 × 0.5 square, x ∈ [−0.2, 0.3], z ∈ [−0.3, 0.2], y = 0.5,
//             facing down, Kd = 0.5; edges parallel to the light's, as the
//             paper asks, so that shadow edges line up with a sampling grid
//             aligned with the light
//   floor     3 × 3 square, x, z ∈ [−1.5, 1.5], y = 0, facing up, Kd = 0.5
//
// Why these numbers. The occluder is half the light's size halfway up, so
// from the floor it has exactly the light's apparent size: the floor's shadow
// is all penumbra, the region where samplers err most, with full shadow only
// at the single point (0.1, 0, −0.1). The penumbra spans x ∈ [−0.9, 1.1],
// z ∈ [−1.1, 0.9] (a shadow edge at occluder coordinate c spreads from
// 2c − 0.5 to 2c + 0.5), inside the receiver grid x, z ∈ [−1.2, 1.2], which
// keeps a fully lit margin. Off centre by (0.05, −0.05), the occluder hides
// part of the light from every receiver near the centre, and its shadow is
// not symmetric about the grid's axes. Unoccluded, the irradiance on the
// axis under the light is 4 s·atan(s) with s = 0.5/√1.25,
// about 0.7523 W·m⁻²; at the grid's outermost points it falls to 0.0764.
// Receivers at y = 0.25 under the occluder's centre are fully hidden.
#pragma once

#include "core/Scene.h"

#include <vector>

namespace ml {

// The bench scene, finalized: meshes "light", "occluder", "floor" with
// materials of the same names.
//   occluderSubdivisions  the occluder quad is split into s × s cells of two
//                         triangles each (s ≥ 1; 60 gives the 7,200-triangle
//                         occluder of the cost bench)
Scene makeBenchScene(int occluderSubdivisions = 1);

struct ReceiverPoint {
    Vec3 position;  // scene units
    Vec3 normal;    // unit
};

// perSide × perSide receivers at the centres of a regular grid of cells
// covering x, z ∈ [−1.2, 1.2] on the floor (y = 0, normal +y), row by row
// (x fastest). perSide ≥ 1; the paper's 10,000 points are perSide = 100.
std::vector<ReceiverPoint> makeBenchReceivers(int perSide = 100);

}  // namespace ml
