// The one-page report of `meshlight grid`: a self-contained HTML file (the
// plan view inlined as a base64 PNG, no script, no other file) with the
// work plane's false-colour plan view, iso-lux lines and legend
// (core/image/FalseColour.h, as `render --quantity lux` and the viewer), the
// statistics table, the luminaires and their flux, the scene and the
// settings.
#pragma once

#include "CalculationSurface.h"
#include "core/image/Image.h"

#include <string>
#include <utility>
#include <vector>

namespace ml {

// The false-colour plan view of a work plane, seen from above (up = y: x to
// the right, z down the page; up = z: x to the right, y up the page), about
// `longSide` pixels along the grid's longer side, lux interpolated
// bilinearly between the cells' centres; cells without a point are the
// background grey. The legend sits in a margin on the right. Display
// values (sRGB-encoded). `lux` holds one value per surface point.
ImageRgb planViewImage(const PlaneGrid& grid, const std::vector<double>& lux, bool zUp, int longSide = 640);

// Bytes as base64 (RFC 4648, with '=' padding), for data: URIs.
std::string base64(const std::vector<unsigned char>& bytes);
// A display image (sRGB-encoded, as planViewImage makes) as a PNG file's
// bytes in base64, for an <img src="data:image/png;base64,...">.
std::string pngBase64(const ImageRgb& display);

struct GridReportSurface {
    std::string name;
    IlluminanceStatistics statistics;
    size_t skipped = 0;  // points left out inside solid objects
};

struct GridReport {
    std::string title;                                            // "office: work plane at 0.75 m"
    std::vector<std::pair<std::string, std::string>> facts;       // scene, unit, settings, time...: label, value
    std::vector<GridReportSurface> surfaces;
    std::vector<std::pair<std::string, double>> luminaires;       // name, luminous flux in lm
    std::string planPngBase64;                                    // the plan view; empty: none (no work plane)
    std::string planCaption;                                      // what the plan view shows
    std::vector<std::string> notes;                               // paragraphs under the tables
};

// The report as one HTML page.
std::string gridReportHtml(const GridReport& report);

}  // namespace ml
