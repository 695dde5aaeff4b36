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
// with a warning), vn, vt (u [v [w]], w unused), f with v, v/vt, v//vn, v/vt/vn
// and negative (relative) indices, o, g, usemtl, mtllib (several files, paths
// relative to the OBJ's folder), s (the crease angle replaces smoothing
// groups), comments, blank lines, CRLF. Polygons are split as a fan from their
// first corner, which is right for convex polygons; a polygon that is not
// convex gets one counted warning per file.
// MTL: newmtl, Kd, Ks, Ke, Tf (1 or 3 values), Ns, Ni, illum; Ka is checked
// and unused. illum 3 and 5 make a mirror of reflectance Ks (5: Schlick), 7 a
// glass of index Ni (1.5 when absent) and filter Tf (1 1 1 when absent), 4,
// 6, 9 and 8 the nearest of these with a warning (core/SmoothSpecular.h);
// they are resolved at the end of each newmtl, whatever the statements'
// order. Other illum values above 2, d < 1 and Tr > 0 (transparency) are
// warned about since they render as opaque Lambert + Phong.
// Kd, Ks or Tf above 1 is clamped to 1 with a warning (it would create
// energy); negative Kd, Ks, Ke, Tf or Ns, and Ni <= 0, are errors.
// Textures: map_Kd, map_Ke and map_d are read (PNG, JPEG or TGA; paths
// relative to the MTL's folder, backslashes read as slashes; the file name is
// the rest of the line after the options, so it may hold blanks), only for
// materials that faces use. The renderer has no per-pixel texturing yet, so
//   Kd = Kd × the mean of map_Kd, Ke = Ke × the mean of map_Ke, each over the
//     triangles that use the material as their vt show it (TextureMean.h):
//     8-bit values sRGB-decoded, the nearest texel at stratified points,
//     weighted by world area; a triangle without vt counts with the mean
//     over the whole image (one warning per statement). One warning per
//     statement gives the value ("texture map_Kd 'wood.png' averaged to Kd
//     (r, g, b)"). With map_Ke, no Ke or Ke 0 0 0 (what exporters write) is
//     taken as Ke 1 1 1: the map is the emission.
//   map_d cuts out per pixel (Material::alphaMap, for shading and shadows)
//     where its coverage (the alpha channel, or the grey level of an image
//     without one) is below 0.5, on faces with vt; a face without vt is
//     removed when the image's mean coverage is below 0.5, else opaque (one
//     warning counts them).
// Texture options: -o u [v [w]] offsets and -s u [v [w]] scales the texture
// coordinates (vt × s + o; w unused), -clamp on clamps them to the image's
// edge (else the image repeats); the other options of the MTL specification
// (-bm, -blendu, -blendv, -boost, -cc, -imfchan, -mm, -t, -texres, -type) give
// one warning each per MTL file and are ignored. Other texture statements
// (map_Ks, map_Ns, map_Ka, bump, disp, decal, refl, norm) give a warning and
// the constant value is used.
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
// texture that cannot be read or decoded ("scene.mtl:12: map_Kd 'wood.png':
// cannot read: ..."), an unknown texture option or one without its values, a
// -clamp other than on or off, a
// face with fewer than 3 corners, a zero-length vn used by a face, an emitting
// material whose faces are all degenerate, a file without faces (or whose
// faces map_d cuts out entirely), and a crease angle outside [0, 180].
Scene loadObj(const std::string& path, const ObjOptions& options = {});

// Where loadObj's files come from: fills `text` with the whole file at `path`
// and returns true, or returns false when it cannot be opened.
using ObjFileReader = std::function<bool(const std::string& path, std::string& text)>;

// The same, with the OBJ, every MTL library and every texture read through
// `read` rather than from the file system (tests and the fuzzer serve them
// from memory). `read` gets `path` for the OBJ and, for an MTL or a texture,
// the path loadObj would open: relative names joined to the OBJ's folder (an
// MTL's) or the MTL's folder (a texture's), lexically normalised. Errors name
// the same paths and lines as for files.
Scene loadObj(const std::string& path, const ObjOptions& options, const ObjFileReader& read);

}  // namespace ml
