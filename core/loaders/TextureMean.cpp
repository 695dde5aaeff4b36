// stb_image is compiled here, as static functions: the only decoder the
// loaders use, for the few textures they average.
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#define STBI_ONLY_TGA
#include <stb/stb_image.h>

#include "TextureMean.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>

namespace ml {

namespace {

// A texture's mean over a triangle uses k² stratified points, about one per
// texel the triangle covers, with k within these bounds. With at most 32 the
// back rooms' light-grid texture came out 4% off its mean; 64 costs 0.5 s
// more there (1.1 s in all for 9,185 triangles and five large textures).
constexpr int kMinTextureSubdivision = 8;
constexpr int kMaxTextureSubdivision = 64;

// The sRGB EOTF (IEC 61966-2-1) for each 8-bit value.
const std::array<double, 256>& srgbToLinear() {
    static const std::array<double, 256> table = [] {
        std::array<double, 256> t{};
        for (int i = 0; i < 256; ++i) {
            const double e = i / 255.0;
            t[i] = e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
        }
        return t;
    }();
    return table;
}

// Reduced to one period of every wrap mode (2 covers mirroring), so texel
// indices stay small for any finite coordinate.
double wrapped(double u, TextureWrap mode) {
    if (mode == TextureWrap::ClampToEdge) return std::clamp(u, -1.0, 2.0);
    return u - 2 * std::floor(u / 2);
}

// `i` is within a texel of [0, 2·size] (wrapped() made it so): a few steps
// of one period replace the slower integer division.
long long wrapIndex(long long i, long long size, TextureWrap mode) {
    if (mode == TextureWrap::ClampToEdge) return std::clamp(i, 0LL, size - 1);
    const bool mirrored = mode == TextureWrap::MirroredRepeat;
    const long long period = mirrored ? 2 * size : size;
    while (i < 0) i += period;
    while (i >= period) i -= period;
    return mirrored && i >= size ? period - 1 - i : i;
}

// The texel value `value(bytes of one texel)` at `uv`, nearest or bilinear.
template <typename Value>
auto lookUp(const Texture& t, Vec2 uv, const Value& value) {
    auto texel = [&](double x, double y) {
        const long long i = wrapIndex(static_cast<long long>(x), t.width, t.wrapS);
        const long long j = wrapIndex(static_cast<long long>(y), t.height, t.wrapT);
        return value(&t.rgba[4 * (static_cast<size_t>(j) * t.width + i)]);
    };
    const double x = wrapped(uv.x, t.wrapS) * t.width;
    const double y = wrapped(uv.y, t.wrapT) * t.height;
    if (t.nearest) return texel(std::floor(x), std::floor(y));
    const double x0 = std::floor(x - 0.5), y0 = std::floor(y - 0.5);
    const double fx = x - 0.5 - x0, fy = y - 0.5 - y0;
    return (1 - fy) * ((1 - fx) * texel(x0, y0) + fx * texel(x0 + 1, y0)) +
           fy * ((1 - fx) * texel(x0, y0 + 1) + fx * texel(x0 + 1, y0 + 1));
}

Rgb linearRgb(const unsigned char* p) {
    const auto& lin = srgbToLinear();
    return Rgb(lin[p[0]], lin[p[1]], lin[p[2]]);
}

// Alpha, or the grey level of an image without alpha (see Texture::coverage).
double coverageOf(const Texture& t, const unsigned char* p) {
    return t.hasAlpha ? p[3] / 255.0 : (p[0] + p[1] + p[2]) / (3 * 255.0);
}

// The mean of `sample(uv)` over the triangle: per triangle, the centroids of
// its k² congruent sub-triangles.
template <typename Sample>
auto footprint(const Texture& t, const std::array<Vec2, 3>& uv, const Sample& sample) {
    const Vec2 a = uv[0], e1 = uv[1] - a, e2 = uv[2] - a;
    const double uvTexels = 0.5 * std::abs(e1.x * e2.y - e1.y * e2.x) * t.width * t.height;
    const int k = static_cast<int>(std::clamp(std::ceil(std::sqrt(uvTexels)), double(kMinTextureSubdivision),
                                              double(kMaxTextureSubdivision)));
    decltype(sample(a)) sum(0.0);
    for (int i = 0; i < k; ++i)
        for (int j = 0; i + j < k; ++j) {
            sum += sample(a + ((i + 1.0 / 3) * e1 + (j + 1.0 / 3) * e2) / double(k));
            if (i + j + 1 < k) sum += sample(a + ((i + 2.0 / 3) * e1 + (j + 2.0 / 3) * e2) / double(k));
        }
    return sum / double(k * k);
}

// The mean of `value` over every texel.
template <typename Value>
auto wholeImage(const Texture& t, const Value& value) {
    decltype(value(t.rgba.data())) sum(0.0);
    for (size_t i = 0; i < t.rgba.size(); i += 4) sum += value(&t.rgba[i]);
    return sum / (double(t.width) * t.height);
}

}  // namespace

Rgb Texture::sample(Vec2 uv) const { return lookUp(*this, uv, linearRgb); }

double Texture::coverage(Vec2 uv) const {
    return lookUp(*this, uv, [this](const unsigned char* p) { return coverageOf(*this, p); });
}

Rgb Texture::imageMean() const { return wholeImage(*this, linearRgb); }

double Texture::imageCoverage() const {
    return wholeImage(*this, [this](const unsigned char* p) { return coverageOf(*this, p); });
}

std::string decodeTexture(const unsigned char* bytes, size_t size, Texture& out) {
    if (size > INT_MAX) return "larger than 2 GiB";
    int width = 0, height = 0, channels = 0;
    unsigned char* pixels = stbi_load_from_memory(bytes, static_cast<int>(size), &width, &height, &channels, 4);
    if (!pixels) {
        // stb leaves no reason for some failures (found by fuzz_gltf_loader:
        // an empty reason read as success gave a texture of no texels).
        const char* why = stbi_failure_reason();
        return why && *why ? why : "not an image stb_image can decode";
    }
    if (width <= 0 || height <= 0) {  // no texel to look up
        stbi_image_free(pixels);
        return "an image of " + std::to_string(width) + " x " + std::to_string(height) + " texels";
    }
    out.width = width;
    out.height = height;
    out.rgba.assign(pixels, pixels + size_t(4) * width * height);
    stbi_image_free(pixels);
    out.hasAlpha = channels == 2 || channels == 4;
    out.minAlpha = 1;
    for (size_t i = 3; i < out.rgba.size(); i += 4) out.minAlpha = std::min(out.minAlpha, out.rgba[i] / 255.0);
    return {};
}

Rgb footprintMean(const Texture& texture, const std::array<Vec2, 3>& uv) {
    return footprint(texture, uv, [&](Vec2 p) { return texture.sample(p); });
}

std::string rgbText(const Rgb& c) {
    char text[96];
    std::snprintf(text, sizeof text, "(%.3g, %.3g, %.3g)", c.r, c.g, c.b);
    return text;
}

}  // namespace ml
