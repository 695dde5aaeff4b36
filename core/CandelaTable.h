// A luminaire's luminous intensity distribution as measured photometry gives
// it (IES LM-63 and EULUMDAT files: core/loaders/PhotometricFile.h).
#pragma once

#include <string>
#include <vector>

namespace ml {

// A luminaire's luminous intensity distribution in Type C photometry (CIE / IES "type C"):
// gamma = vertical angle in degrees from the nadir (0 = the luminaire's aim, 180 = straight up),
// c = horizontal angle in degrees around the aim, measured from the C0 half-plane.
//
// The loaders hand out tables that keep these promises (the fuzzer checks them):
// gamma has at least 2 angles, strictly ascending, within [0, 180]; c is {0} or
// strictly ascending from 0 to below 360; candela.size() == c.size() * gamma.size();
// every value is finite, in [0, 1e15] cd.
struct CandelaTable {
    std::string source;       // file name, for messages
    std::string description;  // IES [MANUFAC] [LUMINAIRE] (else [LUMCAT], else the first label line);
                              // EULUMDAT's luminaire name (else its company line)
    std::vector<double> gamma;  // degrees, ascending, within [0, 180]
    // Degrees, ascending, full circle after symmetry expansion: c.front() == 0,
    // c.back() < 360 (periodic: the last plane interpolates towards the C0 plane
    // at 360), or a single 0 for rotationally symmetric.
    std::vector<double> c;
    // Absolute cd (all multipliers applied), candela[ci * gamma.size() + gi].
    std::vector<double> candela;
    // Rated lamp lumens the relative photometry was scaled to, or -1 for
    // absolute photometry (no lamp rating: use flux()).
    //   IES: lamps × lumens per lamp, as written (ballast factors not applied:
    //     they scale the candela values, not the lamps' rating); -1 when the
    //     file's lumens per lamp is -1.
    //   EULUMDAT: the first lamp set's total lamp flux (the set the
    //     distribution was measured with; later sets are alternative lamps);
    //     -1 when its number of lamps is negative (absolute photometry: that
    //     flux is then the luminaire's own). For a consistent file,
    //     flux() ≈ ratedLumens × LORL / 100.
    double ratedLumens = -1;
    // Luminous opening, metres. IES sign convention kept: a negative width and
    // length (equal) is a circle of that diameter, all three negative a sphere,
    // and so on (LM-63-2002 table 1). EULUMDAT: its luminous area (length,
    // width, mean of the four heights); a circular one (width 0) becomes
    // width = length = -diameter, the IES way.
    double width = 0, length = 0, height = 0;

    // Candela towards (gammaDeg, cDeg): bilinear in (c, gamma), periodic in c
    // (any real cDeg), 0 outside [gamma.front(), gamma.back()] and for NaN.
    double intensity(double gammaDeg, double cDeg) const;
    // The largest tabulated value, cd (0 for an empty table).
    double maxIntensity() const;
    // Lumens: ∫ intensity dω over the sphere. Integrates the bilinear
    // interpolant exactly (closed-form weights of each angle: the hat
    // function in c times the hat function in gamma times sin gamma), so an
    // isotropic table of I cd gives 4πI up to rounding.
    double flux() const;
};

// How the horizontal angles a file stores cover the circle (Type C).
enum class CSymmetry {
    Rotational,        // one plane serves every c
    Quadrant,          // stored 0..90, mirrored about both the C0-C180 and C90-C270 planes
    BilateralC0C180,   // stored 0..180, mirrored about the C0-C180 plane: I(c) = I(360 - c)
    BilateralC90C270,  // stored 90..270, mirrored about the C90-C270 plane: I(c) = I(180 - c)
    Full,              // stored 0 up to 360 (a plane at 360 repeats C0 and is dropped) or below it
};

// Fills table.c and table.candela from the planes a file stores: storedC
// ascending (what `symmetry` asks for, checked by the caller), storedCandela
// [ci * table.gamma.size() + gi] for those planes; table.gamma must be set.
// Every full-circle angle takes the values of the stored plane it mirrors.
void expandCSymmetry(CandelaTable& table, const std::vector<double>& storedC,
                     const std::vector<double>& storedCandela, CSymmetry symmetry);

}  // namespace ml
