#include "GridReport.h"

#include "core/image/FalseColour.h"
#include "core/image/Illuminance.h"
#include "viewer/bench/ReportHtml.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include <unistd.h>

namespace ml {

namespace {

// The legend's margin on the right of the plan, pixels; the plan's least
// height, so a long narrow plane still has room for the legend beside it.
constexpr int kLegendMargin = 210;
constexpr int kMinHeight = 320;

// A measured value as a designer reads it: whole numbers from 100 up
// (thin spaces between thousands), three significant digits below.
std::string number(double v) {
    if (!std::isfinite(v)) return "–";
    char text[48];
    if (std::abs(v) < 100) {
        std::snprintf(text, sizeof text, "%.3g", v);
        return text;
    }
    std::snprintf(text, sizeof text, "%.0f", std::abs(v));
    std::string digits = text, out;
    for (size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0) out += "\u2009";
        out += digits[i];
    }
    return (v < 0 ? "-" : "") + out;
}

std::string ratio(double v) {
    if (!std::isfinite(v)) return "–";
    char text[32];
    std::snprintf(text, sizeof text, "%.2f", v);
    return text;
}

}  // namespace

ImageRgb planViewImage(const PlaneGrid& grid, const std::vector<double>& lux, bool zUp, int longSide) {
    const double lengthU = grid.cellU * grid.columns, lengthV = grid.cellV * grid.rows;
    const double scale = longSide / std::max(lengthU, lengthV);  // pixels per scene unit
    const int planW = std::max(1, int(std::lround(lengthU * scale)));
    const int planH = std::max(1, int(std::lround(lengthV * scale)));
    LuxImage image;
    image.width = planW + kLegendMargin;
    image.height = std::max(planH, kMinHeight);
    image.lux.assign(size_t(image.width) * size_t(image.height), 0.0f);
    image.coverage.assign(image.lux.size(), 0.0f);
    const auto value = [&](int c, int r) -> double {
        const int k = grid.pointAt[size_t(r) * size_t(grid.columns) + size_t(c)];
        return k >= 0 && size_t(k) < lux.size() && std::isfinite(lux[size_t(k)]) ? lux[size_t(k)] : -1.0;
    };
    const int top = (image.height - planH) / 2;
    for (int y = 0; y < planH; ++y)
        for (int x = 0; x < planW; ++x) {
            // Grid coordinates in cells, 0 at the first cell's centre.
            const double gu = (x + 0.5) / scale / grid.cellU - 0.5;
            const double vFromTop = (y + 0.5) / scale / grid.cellV - 0.5;
            const double gv = zUp ? grid.rows - 1 - vFromTop : vFromTop;
            const int nearestC = std::clamp(int(std::lround(gu)), 0, grid.columns - 1);
            const int nearestR = std::clamp(int(std::lround(gv)), 0, grid.rows - 1);
            if (value(nearestC, nearestR) < 0) continue;  // a cell left out: background
            // Bilinear between the four centres around, over those with a value.
            const double cu = std::clamp(gu, 0.0, double(grid.columns - 1));
            const double cv = std::clamp(gv, 0.0, double(grid.rows - 1));
            const int c0 = std::min(int(cu), std::max(grid.columns - 2, 0)), r0 = std::min(int(cv), std::max(grid.rows - 2, 0));
            double sum = 0, weights = 0;
            for (int dc = 0; dc <= 1; ++dc)
                for (int dr = 0; dr <= 1; ++dr) {
                    const int c = std::min(c0 + dc, grid.columns - 1), r = std::min(r0 + dr, grid.rows - 1);
                    const double w = (1 - std::abs(cu - c)) * (1 - std::abs(cv - r));
                    const double e = value(c, r);
                    if (w <= 0 || e < 0) continue;
                    sum += w * e;
                    weights += w;
                }
            const size_t i = image.index(x, top + y);
            image.lux[i] = float(weights > 0 ? sum / weights : value(nearestC, nearestR));
            image.coverage[i] = 1;
        }
    std::vector<double> values;
    for (double e : lux)
        if (std::isfinite(e) && e > 0) values.push_back(e);
    const auto [lo, hi] = autoLuxRange(std::move(values));
    ImageRgb display = falseColourImage(image, lo, hi, true);
    drawLuxLegend(display, lo, hi, concat(formatLux(lo), " .. ", formatLux(hi), " lx"));
    return display;
}

