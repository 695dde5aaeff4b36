// Tone mapping: linear radiance (ImageRgb) to 8-bit sRGB for PNG output and
// the viewer's display.
//
// Order of operations per pixel: exposure scale, tone operator, clip to
// [0, 1], sRGB OETF, round to 8 bits.
#pragma once

#include "core/image/Image.h"

#include <cstdint>
#include <string>
#include <vector>

namespace ml {

enum class ToneOperator {
    // Narkowicz's fit of the ACES RRT+ODT filmic curve ("ACES Filmic Tone
    // Mapping Curve", 2016), per channel; pre-exposed so 1 maps to about 0.8.
    Aces,
    // Reinhard et al. 2002 global operator L / (1 + L) on luminance, with
    // chroma kept (every channel scaled by 1 / (1 + L)).
    Reinhard,
    // Exposure and clip only: for checking linear values by eye.
    Clamp,
};

// "aces", "reinhard" or "clamp"; anything else is an InputError listing them.
ToneOperator parseToneOperator(const std::string& name);
// The name parseToneOperator accepts.
const char* toneOperatorName(ToneOperator op);

struct ToneMapSettings {
    // Stops added on top of the automatic scale: the image is multiplied by 2^exposureEV.
    double exposureEV = 0.0;
    // Scales the image so its log-average luminance maps to middle grey 0.18
    // (the "key" of Reinhard et al. 2002, "Photographic Tone Reproduction for
    // Digital Images"); off, the scale is 1 (before exposureEV).
    bool autoExposure = true;
    ToneOperator op = ToneOperator::Aces;
};

// The factor that maps the log-average luminance of `image` to 0.18:
// 0.18 / exp(mean(ln L)) over the pixels with luminance at least 1e-4 of the
// 99th percentile (black and near-black pixels carry no exposure
// information: ln 0 would make the mean -inf, and an unlit ceiling at 1e-12
// would wash the lit part out); 1 when every pixel is black. All values
// must be finite.
double autoExposureScale(const ImageRgb& image);

// The sRGB OETF (IEC 61966-2-1: linear below 0.0031308, then a 1/2.4 power),
// not a plain 2.2 gamma. `linear` is clipped to [0, 1]; returns [0, 1].
double srgbOetf(double linear);
// srgbOetf quantized to 8 bits, rounded to nearest.
std::uint8_t toSrgb8(double linear);

// Tone maps `linear` to 8-bit sRGB: 3 * width * height bytes, RGB interleaved,
// row 0 at the top (ready for writeImage8). Every value must be finite: a NaN
// or infinity is a renderer bug, reported as std::logic_error with its pixel.
// Negative values (possible after filtering) count as 0.
std::vector<std::uint8_t> toneMap(const ImageRgb& linear, const ToneMapSettings& settings);

}  // namespace ml
