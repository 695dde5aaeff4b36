// Illuminance in false colour on the CPU: what the viewer shows in lux mode
// (viewer/compositor/common_display.glsl, QUANTITY 2) and its legend (the
// viewer's panel, viewer/window/Ui.cpp), for `render --quantity lux` to a
// PNG. The scale, palette and levels are Illuminance.h's, shared with the
// GPU; the legend's layout (which levels are labelled, the bar's height) is
// decided here for both.
#pragma once

#include "core/image/Image.h"

#include <cstdint>
#include <string>
#include <vector>

namespace ml {

// An illuminance image as the compositor resolves it to pixels.
struct LuxImage {
    int width = 0, height = 0;     // pixels
    std::vector<float> lux;        // lx: the mean over the pixel's sub-pixels that see a surface; 0 where none does
    std::vector<float> coverage;   // the share of the pixel's sub-pixels that see a surface, [0, 1]
    // Row 0 at the top.
    size_t index(int x, int y) const { return size_t(y) * size_t(width) + size_t(x); }
};

// The display colour off every surface (display.frag's background).
constexpr double kFalseColourBackground = 0.08;

// The viewer's lux display, pixel for pixel: falseColour() of where the
// pixel's lux falls on a log scale from `lo` to `hi` where a surface is
// seen (kFalseColourBackground grey elsewhere); with `contours`, black
// iso-lux lines about a pixel wide where the 1-2-5 level index crosses an
// integer, only inside surfaces (coverage 1) and where the index moves by
// less than a level from a pixel to the next, as fwidth() does on the GPU
// (the neighbours of a 2×2 quad). Display values, sRGB-encoded; row 0 at
// the top.
ImageRgb falseColourImage(const LuxImage& image, double lo, double hi, bool contours);

// One 1-2-5 level of the legend.
struct LegendTick {
    double lux = 0;
    double position = 0;    // on the bar: 0 at the top (the high end, `hi`), 1 at the bottom (`lo`)
    bool labelled = false;  // its value is written beside it
};
// The legend's levels in [lo, hi]: every one is labelled when they fit
// (10% spare) in a bar `barHeight` tall with text lines `lineHeight` tall
// (pixels), else only the decades (1, 10, 100 ...).
std::vector<LegendTick> legendTicks(double lo, double hi, double barHeight, double lineHeight);
// The colour bar's height in a view `viewHeight` pixels tall: 45% of it,
// within 120..360 pixels.
double legendBarHeight(double viewHeight);

// Draws the legend into `image` (display values, as falseColourImage
// makes) at its top-right corner, laid out as the viewer's panel: a dark
// panel, the colour bar (top: `hi`), a tick and a label at each
// legendTicks() level, and `caption` under the bar. Labels use a built-in
// 5×7 pixel font of digits, '.', '-', '+', ' ' and the letters of formatLux
// and of "lx"; other characters are left blank. Draws nothing in an image
// too small to hold a bar of 40 pixels.
void drawLuxLegend(ImageRgb& image, double lo, double hi, const std::string& caption);

// Display values (sRGB-encoded, as falseColourImage gives) to 8 bits per
// channel, rounded to nearest: 3 × width × height bytes for writeImage8.
std::vector<std::uint8_t> displayBytes(const ImageRgb& display);

}  // namespace ml
