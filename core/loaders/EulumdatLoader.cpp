#include "core/loaders/EulumdatLoader.h"

#include "core/Error.h"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace ml {

using photometric::TokenStream;

namespace {

// The header's fields, one per line, read by line number (1-based).
class HeaderLines {
public:
    HeaderLines(const std::vector<std::string>& lines, const std::string& file) : lines_(lines), file_(file) {}

    SourceLocation at(int line) const { return SourceLocation{file_, line}; }

    std::string text(int line, const std::string& field) const {
        if (line > int(lines_.size()))
            throwInputError(at(std::max(1, int(lines_.size()))), "the file ends before line ", line, " (", field,
                            ")");
        const std::string& s = lines_[size_t(line - 1)];
        size_t b = 0, e = s.size();
        while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
        while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
        return s.substr(b, e - b);
    }

    // A line holding one finite number (a decimal comma is read as a point).
    double number(int line, const std::string& field) const {
        std::string t = text(line, field);
        std::replace(t.begin(), t.end(), ',', '.');
        double value = 0;
        if (!photometric::parseNumber(t, value))
            throwInputError(at(line), field, ": expected a finite number, found ", photometric::quoted(t));
        return value;
    }

    double atLeast(int line, const std::string& field, double lo) const {
        const double value = number(line, field);
        if (value < lo) throwInputError(at(line), field, " is ", value, ": must be at least ", lo);
        return value;
    }

    int count(int line, const std::string& field, int lo, int hi) const {
        const double value = number(line, field);
        if (value != std::floor(value) || value < lo || value > hi)
            throwInputError(at(line), field, " is ", value, ": expected a whole number from ", lo, " to ", hi);
        return int(value);
    }

private:
    const std::vector<std::string>& lines_;
    const std::string& file_;
};

}  // namespace

CandelaTable loadEulumdat(const std::string& path) { return loadEulumdat(path, readPhotometricFileFromDisk); }

CandelaTable loadEulumdat(const std::string& path, const PhotometricFileReader& read) {
    std::string text;
    if (!read(path, text)) throwInputError(SourceLocation{path, 0}, "cannot open the EULUMDAT file");
    return parseEulumdat(text, path);
}

