// Clean-up and shading-normal generation for triangle meshes, shared by the
// loaders and the built-in scenes.
#pragma once

#include "Scene.h"

#include <cstddef>
#include <vector>

namespace ml {

// Drops the triangles nothing downstream can shade or sample: a repeated
// vertex index, a non-finite corner, or an area <= (relTol · d)², d being the
// diagonal of the bounding box of the mesh's referenced finite positions.
// The test is relative so that it means the same in millimetres and in metres.
//   relTol:  relative edge tolerance, >= 0; typical 1e-6 (area <= 1e-12 · d²).
//   removed: when not null, receives the indices the dropped triangles had
//            before the call, ascending (e.g. to report their sourceLines).
// Keeps `materials`, `sourceLines` and `albedo` aligned with `triangles`
// (each may be empty); vertices are left as they are, even when no longer referenced.
// Returns the number of triangles dropped. Throws std::invalid_argument if
// relTol is negative or not finite, or a per-triangle array is misaligned.
size_t removeDegenerateTriangles(Mesh& mesh, double relTol,
                                 std::vector<size_t>* removed = nullptr);

// Replaces the mesh's vertices by (position, shading normal) pairs, and
// (position, normal, texture coordinate) when the mesh has texcoords.
// Each corner's normal is the angle-weighted mean of the face normals of the
// triangles around its position (positions welded by exact equality) whose
// normal is within creaseAngleDegrees of the corner's own face normal; faces
// meeting at a sharper angle keep separate vertices. Angle weights make the
// result independent of how a planar polygon was split into triangles.
//   creaseAngleDegrees: in [0, 180]; typical 30. 0 gives flat faces (exactly
//                       coplanar triangles still share vertices), 180 smooths
//                       everything.
// Corners with equal position, normal (and texcoord) share one vertex; vertices are
// ordered by the first use of their position; triangle order, `materials` and
// `sourceLines` are unchanged; unreferenced positions are dropped; existing
// normals are ignored. Cost grows with the square of the number of triangles
// around a position. Throws std::invalid_argument for a crease angle outside
// [0, 180] or a triangle of zero or non-finite area (run
// removeDegenerateTriangles first).
void computeShadingNormals(Mesh& mesh, double creaseAngleDegrees);

// Whether an object is closed: with its vertices welded by position (they
// are split at creases), every edge is shared by an even number of its
// triangles. The inside of a closed object is never seen nor lit.
bool isClosedMesh(const Mesh& mesh);

// Longest-edge bisection (Rivara's) until no edge is longer than
// maxLength: the longest edge left is split at its midpoint, in every
// triangle beside it, so the mesh stays conforming (no T-vertex), also
// across edges whose vertices are repeated at a seam (positions welded by
// exact equality: each side gets a midpoint of its own, with its own normal
// and texture coordinate). New vertices interpolate their edge's normal
// (renormalised) and texcoords; a split triangle's halves keep its
// material, source line and albedo. The cache's base meshes are bisected
// this way; cutting large triangles first and bisecting the pieces after
// shapes them worse (ContactCuts.h). Returns the number of vertices added.
// Throws std::invalid_argument unless maxLength is positive and finite.
size_t bisectLongEdges(Mesh& mesh, double maxLength);

}  // namespace ml
