// Illuminance for lighting designers: the scene's length unit, and the
// false-colour scale with its 1-2-5 iso-lux levels. Lux itself comes from
// Photometry.h; the false-colour image and its legend on the CPU from
// FalseColour.h. The compositor's shaders compute the same mapping on the
// GPU (display.frag gets the palette from falseColourPalette()).
//
// Units. Irradiance E = ∫ L cos θ dω integrates radiance (W·sr⁻¹·m⁻²) over
// solid angle, which has no length unit: for a given Ke, the cached
// irradiance in W·m⁻² is the same whether the scene's coordinates are
// millimetres or metres. Lux therefore never depends on the length unit,
// only on the photometry (efficacy and luminance weights). The unit matters
// where a length or an area is shown or used: walking speed, positions, and
// a light's power Φ = π Ke A (A in m² = A in scene units² × metres per unit²).
#pragma once

#include "core/Math.h"

#include <string>
#include <utility>
#include <vector>

namespace ml {

enum class LengthUnit { Millimetre, Centimetre, Metre };
LengthUnit parseLengthUnit(const std::string& name);  // "mm", "cm", "m"; InputError otherwise
const char* lengthUnitName(LengthUnit unit);           // "mm", "cm", "m"
double metresPerUnit(LengthUnit unit);                 // 0.001, 0.01, 1

// The 1-2-5 levels (1, 2, 5, 10, 20, ...) as a continuous index: an integer
// exactly at each level (index 0 at 1 lx, 3 at 10 lx, −3 at 0.1 lx) and
// linear in lux between two levels, so iso-lux lines are where it crosses
// an integer. −inf at 0. display.frag computes the same.
double luxLevelIndex(double lux);
// The lux value of a level index (integer: a 1-2-5 value).
double luxAtLevel(int index);
// The 1-2-5 values in [lo, hi], ascending.
std::vector<double> luxLevels(double lo, double hi);
// "0.5", "20", "1.2k", ... for legends.
std::string formatLux(double lux);

// The false-colour palette, dark blue (low) to red (high): 9 stops spread
// evenly, interpolated linearly in between. Display values (sRGB-encoded,
// shown as they are), so the legend and the image agree.
const std::vector<Rgb>& falseColourPalette();
// The colour at t ∈ [0, 1] (clamped).
Rgb falseColour(double t);
// Where `lux` falls on a log scale from `lo` to `hi` (both > 0), clamped to [0, 1].
double falseColourPosition(double lux, double lo, double hi);

// A range for false colour from an illuminance image's covered pixels
// (value > 0): its 2nd and 98th percentiles, widened to 1-2-5 values and to
// at least one decade. {1, 1000} when nothing is lit.
std::pair<double, double> autoLuxRange(std::vector<double> lux);

}  // namespace ml
