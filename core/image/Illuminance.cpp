#include "Illuminance.h"

#include "core/Error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ml {

LengthUnit parseLengthUnit(const std::string& name) {
    if (name == "mm") return LengthUnit::Millimetre;
    if (name == "cm") return LengthUnit::Centimetre;
    if (name == "m") return LengthUnit::Metre;
    throw InputError(concat("unknown length unit '", name, "' (use mm, cm or m)"));
}

const char* lengthUnitName(LengthUnit unit) {
    switch (unit) {
        case LengthUnit::Millimetre: return "mm";
        case LengthUnit::Centimetre: return "cm";
        case LengthUnit::Metre: return "m";
    }
    return "?";
}

double metresPerUnit(LengthUnit unit) {
    switch (unit) {
        case LengthUnit::Millimetre: return 1e-3;
        case LengthUnit::Centimetre: return 1e-2;
        case LengthUnit::Metre: return 1.0;
    }
    return 1.0;
}

double luxLevelIndex(double lux) {
    if (!(lux > 0)) return -kInf;
    // Decade k and mantissa m ∈ [1, 10): levels 1, 2, 5 at 3k, 3k+1, 3k+2.
    const double k = std::floor(std::log10(lux));
    double m = lux / std::pow(10.0, k);
    if (m < 1) m = 1;  // rounding of log10 just below a power of ten
    double within;
    if (m < 2)
        within = m - 1;
    else if (m < 5)
        within = 1 + (m - 2) / 3;
    else
        within = std::min(2 + (m - 5) / 5, 3.0);
    return 3 * k + within;
}

double luxAtLevel(int index) {
    static const double kMantissa[3] = {1, 2, 5};
    const int k = int(std::floor(index / 3.0));
    return kMantissa[index - 3 * k] * std::pow(10.0, k);
}

std::vector<double> luxLevels(double lo, double hi) {
    std::vector<double> out;
    if (!(lo > 0) || !(hi >= lo)) return out;
    for (int i = int(std::ceil(luxLevelIndex(lo) - 1e-9)); i <= int(std::floor(luxLevelIndex(hi) + 1e-9)); ++i)
        out.push_back(luxAtLevel(i));
    return out;
}

std::string formatLux(double lux) {
    char buf[32];
    if (lux >= 1e6)
        std::snprintf(buf, sizeof buf, "%gM", lux / 1e6);
    else if (lux >= 1e4)
        std::snprintf(buf, sizeof buf, "%gk", lux / 1e3);
    else
        std::snprintf(buf, sizeof buf, "%g", lux);
    return buf;
}

const std::vector<Rgb>& falseColourPalette() {
    static const std::vector<Rgb> palette = {
        {0.05, 0.03, 0.25}, {0.10, 0.15, 0.75}, {0.00, 0.45, 0.95}, {0.00, 0.75, 0.75}, {0.15, 0.80, 0.25},
        {0.65, 0.85, 0.05}, {1.00, 0.80, 0.00}, {1.00, 0.45, 0.00}, {0.85, 0.05, 0.05},
    };
    return palette;
}

Rgb falseColour(double t) {
    const std::vector<Rgb>& p = falseColourPalette();
    const double x = std::clamp(t, 0.0, 1.0) * double(p.size() - 1);
    const size_t i = std::min(size_t(x), p.size() - 2);
    return glm::mix(p[i], p[i + 1], x - double(i));
}

double falseColourPosition(double lux, double lo, double hi) {
    if (!(lux > 0)) return 0;
    return std::clamp((std::log10(lux) - std::log10(lo)) / std::max(std::log10(hi) - std::log10(lo), 1e-12), 0.0, 1.0);
}

std::pair<double, double> autoLuxRange(std::vector<double> lux) {
    lux.erase(std::remove_if(lux.begin(), lux.end(), [](double v) { return !(v > 0) || !std::isfinite(v); }),
              lux.end());
    if (lux.empty()) return {1.0, 1000.0};
    std::sort(lux.begin(), lux.end());
    const double lo = lux[size_t(0.02 * double(lux.size() - 1))];
    const double hi = lux[size_t(0.98 * double(lux.size() - 1))];
    int a = int(std::floor(luxLevelIndex(lo) + 1e-9));
    int b = int(std::ceil(luxLevelIndex(hi) - 1e-9));
    if (b - a < 3) {  // at least a decade: a flat image still gets a readable scale
        const int grow = 3 - (b - a);
        a -= grow / 2;
        b += grow - grow / 2;
    }
    return {luxAtLevel(a), luxAtLevel(b)};
}

}  // namespace ml
