// Textures and their means: the loaders (OBJ/MTL, glTF) decode textures
// (Texture, core/Texture.h) and multiply a material's constant by its
// texture's mean over the triangles that use it (Material::kd, ke: what the
// cache, the light sampler and the bounce count use), and each triangle's
// own mean (Mesh::albedo: the radiance proxy, the bounce count); the
// compositor and the path tracer draw the texture itself. Decoding is
// stb_image's (PNG, JPEG, TGA), kept inside TextureMean.cpp.
#pragma once

#include "core/Math.h"
#include "core/Texture.h"

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace ml {

// Decodes the PNG, JPEG or TGA image in `bytes` into `out` (its size,
// texels and alpha; name, wrap and filter are left as they are). Returns an
// empty string, or stb_image's reason when it cannot ("bad png sig",
// "outofdata"): the caller says which file.
std::string decodeTexture(const unsigned char* bytes, size_t size, Texture& out);

// The texture's mean over one triangle of texture space (its corners' `uv`):
// the centroids of its k² congruent sub-triangles, k about the square root
// of the texels it covers, between 8 and 64.
Rgb footprintMean(const Texture& texture, const std::array<Vec2, 3>& uv);

// The area-weighted mean of a texture over the triangles of a material, as
// they show it: add each triangle with its world area.
class TextureMean {
public:
    explicit TextureMean(const Texture& texture) : texture_(texture) {}

    // A triangle of `area` (world units², >= 0) whose corners have `uv`.
    void add(double area, const std::array<Vec2, 3>& uv) { addValue(area, footprintMean(texture_, uv)); }
    // A triangle without texture coordinates: the mean over the whole image.
    void addWithoutUv(double area) { addValue(area, texture_.imageMean()); }
    // A triangle whose footprint mean (footprintMean) is already known.
    void addValue(double area, const Rgb& value) {
        if (!(area > 0)) return;
        sum_ += area * value;
        weight_ += area;
    }
    // The mean so far; 1 (the constant unchanged) when nothing of positive area was added.
    Rgb mean() const { return weight_ > 0 ? sum_ / weight_ : Rgb(1.0); }

private:

    const Texture& texture_;
    Rgb sum_{0.0};
    double weight_ = 0;
};

// "(0.304, 0.304, 0.304)": how texture warnings give a mean.
std::string rgbText(const Rgb& c);

}  // namespace ml
