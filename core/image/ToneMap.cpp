#include "ToneMap.h"

#include <algorithm>
#include <cmath>
#include <vector>
#include <stdexcept>

namespace ml {

namespace {

constexpr ToneOperator kOperators[] = {ToneOperator::Aces, ToneOperator::Reinhard,
                                       ToneOperator::Clamp};
constexpr double kMiddleGrey = 0.18;

double clamp01(double v) { return std::clamp(v, 0.0, 1.0); }

double acesNarkowicz(double x) {
    return clamp01(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14));
}

void assertFinite(const ImageRgb& image) {
    ML_ASSERT(image.data.size() == 3 * image.pixelCount(), image.width, "x", image.height,
              " image with ", image.data.size(), " floats");
    for (std::size_t i = 0; i < image.data.size(); ++i) {
        const std::size_t pixel = i / 3;
        ML_ASSERT(std::isfinite(image.data[i]), "at pixel (", pixel % std::size_t(image.width),
                  ", ", pixel / std::size_t(image.width), "): ", image.data[i]);
    }
}

// autoExposureScale without the finiteness scan, for callers that did it.
double autoExposureScaleOfFinite(const ImageRgb& image) {
    std::vector<double> lum;
    lum.reserve(image.pixelCount());
    for (std::size_t i = 0; i < image.data.size(); i += 3) {
        const double l = luminance(Rgb(image.data[i], image.data[i + 1], image.data[i + 2]));
        if (l > 0.0) lum.push_back(l);
    }
    if (lum.empty()) return 1.0;
    // Pixels darker than 1e-4 of the 99th percentile carry no exposure
    // information either: an unlit ceiling holding 1e-12 of rounding would
    // otherwise drag the log average down by orders of magnitude and wash
    // the lit part of the frame out. The percentile, not the maximum, so a
    // visible emitter does not raise the cut.
    std::vector<double> sorted = lum;
    const std::size_t k = std::min(sorted.size() - 1, std::size_t(0.99 * double(sorted.size())));
    std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(k), sorted.end());
    const double floor = 1e-4 * sorted[k];
    double sumLog = 0.0;
    std::size_t count = 0;
    for (double l : lum)
        if (l >= floor) {
            sumLog += std::log(l);
            ++count;
        }
    return count == 0 ? 1.0 : kMiddleGrey / std::exp(sumLog / double(count));
}

}  // namespace

ToneOperator parseToneOperator(const std::string& name) {
    for (ToneOperator op : kOperators)
        if (name == toneOperatorName(op)) return op;
    throw InputError(concat("unknown tone operator '", name, "' (use aces, reinhard or clamp)"));
}

const char* toneOperatorName(ToneOperator op) {
    switch (op) {
        case ToneOperator::Aces: return "aces";
        case ToneOperator::Reinhard: return "reinhard";
        case ToneOperator::Clamp: return "clamp";
    }
    throw std::logic_error(concat("unknown ToneOperator ", int(op)));
}

double autoExposureScale(const ImageRgb& image) {
    assertFinite(image);
    return autoExposureScaleOfFinite(image);
}

double srgbOetf(double linear) {
    const double v = clamp01(linear);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

std::uint8_t toSrgb8(double linear) {
    return std::uint8_t(std::lround(srgbOetf(linear) * 255.0));
}

std::vector<std::uint8_t> toneMap(const ImageRgb& linear, const ToneMapSettings& settings) {
    assertFinite(linear);
    const double scale = (settings.autoExposure ? autoExposureScaleOfFinite(linear) : 1.0) *
                         std::exp2(settings.exposureEV);

    std::vector<std::uint8_t> out(linear.data.size());
    for (std::size_t i = 0; i < linear.data.size(); i += 3) {
        Rgb c = glm::max(Rgb(linear.data[i], linear.data[i + 1], linear.data[i + 2]) * scale,
                         Rgb(0.0));
        switch (settings.op) {
            case ToneOperator::Aces:
                c = Rgb(acesNarkowicz(c.r), acesNarkowicz(c.g), acesNarkowicz(c.b));
                break;
            case ToneOperator::Reinhard:
                // Saturated colours can still exceed 1 in one channel; toSrgb8 clips it.
                c /= 1.0 + luminance(c);
                break;
            case ToneOperator::Clamp:
                break;
        }
        out[i] = toSrgb8(c.r);
        out[i + 1] = toSrgb8(c.g);
        out[i + 2] = toSrgb8(c.b);
    }
    return out;
}

}  // namespace ml
