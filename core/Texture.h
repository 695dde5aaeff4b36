// Images a material draws per pixel (base colour, emission): decoded once by
// a loader, shared read-only by the scene, the compositor (which uploads them
// with mipmaps) and the path tracer (which samples them at a hit). Decoding
// and the CPU look-ups are in loaders/TextureMean.cpp, with stb_image.
#pragma once

#include "Math.h"

#include <memory>
#include <string>
#include <vector>

namespace ml {

// What a texture coordinate outside [0, 1] reads (glTF's sampler wrap modes;
// MTL `-clamp on` is ClampToEdge).
enum class TextureWrap { Repeat, MirroredRepeat, ClampToEdge };

// A decoded image, 8-bit RGBA whatever the file holds, and how it is looked
// up. Texture coordinates follow glTF: (0, 0) is the top-left corner of the
// first row, u to the right, v down (an OBJ `vt` has v up: 1 − v here).
// RGB is sRGB-encoded (IEC 61966-2-1), as glTF says of colour textures and
// as OBJ exporters write them: sample() decodes each texel to linear before
// it interpolates, as GL_SRGB8_ALPHA8 does on the GPU.
struct Texture {
    std::string name;                 // for messages: a file name or a glTF field
    int width = 0;                    // texels, > 0 once decoded
    int height = 0;                   // texels, > 0 once decoded
    std::vector<unsigned char> rgba;  // 4 bytes a texel, top row first
    bool hasAlpha = false;            // the file has an alpha channel (grey + alpha or RGBA)
    double minAlpha = 1;              // the smallest alpha, in [0, 1] (1 without an alpha channel)
    TextureWrap wrapS = TextureWrap::Repeat;  // along u
    TextureWrap wrapT = TextureWrap::Repeat;  // along v
    bool nearest = false;             // the nearest texel, else bilinear between the four nearest

    // Linear RGB at `uv` (texture space, after TextureMap::lookup).
    Rgb sample(Vec2 uv) const;
    // Coverage in [0, 1] at `uv`: the alpha channel, or for an image without
    // one its grey level (the mean of R, G and B, not decoded: MTL `map_d`
    // images are often grey masks).
    double coverage(Vec2 uv) const;
    // The means over every texel, for surfaces without texture coordinates.
    Rgb imageMean() const;
    double imageCoverage() const;
};

// A material's use of a texture: value(uv) = factor × image(uv·scale + offset),
// uv being the mesh's per-vertex coordinate (Mesh::texcoords, glTF's
// convention). The transform holds what the OBJ loader reads from `-s` and
// `-o` (and the flip of an OBJ vt's v); glTF's is the identity.
struct TextureMap {
    std::shared_ptr<const Texture> image;  // null: the material is not textured here
    Rgb factor{1.0};                       // glTF's baseColorFactor / emissive factor, MTL's Kd / Ke
    Vec2 scale{1.0};
    Vec2 offset{0.0};

    explicit operator bool() const { return image != nullptr; }
    Vec2 lookup(Vec2 uv) const { return uv * scale + offset; }
    // factor × the image at the mesh coordinate `uv` (linear RGB).
    Rgb value(Vec2 uv) const { return factor * image->sample(lookup(uv)); }
};

}  // namespace ml
