// EULUMDAT photometric files (.ldt).
#pragma once

#include "core/CandelaTable.h"
#include "core/loaders/PhotometricFile.h"

#include <string>

namespace ml {

// Reads a EULUMDAT file into a CandelaTable (source = path).
//
// The header is one field per line (1 company, 2 Ityp 0-3, 3 Isym 0-4, 4 Mc,
// 5 Dc, 6 Ng, 7 Dg, 8-12 texts, 13-21 dimensions in mm, 22 DFF, 23 LORL,
// 24 conversion factor, 25 tilt, 26 n lamp sets, then per set: number of
// lamps, type, total flux, colour, CRI, wattage; then 10 direct ratios);
// the Mc C angles, Ng gamma angles and the intensities follow, one per line
// as the format has it or several per line (blank-separated). A decimal comma
// is read as a point. CRLF, CR or LF line ends.
//
// Symmetry (Isym) and the planes stored: 0 all Mc (C angles from 0 up to below
// 360); 1 one plane (rotationally symmetric); 2 the Mc/2 + 1 planes C0..C180;
// 3 the Mc/2 + 1 planes C90..C270; 4 the Mc/4 + 1 planes C0..C90. They are
// mirrored to the full circle as CSymmetry says.
//
// Intensities are cd per 1000 lm of lamp flux: candela = value × conversion
// factor (line 24) × Φ / 1000, where Φ is the first lamp set's total flux, the
// equipment the distribution was measured with (further sets are alternative
// lamps). A negative number of lamps in that set marks absolute photometry
// (as DIALux and Relux write LED luminaires): Φ is then the luminaire's flux
// and the conversion is the same; ratedLumens is -1 in that case and Φ
// otherwise. Luminous area: length (line 16), width (line 17; 0 = circular,
// stored as width = length = -diameter, the IES convention) and the mean of
// the four heights (lines 18-21), mm converted to metres.
//
// Throws InputError (file:line: problem, naming the field, e.g.
// "lamp.ldt:4: Mc (number of C planes) is -3: expected a whole number from 1
// to 10000") for a file that cannot be opened, a file that ends before a
// field, a malformed or non-finite number, Ityp, Isym or counts out of range,
// Mc that the symmetry cannot split (Isym 2, 3: even; Isym 4: multiple of 4),
// negative dimensions, DFF or LORL, a non-positive conversion factor or first
// set's flux, C angles not ascending within [0, 360) or without the planes the
// symmetry stores (C0, C90, C180, C270 as it needs), gamma angles not
// ascending within [0, 180], too few intensities (expected and found),
// negative ones or above 1e15 cd once converted, and anything but blanks
// after the last intensity.
CandelaTable loadEulumdat(const std::string& path);
CandelaTable loadEulumdat(const std::string& path, const PhotometricFileReader& read);

// The same for a EULUMDAT text already in memory; `name` stands for the file
// in messages and in source.
CandelaTable parseEulumdat(const std::string& text, const std::string& name);

}  // namespace ml
