// glTF 2.0 loading: .gltf (JSON with .bin buffers and image files, or data
// URIs) and .glb.
//
// The parser is tinygltf (Debian's libtinygltf-dev, one header, used inside
// GltfLoader.cpp only) rather than assimp: it reads glTF only and keeps every
// field we need, extensions included (as JSON values: emissive strength,
// punctual lights), where assimp converts every format to its own scene model
// and is a large dependency for one format.
#pragma once

#include "core/Scene.h"

#include <string>
#include <vector>

namespace ml {

struct GltfOptions {
    // Multiplies every emitted radiance. glTF gives emission in unspecified
    // "nits-like" units; the loader takes emissiveFactor × emissiveTexture ×
    // KHR_materials_emissive_strength as radiance in W·sr⁻¹·m⁻², times this.
    // >= 0 and finite; typical 1.
    double emissionScale = 1;
    // Primitives without NORMAL, as ObjOptions::creaseAngleDegrees: faces
    // whose normals differ by more than this keep separate vertices; degrees
    // in [0, 180], typical 30.
    double creaseAngleDegrees = 30;
};

// Reads a glTF 2.0 file (.glb when it starts with the binary header, else
// JSON) into a finalized Scene, in metres as glTF defines (Scene::name = path).
//
// Geometry: the node hierarchy of the default scene (scene 0 without one; all
// root nodes when the file has no scenes), TRS and matrix transforms composed
// parent to child. One Mesh per primitive and node instance, named after the
// glTF mesh ("name#k" for its k-th primitive when it has several). Positions
// go through the world matrix, normals through its inverse transpose; a
// mirroring transform (negative determinant) swaps the winding so that
// counter-clockwise stays the front face. Triangles, strips and fans, indexed
// or not; points and lines are skipped with one warning. Indices u8/u16/u32;
// POSITION and NORMAL float; TEXCOORD_n float or normalized u8/u16; sparse
// accessors and byteStride are supported. A primitive without NORMAL (or with
// a zero NORMAL, or under a singular transform) gets computeShadingNormals with
// options.creaseAngleDegrees. Degenerate triangles are dropped with one
// counted warning. Skins, morph targets and COLOR_0 are ignored with a warning.
//
// Materials (pbrMetallicRoughness), one Meshlight material per glTF material
// that kept triangles use; primitives without one get "default" (Kd 0.8):
//   Kd = baseColorFactor.rgb × the mean of baseColorTexture, clamped to [0, 1].
//   Ke = emissiveFactor × the mean of emissiveTexture × emissiveStrength
//        (KHR_materials_emissive_strength, default 1) × options.emissionScale.
//   Textures are reduced to ONE MEAN PER MATERIAL for now: the compositor has
//   no per-pixel texturing yet. The mean is over the texture as the material's
//   triangles show it: sRGB decoded to linear, sampled at stratified points of
//   each triangle (bilinear, or nearest when magFilter says so, with the
//   sampler's wrap modes), weighted by the triangle's world area. Each averaged
//   texture gives a warning "texture <name> averaged to Kd (r, g, b)".
//   doubleSided emitters also emit from their back: their emissive triangles
//   are added again, reversed, as a separate Mesh "<mesh> (back)" (so that
//   front and back make separate, planar lights). Meshlight shows both sides of
//   every surface, so doubleSided changes nothing else.
//   A mirror (core/SmoothSpecular.h): metallicFactor 1, roughnessFactor <=
//   0.05, no metallicRoughnessTexture; F0 = the base colour (Schlick), Kd 0.
//   Glass: KHR_materials_transmission with transmissionFactor > 0; index
//   KHR_materials_ior (default 1.5), filter transmissionFactor × base colour,
//   Kd × (1 − transmissionFactor).
//   Otherwise rendered as diffuse, with one warning per material naming what
//   is left out: metallicFactor >= 0.5 (rough metals), roughness of glass,
//   normalTexture, and material extensions other than those above
//   (KHR_materials_specular, _clearcoat, ...). alphaMode MASK with a baseColorFactor alpha below
//   alphaCutoff removes the material's triangles (warning); MASK with a
//   baseColorTexture whose alpha takes it below the cut-off somewhere is a
//   cut-out per pixel (Material::alphaMap: the factor's alpha × the
//   texture's), for shading and for shadows; BLEND is rendered opaque (warning).
// Camera: the first node in traversal order with a perspective camera gives
//   Scene::camera (its world position, its -Z as the view direction, its +Y as
//   up, yfov); orthographic cameras are ignored with a warning.
// KHR_lights_punctual lights are not rendered (area lights only so far): one
//   warning per light. A scene without emissive surfaces loads with the warning
//   "no emissive surface: the image will be black".
// Unknown optional extensions give a warning; unknown required ones are errors.
//
// Throws InputError with the file and the JSON path of the problem
// ("scene.gltf: meshes[0].primitives[1].indices (accessors[3]): index 9 is out
// of range (4 vertices)") for: a file that cannot be read, JSON or glTF that
// tinygltf rejects (its message), a missing buffer or image file, an
// undecodable image, a reference to an element that does not exist, an
// accessor whose type or component type the attribute does not allow, an
// accessor or buffer view outside its buffer, an index out of range of the
// vertex count, non-finite positions, normals, texture coordinates or
// transforms, a node reached twice (a cycle or two parents), an invalid camera,
// a negative emissive value, an unknown alphaMode, an unsupported required
// extension, a file without triangles, and options out of range.
Scene loadGltf(const std::string& path, const GltfOptions& options = {});

// loadGltf on a .gltf or .glb file's bytes held in memory, `name` standing
// for its path in messages and Scene::name. Nothing is read from disk: a
// URI naming a file (a buffer, an image, a photometric file) is an
// InputError "not found"; data URIs and a .glb's own buffer are read. The
// fuzz target's entry (tests/fuzz/fuzz_gltf_loader.cpp).
Scene loadGltfFromMemory(const std::string& name, const std::vector<unsigned char>& bytes,
                         const GltfOptions& options = {});

}  // namespace ml