std::string base64(const std::vector<unsigned char>& bytes) {
    static const char* kDigits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    for (size_t i = 0; i < bytes.size(); i += 3) {
        const unsigned n = unsigned(bytes[i]) << 16 | (i + 1 < bytes.size() ? unsigned(bytes[i + 1]) << 8 : 0u) |
                           (i + 2 < bytes.size() ? unsigned(bytes[i + 2]) : 0u);
        out += kDigits[n >> 18 & 63];
        out += kDigits[n >> 12 & 63];
        out += i + 1 < bytes.size() ? kDigits[n >> 6 & 63] : '=';
        out += i + 2 < bytes.size() ? kDigits[n & 63] : '=';
    }
    return out;
}

std::string pngBase64(const ImageRgb& display) {
    // writeImage8 writes files only: through a temporary file, read back and removed.
    const std::filesystem::path tmp =
        std::filesystem::temp_directory_path() / concat("meshlight-grid-plan-", ::getpid(), ".png");
    writeImage8(tmp.string(), displayBytes(display), display.width, display.height);
    std::ifstream in(tmp, std::ios::binary);
    const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::filesystem::remove(tmp);
    return base64(bytes);
}

std::string gridReportHtml(const GridReport& r) {
    std::ostringstream h;
    h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" << htmlEscape(r.title)
      << "</title>\n<style>\n"
         "body{font:14px/1.4 sans-serif;max-width:60em;margin:1.5em auto;color:#222}\n"
         "h1{font-size:1.4em;margin:0 0 .4em}h2{font-size:1.1em;margin:1.2em 0 .3em}\n"
         "table{border-collapse:collapse}td,th{padding:2px 10px;border-bottom:1px solid #ddd;text-align:left}\n"
         "td.num,th.num{text-align:right;font-variant-numeric:tabular-nums}\n"
         "dl{display:grid;grid-template-columns:max-content auto;gap:0 1em;margin:0}dt{color:#666}dd{margin:0}\n"
         "img{max-width:100%;image-rendering:auto}figure{margin:.5em 0}figcaption{color:#555;font-size:.9em}\n"
         "@media print{body{margin:0}}\n"
         "</style>\n</head>\n<body>\n<h1>"
      << htmlEscape(r.title) << "</h1>\n<dl>\n";
    for (const auto& [label, value] : r.facts)
        h << "<dt>" << htmlEscape(label) << "</dt><dd>" << htmlEscape(value) << "</dd>\n";
    h << "</dl>\n";
    if (!r.planPngBase64.empty())
        h << "<h2>Plan view</h2>\n<figure><img alt=\"false-colour illuminance of the work plane\" "
             "src=\"data:image/png;base64,"
          << r.planPngBase64 << "\">\n<figcaption>" << htmlEscape(r.planCaption) << "</figcaption></figure>\n";
    h << "<h2>Illuminance (EN 12464-1)</h2>\n<table>\n<tr><th>surface</th><th class=\"num\">points</th>"
         "<th class=\"num\">Ē (lx)</th><th class=\"num\">Emin (lx)</th><th class=\"num\">Emax (lx)</th>"
         "<th class=\"num\">U0 = Emin/Ē</th><th class=\"num\">Emin/Emax</th></tr>\n";
    for (const GridReportSurface& s : r.surfaces) {
        const IlluminanceStatistics& st = s.statistics;
        h << "<tr><td>" << htmlEscape(s.name) << "</td><td class=\"num\">" << st.points
          << (s.skipped ? concat(" (+", s.skipped, " inside objects)") : std::string()) << "</td><td class=\"num\">"
          << number(st.average) << "</td><td class=\"num\">" << number(st.minimum) << "</td><td class=\"num\">"
          << number(st.maximum) << "</td><td class=\"num\">" << ratio(st.uniformity())
          << "</td><td class=\"num\">" << ratio(st.diversity()) << "</td></tr>\n";
    }
    h << "</table>\n<h2>Luminaires</h2>\n<table>\n<tr><th>light</th><th class=\"num\">flux (lm)</th></tr>\n";
    double total = 0;
    for (const auto& [name, lumens] : r.luminaires) {
        h << "<tr><td>" << htmlEscape(name) << "</td><td class=\"num\">" << number(lumens) << "</td></tr>\n";
        total += lumens;
    }
    h << "<tr><th>" << r.luminaires.size() << (r.luminaires.size() == 1 ? " light" : " lights")
      << "</th><th class=\"num\">" << number(total) << "</th></tr>\n</table>\n";
    for (const std::string& note : r.notes) h << "<p>" << htmlEscape(note) << "</p>\n";
    h << "</body>\n</html>\n";
    return h.str();
}

}  // namespace ml
