#include "FalseColour.h"

#include "Illuminance.h"

#include <algorithm>
#include <cmath>

namespace ml {

namespace {

// The level index as display.frag takes it: −60 (far below any level) where
// nothing is lit, so no line runs along a silhouette.
double contourIndex(double lux) { return lux > 0 ? luxLevelIndex(lux) : -60.0; }

// The legend's text: 5×7 glyphs, a row a string, '#' lit.
struct Glyph {
    char c;
    const char* rows[7];
};
const Glyph kGlyphs[] = {
    {'0', {" ### ", "#   #", "#  ##", "# # #", "##  #", "#   #", " ### "}},
    {'1', {"  #  ", " ##  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "}},
    {'2', {" ### ", "#   #", "    #", "   # ", "  #  ", " #   ", "#####"}},
    {'3', {"#####", "   # ", "  #  ", "   # ", "    #", "#   #", " ### "}},
    {'4', {"   # ", "  ## ", " # # ", "#  # ", "#####", "   # ", "   # "}},
    {'5', {"#####", "#    ", "#### ", "    #", "    #", "#   #", " ### "}},
    {'6', {"  ## ", " #   ", "#    ", "#### ", "#   #", "#   #", " ### "}},
    {'7', {"#####", "    #", "   # ", "  #  ", " #   ", " #   ", " #   "}},
    {'8', {" ### ", "#   #", "#   #", " ### ", "#   #", "#   #", " ### "}},
    {'9', {" ### ", "#   #", "#   #", " ####", "    #", "   # ", " ##  "}},
    {'.', {"     ", "     ", "     ", "     ", "     ", " ##  ", " ##  "}},
    {'-', {"     ", "     ", "     ", "#####", "     ", "     ", "     "}},
    {'+', {"     ", "  #  ", "  #  ", "#####", "  #  ", "  #  ", "     "}},
    {'k', {"#    ", "#    ", "#  # ", "# #  ", "##   ", "# #  ", "#  # "}},
    {'M', {"#   #", "## ##", "# # #", "# # #", "#   #", "#   #", "#   #"}},
    {'e', {"     ", "     ", " ### ", "#   #", "#####", "#    ", " ### "}},
    {'l', {" ##  ", "  #  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "}},
    {'x', {"     ", "     ", "#   #", " # # ", "  #  ", " # # ", "#   #"}},
};

class Canvas {
public:
    Canvas(ImageRgb& image, int scale) : image_(image), scale_(scale) {}
    int advance() const { return 6 * scale_; }
    int lineHeight() const { return 9 * scale_; }
    int textWidth(const std::string& s) const { return int(s.size()) * advance() - scale_; }

    void fill(int x0, int y0, int x1, int y1, const Rgb& c, double alpha = 1) {
        for (int y = std::max(y0, 0); y < std::min(y1, image_.height); ++y)
            for (int x = std::max(x0, 0); x < std::min(x1, image_.width); ++x)
                image_.set(x, y, glm::mix(image_.at(x, y), c, alpha));
    }
    // `s` with its top-left corner at (x, y).
    void text(int x, int y, const std::string& s, const Rgb& c) {
        for (char ch : s) {
            for (const Glyph& g : kGlyphs) {
                if (g.c != ch) continue;
                for (int row = 0; row < 7; ++row)
                    for (int col = 0; col < 5; ++col)
                        if (g.rows[row][col] == '#')
                            fill(x + col * scale_, y + row * scale_, x + (col + 1) * scale_,
                                 y + (row + 1) * scale_, c);
            }
            x += advance();
        }
    }

private:
    ImageRgb& image_;
    int scale_;
};

}  // namespace

ImageRgb falseColourImage(const LuxImage& image, double lo, double hi, bool contours) {
    ML_ASSERT(image.lux.size() == size_t(image.width) * size_t(image.height) &&
                  image.coverage.size() == image.lux.size(),
              image.width, "x", image.height, " lux image with ", image.lux.size(), " values");
    ImageRgb out(image.width, image.height);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const size_t i = image.index(x, y);
            const double lux = image.lux[i], coverage = image.coverage[i];
            Rgb c = coverage > 0 ? falseColour(falseColourPosition(lux, lo, hi)) : Rgb(kFalseColourBackground);
            if (contours && coverage >= 1) {
                // fwidth(): |d/dx| + |d/dy| within the pixel's 2×2 quad, whose
                // rows GL counts from the bottom.
                const int px = x ^ 1;
                const int py = image.height - 1 - ((image.height - 1 - y) ^ 1);
                const double index = contourIndex(lux);
                const double dx =
                    px < image.width ? std::abs(contourIndex(image.lux[image.index(px, y)]) - index) : 0.0;
                const double dy =
                    py >= 0 && py < image.height ? std::abs(contourIndex(image.lux[image.index(x, py)]) - index) : 0.0;
                const double width = dx + dy;
                const double d = std::abs(index + 0.5 - std::floor(index + 0.5) - 0.5) / std::max(width, 1e-6);
                if (width < 1) c *= std::clamp(d, 0.0, 1.0);
            }
            out.set(x, y, c);
        }
    return out;
}

