// Textures reduced to means: the loaders (OBJ/MTL, glTF) multiply a
// material's constant by its texture's mean over the triangles that use it,
// since the renderer has no per-pixel texturing yet. Decoding is stb_image's
// (PNG, JPEG, TGA), kept inside TextureMean.cpp.
#pragma once

#include "core/Math.h"

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace ml {

// What a texture coordinate outside [0, 1] reads (glTF's sampler wrap modes;
// MTL `-clamp on` is ClampToEdge).
enum class TextureWrap { Repeat, MirroredRepeat, ClampToEdge };

// A decoded image, 8-bit RGBA whatever the file holds, and how it is looked
// up. Texture coordinates follow glTF: (0, 0) is the top-left corner of the
// first row, u to the right, v down (an OBJ `vt` has v up: 1 − v here).
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

    // Linear RGB at `uv`: 8-bit values are sRGB-encoded (IEC 61966-2-1), as
    // glTF says of colour textures and as OBJ exporters write them.
    Rgb sample(Vec2 uv) const;
    // Coverage in [0, 1] at `uv`: the alpha channel, or for an image without
    // one its grey level (the mean of R, G and B, not decoded: MTL `map_d`
    // images are often grey masks).
    double coverage(Vec2 uv) const;
    // The means over every texel, for surfaces without texture coordinates.
    Rgb imageMean() const;
    double imageCoverage() const;
};

// Decodes the PNG, JPEG or TGA image in `bytes` into `out` (its size,
// texels and alpha; name, wrap and filter are left as they are). Returns an
// empty string, or stb_image's reason when it cannot ("bad png sig",
// "outofdata"): the caller says which file.
std::string decodeTexture(const unsigned char* bytes, size_t size, Texture& out);

// The texture's mean over one triangle of texture space (its corners' `uv`):
// the centroids of its k² congruent sub-triangles, k about the square root
// of the texels it covers, between 8 and 64.
Rgb footprintMean(const Texture& texture, const std::array<Vec2, 3>& uv);
double footprintCoverage(const Texture& texture, const std::array<Vec2, 3>& uv);

// The area-weighted mean of a texture over the triangles of a material, as
// they show it: add each triangle with its world area.
class TextureMean {
public:
    explicit TextureMean(const Texture& texture) : texture_(texture) {}

    // A triangle of `area` (world units², >= 0) whose corners have `uv`.
    void add(double area, const std::array<Vec2, 3>& uv) { addValue(area, footprintMean(texture_, uv)); }
    // A triangle without texture coordinates: the mean over the whole image.
    void addWithoutUv(double area) { addValue(area, texture_.imageMean()); }
    // The mean so far; 1 (the constant unchanged) when nothing of positive area was added.
    Rgb mean() const { return weight_ > 0 ? sum_ / weight_ : Rgb(1.0); }

private:
    void addValue(double area, const Rgb& value) {
        if (!(area > 0)) return;
        sum_ += area * value;
        weight_ += area;
    }

    const Texture& texture_;
    Rgb sum_{0.0};
    double weight_ = 0;
};

// "(0.304, 0.304, 0.304)": how texture warnings give a mean.
std::string rgbText(const Rgb& c);

}  // namespace ml
