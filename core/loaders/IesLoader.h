// IES LM-63 photometric files (.ies): 1986, 1991, 1995, 2002 and 2019.
#pragma once

#include "core/CandelaTable.h"
#include "core/loaders/PhotometricFile.h"

#include <string>

namespace ml {

// Reads an IES LM-63 file into a CandelaTable (source = path).
//
// Accepted: the first line IESNA:LM-63-1995, IESNA:LM-63-2002, IESNA91,
// IES:LM-63-2019 or none (1986); keyword lines [KEY] value and free text
// before TILT=, in any case ([MANUFAC] and [LUMINAIRE] give the description);
// then the numbers spread over lines in any way, separated by blanks and/or
// commas; CRLF, CR or LF line ends; a UTF-8 byte order mark; Ctrl-Z and blank
// lines after the candela values. Photometric type C (1) only: the horizontal
// angles give the symmetry, expanded to the full circle (a single angle:
// rotationally symmetric; 0..90: quadrants; 0..180: bilateral about C0-C180;
// 90..270: bilateral about C90-C270; 0..360, or 0 to within one step of 360:
// none); the vertical angles may cover any part of [0, 180] (0..90, 90..180,
// 0..180 in practice), intensity() is 0 outside it.
//
// Multipliers: candela = value × candela multiplier × ballast factor × tilt
// factor, and × the ballast-lamp photometric factor in files before 2002
// (LM-63-2002 renamed that field "future use", value 1; it is read and
// ignored there). Dimensions in feet (units type 1) are converted to metres;
// negative ones (circular and spherical openings) are kept as they are.
//
// TILT: NONE; INCLUDE (the tilt data follows in the file); or a file name,
// read relative to the IES file's folder. The tilt data (lamp-to-luminaire
// geometry 1 to 3, number of tilt angles, the angles ascending within
// [-180, 180], as many non-negative multiplying factors) is checked in full,
// and the candela values are multiplied by the factor interpolated at tilt 0:
// the luminaire as photometered and mounted, lamp in its design position. A
// CandelaTable has one distribution for the luminaire as placed in the
// scene; a scene that tilts it would need the factor at its tilt, which the
// renderer does not model.
//
// Throws InputError (file:line: problem) for a file that cannot be opened,
// no TILT= line, a TILT file that cannot be read (at the TILT line; errors
// inside it name the tilt file and its line), a malformed or non-finite
// number, counts that are negative, not whole or above 10000 (vertical angles:
// at least 2), lumens per lamp other than -1 or positive, a non-positive
// multiplier or ballast factor, photometric types B (2) and A (3), units other
// than 1 or 2, angles not ascending or outside [0, 180] (vertical) or
// [0, 360] (horizontal), horizontal angles that are no Type C symmetry, too
// few candela values (expected and found), negative ones or above 1e15 cd
// after the multipliers, and anything but blanks after the last value.
CandelaTable loadIes(const std::string& path);
CandelaTable loadIes(const std::string& path, const PhotometricFileReader& read);

// The same for an IES text already in memory; `name` stands for the file in
// messages and in source, and locates a TILT=<file> (read through `read`;
// with no reader, TILT=<file> is an error).
CandelaTable parseIes(const std::string& text, const std::string& name, const PhotometricFileReader& read = {});

}  // namespace ml