double legendBarHeight(double viewHeight) { return std::clamp(viewHeight * 0.45, 120.0, 360.0); }

std::vector<LegendTick> legendTicks(double lo, double hi, double barHeight, double lineHeight) {
    const std::vector<double> levels = luxLevels(lo, hi);
    const bool all = double(levels.size()) * lineHeight * 1.1 < barHeight;
    std::vector<LegendTick> ticks;
    for (double lux : levels) {
        const bool decade = std::abs(std::fmod(luxLevelIndex(lux), 3.0)) < 1e-6;
        ticks.push_back({lux, 1.0 - falseColourPosition(lux, lo, hi), all || decade});
    }
    return ticks;
}

void drawLuxLegend(ImageRgb& image, double lo, double hi, const std::string& caption) {
    Canvas canvas(image, image.height >= 480 ? 2 : 1);  // text about as tall as the viewer's (13 px) from 480 px up
    const int margin = 10, barWidth = 22, tick = 6, gap = 9;
    const int lh = canvas.lineHeight(), pad = std::max(8, lh / 2 + 2);
    const int barHeight =
        int(std::min(legendBarHeight(image.height), double(image.height - 2 * margin - 2 * pad - lh - 4)));
    if (barHeight < 40) return;
    const std::vector<LegendTick> ticks = legendTicks(lo, hi, barHeight, lh);
    int labelWidth = 0;
    for (const LegendTick& t : ticks)
        if (t.labelled) labelWidth = std::max(labelWidth, canvas.textWidth(formatLux(t.lux)));
    const int width = 2 * pad + std::max(barWidth + gap + labelWidth, canvas.textWidth(caption));
    if (width > image.width - 2 * margin) return;
    const int x0 = image.width - margin - width, y0 = margin;
    const int barX = x0 + pad, barY = y0 + pad;
    canvas.fill(x0, y0, x0 + width, barY + barHeight + 4 + lh + pad, Rgb(0.06), 0.75);
    for (int row = 0; row < barHeight; ++row)
        canvas.fill(barX, barY + row, barX + barWidth, barY + row + 1,
                    falseColour(1.0 - (row + 0.5) / double(barHeight)));
    const Rgb white(1.0);
    for (const LegendTick& t : ticks) {
        if (!t.labelled) continue;
        const int y = barY + int(std::lround(t.position * barHeight));
        const int thickness = lh / 9;
        canvas.fill(barX + barWidth, y - thickness / 2, barX + barWidth + tick, y - thickness / 2 + thickness, white);
        canvas.text(barX + barWidth + gap, y - 7 * thickness / 2, formatLux(t.lux), white);
    }
    canvas.text(barX, barY + barHeight + 4, caption, white);
}

std::vector<std::uint8_t> displayBytes(const ImageRgb& display) {
    std::vector<std::uint8_t> bytes(display.data.size());
    for (size_t i = 0; i < bytes.size(); ++i)
        bytes[i] = std::uint8_t(std::lround(std::clamp(double(display.data[i]), 0.0, 1.0) * 255.0));
    return bytes;
}

}  // namespace ml
