// Photometry: radiometric RGB (W per channel) to photometric quantities,
// the one place lux is computed (probe's lux columns, render --quantity lux,
// the viewer's lux meter, false colour and lumens).
//
// A photometric quantity is the luminous efficacy K (lm/W) times the
// luminance weights w applied to the RGB radiometric one:
//   illuminance E_v = K (w_r E_r + w_g E_g + w_b E_b)   lx from W·m⁻²
//   luminous flux Φ_v = K (w · Φ)                      lm from W
// Two conventions, chosen by name (--photometry):
//   radiance (default): K = 179 lm/W, w = (0.265, 0.670, 0.065): what
//     RADIANCE computes (rtrace -I piped to rcalc '179*(.265*$1+.67*$2+.065*$3)',
//     its WHTEFFICACY and the luminance of its standard primaries), so
//     Meshlight's lux and RADIANCE's agree for the same scene;
//   rec709: K = 179 lm/W, w = (0.2126, 0.7152, 0.0722), the Rec. 709 / sRGB
//     luminance weights.
// K = 179 lm/W is the efficacy of equal-energy white over the visible band
// (683 lm/W × the mean of V(λ) there): what an RGB white of 1 W stands for
// when no spectrum is given. 683 lm/W would hold only if every watt were at
// 555 nm; a scene calibrated for another source passes its own efficacy.
//
// Display luminance (tone mapping, auto exposure: luminance() in
// core/Math.h) stays Rec. 709 whatever the photometry: it says how bright a
// pixel looks on an sRGB screen, not how many lux a designer measures.
#pragma once

#include "core/Math.h"

#include <string>

namespace ml {

// RADIANCE's luminous efficacy of equal-energy white (WHTEFFICACY), lm/W.
constexpr double kRadianceEfficacy = 179.0;

struct Photometry {
    std::string name = "radiance";       // the name photometryNamed() takes
    double efficacy = kRadianceEfficacy;  // K, lm/W; (0, 1e6), typical 179
    Rgb weights{0.265, 0.670, 0.065};     // w, summing to 1

    // K (w · x): lux from irradiance in W·m⁻², lumens from W, cd·m⁻² from
    // radiance in W·sr⁻¹·m⁻².
    double luminous(const Rgb& radiometric) const {
        return efficacy * (weights.r * radiometric.r + weights.g * radiometric.g + weights.b * radiometric.b);
    }
    // K w, the factors luminous() applies per channel (for shaders).
    Rgb factors() const { return efficacy * weights; }
    // Throws InputError unless the efficacy is within (0, 1e6).
    void validate() const;
    // "radiance (179 lm/W × (0.265, 0.67, 0.065))"
    std::string describe() const;
};

// "radiance" or "rec709", with K = 179 lm/W; anything else is an InputError
// listing the names.
Photometry photometryNamed(const std::string& name);
// The names photometryNamed() takes, for help texts: "radiance|rec709".
const char* photometryNames();

}  // namespace ml