CandelaTable parseEulumdat(const std::string& text, const std::string& name) {
    const std::vector<std::string> lines = photometric::splitLines(text);
    const HeaderLines h(lines, name);
    CandelaTable table;
    table.source = name;

    const std::string company = h.text(1, "company identification");
    h.count(2, "Ityp (type indicator)", 0, 3);
    const int isym = h.count(3, "Isym (symmetry indicator)", 0, 4);
    const int mc = h.count(4, "Mc (number of C planes)", 1, photometric::kMaxAngles);
    if ((isym == 2 || isym == 3) && mc % 2 != 0)
        throwInputError(h.at(4), "Mc (number of C planes) is ", mc, ": Isym ", isym, " needs an even number");
    if (isym == 4 && mc % 4 != 0)
        throwInputError(h.at(4), "Mc (number of C planes) is ", mc, ": Isym 4 needs a multiple of 4");
    h.atLeast(5, "Dc (distance between C planes)", 0);
    const int ng = h.count(6, "Ng (number of gamma angles)", 2, photometric::kMaxAngles);
    h.atLeast(7, "Dg (distance between gamma angles)", 0);
    const std::string luminaireName = h.text(9, "luminaire name");
    for (int line = 8; line <= 12; ++line) h.text(line, "report number, luminaire name and number, file name, date");
    table.description = luminaireName.empty() ? company : luminaireName;
    h.atLeast(13, "length/diameter of the luminaire (mm)", 0);
    h.atLeast(14, "width of the luminaire (mm)", 0);
    h.atLeast(15, "height of the luminaire (mm)", 0);
    const double areaLength = h.atLeast(16, "length/diameter of the luminous area (mm)", 0) / 1000;
    const double areaWidth = h.atLeast(17, "width of the luminous area (mm)", 0) / 1000;
    double heights = 0;
    for (int i = 0; i < 4; ++i)
        heights += h.atLeast(18 + i, concat("height of the luminous area at C", 90 * i, " (mm)"), 0);
    table.length = areaWidth == 0 ? -areaLength : areaLength;
    table.width = areaWidth == 0 ? -areaLength : areaWidth;
    table.height = heights / 4 / 1000;
    const double dff = h.atLeast(22, "DFF (downward flux fraction, %)", 0);
    if (dff > 100) throwInputError(h.at(22), "DFF (downward flux fraction, %) is ", dff, ": must be at most 100");
    h.atLeast(23, "LORL (light output ratio of the luminaire, %)", 0);
    const double conversion = h.number(24, "conversion factor for luminous intensities");
    if (!(conversion > 0))
        throwInputError(h.at(24), "conversion factor for luminous intensities is ", conversion, ": must be positive");
    h.number(25, "tilt of the luminaire during measurement");
    const int sets = h.count(26, "n (number of lamp sets)", 1, 1000);

    int lampsInFirstSet = 0;
    double fluxOfFirstSet = 0;
    for (int s = 0; s < sets; ++s) {
        const int first = 27 + 6 * s;
        const std::string set = concat(" of lamp set ", s + 1);
        const double lamps = h.number(first, "number of lamps" + set);
        if (lamps != std::floor(lamps) || lamps == 0 || std::abs(lamps) > 1000000)
            throwInputError(h.at(first), "number of lamps", set, " is ", lamps,
                            ": expected a whole number, not 0 (negative: absolute photometry)");
        h.text(first + 1, "type of lamps" + set);
        const double flux = h.atLeast(first + 2, "total luminous flux (lm)" + set, 0);
        h.text(first + 3, "colour" + set);
        h.text(first + 4, "colour rendering index" + set);
        h.atLeast(first + 5, "wattage including ballast (W)" + set, 0);
        if (s == 0) {
            lampsInFirstSet = int(lamps);
            fluxOfFirstSet = flux;
        }
    }
    const int lampLine = 29;  // the first set's flux
    if (!(fluxOfFirstSet > 0))
        throwInputError(h.at(lampLine), "total luminous flux (lm) of lamp set 1 is ", fluxOfFirstSet,
                        ": must be positive, it turns cd/klm into cd");
    table.ratedLumens = lampsInFirstSet < 0 ? -1 : fluxOfFirstSet;
    const int drFirst = 27 + 6 * sets;
    for (int k = 0; k < 10; ++k) h.number(drFirst + k, concat("DR (direct ratio) ", k + 1, " of 10"));

    TokenStream in(lines, size_t(drFirst + 10 - 1), name, false);
    const std::vector<double> allC = photometric::readAngles(in, mc, "C angle", 0, 360 - photometric::kMinAngleStep);
    const int cLine = in.line();
    table.gamma = photometric::readAngles(in, ng, "gamma angle", 0, 180);

    // The planes the symmetry stores: [firstPlane, firstPlane + planes).
    size_t firstPlane = 0, planes = size_t(mc);
    CSymmetry symmetry = CSymmetry::Full;
    const auto need = [&](size_t index, double angle) {
        if (index >= allC.size() || allC[index] != angle)
            throwInputError(in.at(cLine), "Isym ", isym, " needs C angle ", index + 1, " of ", mc, " to be ", angle,
                            ", found ", index < allC.size() ? concat(allC[index]) : std::string("none"));
    };
    if (isym == 0) {
        need(0, 0);
        symmetry = mc == 1 ? CSymmetry::Rotational : CSymmetry::Full;
    } else if (isym == 1) {
        planes = 1;
        symmetry = CSymmetry::Rotational;
    } else if (isym == 2) {
        planes = size_t(mc / 2 + 1);
        need(0, 0);
        need(planes - 1, 180);
        symmetry = CSymmetry::BilateralC0C180;
    } else if (isym == 3) {
        planes = size_t(mc / 2 + 1);
        firstPlane = size_t(std::find(allC.begin(), allC.end(), 90.0) - allC.begin());
        if (firstPlane == allC.size())
            throwInputError(in.at(cLine), "Isym 3 stores the planes C90 to C270, but the C angles have no 90");
        need(firstPlane + planes - 1, 270);
        symmetry = CSymmetry::BilateralC90C270;
    } else {
        planes = size_t(mc / 4 + 1);
        need(0, 0);
        need(planes - 1, 90);
        symmetry = CSymmetry::Quadrant;
    }
    const std::vector<double> storedC(allC.begin() + long(firstPlane), allC.begin() + long(firstPlane + planes));

    const double scale = conversion * fluxOfFirstSet / 1000;
    const size_t total = planes * size_t(ng);
    const std::vector<double> values = photometric::readIntensities(
        in, total, "intensity", scale,
        concat("Isym ", isym, " with Mc ", mc, " stores ", planes, " C planes × ", ng, " gamma angles = ", total));
    in.expectEnd(concat("the last of the ", total, " intensities (", planes, " C planes × ", ng, " gamma angles)"));
    expandCSymmetry(table, storedC, values, symmetry);
    return table;
}

}  // namespace ml
