// Closed forms for a planar polygon seen from a point: Lambert's formula for
// the cosine-weighted solid angle (the irradiance from a uniform emitter) and
// Van Oosterom–Strackee's solid angle. The ground truth of the tests and of
// the exact direct-lighting reference (ExactIrradiance.h).
//
// Sign convention. The signed sums below are positive when the polygon's
// right-hand normal, (p1 − p0) × (p2 − p0) for a convex polygon, points away
// from the viewpoint x, i.e. when the polygon winds clockwise as seen from x.
// A scene's emitter (counter-clockwise = emitting face, facing x) therefore
// gives a negative signed sum; the public functions return the magnitude so
// that either orientation gives the positive value.
#pragma once

#include "core/Math.h"
#include "core/Scene.h"

#include <vector>

namespace ml {

// ∫ max(0, cos θ) dω over the directions from x that hit `polygon`, θ being
// measured from n: the irradiance at x from a uniform unit-radiance polygon
// (E = L × this, W·m⁻² for L in W·sr⁻¹·m⁻²). Dimensionless, in [0, π].
//   x        receiver position (scene units)
//   n        receiver normal; need not be unit (it is normalised)
//   polygon  vertices of a planar simple polygon, either orientation, any size
// The polygon is first clipped to the half-space n·(p − x) ≥ 0, so only the
// part above the receiver's horizon counts. Returns 0 when x lies in the
// polygon's plane (within 1e-12 of the polygon's size), boundary included.
double cosineSolidAngle(const Vec3& x, const Vec3& n, const std::vector<Vec3>& polygon);

// cosineSolidAngle summed over the light's triangles whose emitting (CCW)
// side faces x: the irradiance at x from the light with nothing in the way,
// per unit of its radiance.
double unoccludedCosineSolidAngle(const Light& light, const Vec3& x, const Vec3& n);

// Solid angle (sr, in [0, 2π]) that the planar simple polygon subtends at x,
// either orientation; 0 when x lies in its plane.
double solidAngle(const Vec3& x, const std::vector<Vec3>& polygon);

// Building blocks for callers that clip and orient polygons themselves.

// Lambert's sum ½ Σ Θ_i (n·ĝ_i) over a closed boundary whose vertices,
// relative to the receiver, are base + local[i] (not clipped: each must
// satisfy n·(base + local[i]) ≥ 0 up to rounding). Θ_i is the angle edge i
// subtends at the receiver and ĝ_i the unit normal of the plane through the
// receiver and that edge. Signed as described at the top of this file, so
// the boundaries of a polygon with holes can simply be summed. n must be unit.
// Edges are computed as differences of `local` points: with the large common
// offset in `base` (a vertex, the foot of the perpendicular), a small polygon
// far away keeps its digits (the edge terms cancel down to Ω ~ area/d²).
double signedCosineSolidAngle(const Vec3& n, const Vec3& base, const std::vector<Vec3>& local);

// Sutherland–Hodgman: the part of the convex or simple `polygon` where
// m·p ≥ c. The point where an edge crosses the plane is computed from the
// edge's lexicographically smaller end, so two triangles sharing an edge get
// bit-identical crossing points and their clipped pieces still fit together.
std::vector<Vec3> clipToHalfSpace(const std::vector<Vec3>& polygon, const Vec3& m, double c);

}  // namespace ml
