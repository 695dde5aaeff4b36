// Wavefront OBJ + MTL loading.
#pragma once

#include "core/Scene.h"

#include <functional>
#include <string>

namespace ml {

struct ObjOptions {
    // Faces whose normals differ by more than this keep separate vertices when
    // the file gives no `vn` for a face; degrees in [0, 180], typical 30.
    double creaseAngleDegrees = 30;
};

// Reads an OBJ file and the MTL libraries it names into a finalized Scene
// (Scene::name = path; one Mesh per `o`/`g`, re-entered groups continue their
// mesh; faces before any `o`/`g` form a mesh named after the file).
//
// Accepted: v (x y z [w], w ignored; x y z r g b [a] vertex colours ignored
// with a warning), vn, vt (checked, unused), f with v, v/vt, v//vn, v/vt/vn
// and negative (relative) indices, o, g, usemtl, mtllib (several files, paths
// relative to the OBJ's folder), s (the crease angle replaces smoothing
// groups), comments, blank lines, CRLF. Polygons are split as a fan from their
// first corner, which is right for convex polygons; a polygon that is not
// convex gets one counted warning per file.
// MTL: newmtl, Kd, Ks, Ke (1 or 3 values), Ns; Ka and Ni are checked and
// unused; d < 1, Tr > 0 and illum > 2 (transparency, mirrors, glass) are
// checked and warned about since they render as opaque Lambert + Phong.
// Kd or Ks above 1 is clamped to 1 with a warning (it would create energy);
// negative Kd, Ks, Ke or Ns is an error. Texture statements (map_*, bump,
// disp, decal, refl, norm) give a warning and the constant value is used.
// Faces without usemtl get a material "default" (Kd 0.8).
// Unknown statements give one warning per keyword and file, with the first
// line and a count: OBJ has many dialects.
//
// Normals: a face whose corners all have `vn` uses them (normalised); other
// faces get computeShadingNormals with options.creaseAngleDegrees.
// Degenerate triangles are dropped with one counted warning per file.
//
// Throws InputError with file:line for: a file that cannot be opened, a
// missing MTL, usemtl of an unknown material, a malformed or non-finite
// number, a wrong number of values, a face index that is 0 or out of range, a
// face with fewer than 3 corners, a zero-length vn used by a face, an emitting
// material whose faces are all degenerate, a file without faces, and a crease
// angle outside [0, 180].
Scene loadObj(const std::string& path, const ObjOptions& options = {});

// Where loadObj's files come from: fills `text` with the whole file at `path`
// and returns true, or returns false when it cannot be opened.
using ObjFileReader = std::function<bool(const std::string& path, std::string& text)>;

// The same, with the OBJ and every MTL library read through `read` rather
// than from the file system (tests and the fuzzer serve them from memory).
// `read` gets `path` for the OBJ and, for an MTL, the path loadObj would open:
// relative names joined to the OBJ's folder, lexically normalised. Errors
// name the same paths and lines as for files.
Scene loadObj(const std::string& path, const ObjOptions& options, const ObjFileReader& read);

}  // namespace ml
