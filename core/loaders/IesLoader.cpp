#include "core/loaders/IesLoader.h"

#include "core/Error.h"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace ml {

using photometric::TokenStream;

namespace {

std::string trim(const std::string& s) {
    const auto blank = [](unsigned char ch) { return std::isspace(ch) || ch == '\x1A'; };
    size_t b = 0, e = s.size();
    while (b < e && blank(s[b])) ++b;
    while (e > b && blank(s[e - 1])) --e;
    return s.substr(b, e - b);
}

std::string upper(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char ch) { return char(std::toupper(ch)); });
    return s;
}

// "TILT=..." (any case, blanks around '='): true and the value after '='.
bool tiltLine(const std::string& line, std::string& value) {
    const std::string t = trim(line);
    if (t.size() < 4 || upper(t.substr(0, 4)) != "TILT") return false;
    const std::string rest = trim(t.substr(4));
    if (rest.empty() || rest[0] != '=') return false;
    value = trim(rest.substr(1));
    return true;
}

// The tilt data (TILT=INCLUDE or a tilt file), checked in full; returns the
// multiplying factor at tilt 0 (the ends' factors beyond the angles given).
double readTilt(TokenStream& in) {
    in.count("lamp-to-luminaire geometry (TILT)", 1, 3);
    const int n = in.count("number of tilt angles", 1, photometric::kMaxAngles);
    const std::vector<double> angles = photometric::readAngles(in, n, "tilt angle", -180, 180);
    std::vector<double> factors;
    for (int i = 0; i < n; ++i) {
        const double f = in.number(concat("tilt multiplying factor ", i + 1, " of ", n));
        if (f < 0 || f > 1e6)
            throwInputError(in.at(in.line()), "tilt multiplying factor ", i + 1, " of ", n, " is ", f,
                            ": expected a factor in [0, 1e6]");
        factors.push_back(f);
    }
    if (0 <= angles.front()) return factors.front();
    if (0 >= angles.back()) return factors.back();
    const size_t i = size_t(std::upper_bound(angles.begin(), angles.end(), 0.0) - angles.begin()) - 1;
    const double t = (0 - angles[i]) / (angles[i + 1] - angles[i]);
    return factors[i] + t * (factors[i + 1] - factors[i]);
}

std::string folderOf(const std::string& path) {
    const size_t slash = path.find_last_of("/\\");
    return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

}  // namespace

CandelaTable loadIes(const std::string& path) { return loadIes(path, readPhotometricFileFromDisk); }

CandelaTable loadIes(const std::string& path, const PhotometricFileReader& read) {
    std::string text;
    if (!read(path, text)) throwInputError(SourceLocation{path, 0}, "cannot open the IES file");
    return parseIes(text, path, read);
}

CandelaTable parseIes(const std::string& text, const std::string& name, const PhotometricFileReader& read) {
    const std::vector<std::string> lines = photometric::splitLines(text);
    CandelaTable table;
    table.source = name;

    // Header: version line, keywords and free text up to TILT=.
    bool futureUseField = false;  // 2002 on: the ballast-lamp factor field is "future use"
    std::string manufac, luminaire, lumcat, firstLabel, tilt;
    size_t row = 0;
    bool haveTilt = false;
    for (; row < lines.size() && !haveTilt; ++row) {
        if (tiltLine(lines[row], tilt)) {
            haveTilt = true;
            break;
        }
        const std::string t = trim(lines[row]);
        const std::string u = upper(t);
        if (row == 0 && (u.rfind("IESNA", 0) == 0 || u.rfind("IES:", 0) == 0)) {
            futureUseField = u.find("2002") != std::string::npos || u.find("2019") != std::string::npos ||
                             u.rfind("IES:", 0) == 0;
            continue;
        }
        if (!t.empty() && t[0] == '[') {
            const size_t close = t.find(']');
            if (close == std::string::npos) continue;  // free text, as 1986 files hold
            const std::string key = upper(t.substr(1, close - 1)), value = trim(t.substr(close + 1));
            if (key == "MANUFAC" && manufac.empty()) manufac = value;
            if (key == "LUMINAIRE" && luminaire.empty()) luminaire = value;
            if (key == "LUMCAT" && lumcat.empty()) lumcat = value;
        } else if (firstLabel.empty()) {
            firstLabel = t;
        }
    }
    if (!haveTilt)
        throwInputError(SourceLocation{name, std::max(1, int(lines.size()))},
                        "the file ends without a TILT= line (TILT=NONE, TILT=INCLUDE or TILT=<file> must come "
                        "before the photometric data)");
    const int tiltRow = int(row + 1);
    table.description = !manufac.empty() && !luminaire.empty() ? manufac + " " + luminaire
                        : !manufac.empty() || !luminaire.empty() ? manufac + luminaire
                        : !lumcat.empty()                        ? lumcat
                                                                 : firstLabel;

    TokenStream in(lines, row + 1, name, true);
    double tiltFactor = 1;
    const std::string tiltUpper = upper(tilt);
    if (tiltUpper == "INCLUDE") {
        tiltFactor = readTilt(in);
    } else if (tiltUpper.empty()) {
        throwInputError(in.at(tiltRow), "TILT= names nothing: expected NONE, INCLUDE or a file name");
    } else if (tiltUpper != "NONE") {
        const bool absolute = tilt[0] == '/' || (tilt.size() > 1 && tilt[1] == ':');
        const std::string tiltPath = absolute ? tilt : folderOf(name) + tilt;
        std::string tiltText;
        if (!read || !read(tiltPath, tiltText))
            throwInputError(in.at(tiltRow), "TILT file '", tilt, "' cannot be read (looked for '", tiltPath, "')");
        const std::vector<std::string> tiltLines = photometric::splitLines(tiltText);
        TokenStream tiltIn(tiltLines, 0, tiltPath, true);
        tiltFactor = readTilt(tiltIn);
        tiltIn.expectEnd("the tilt data");
    }

    // The photometric data.
    const int lamps = in.count("number of lamps", 0, 1000000);
    const double lumensPerLamp = in.number("lumens per lamp");
    if (lumensPerLamp == -1) {
        table.ratedLumens = -1;
    } else if (!(lumensPerLamp > 0) || lamps == 0) {
        throwInputError(in.at(in.line()), "lumens per lamp is ", lumensPerLamp, " with ", lamps,
                        " lamps: expected -1 (absolute photometry) or positive lumens for at least one lamp");
    } else {
        table.ratedLumens = lamps * lumensPerLamp;
    }
    const double multiplier = in.number("candela multiplier");
    if (!(multiplier > 0)) throwInputError(in.at(in.line()), "candela multiplier is ", multiplier, ": must be positive");
    const int nv = in.count("number of vertical angles", 2, photometric::kMaxAngles);
    const int nh = in.count("number of horizontal angles", 1, photometric::kMaxAngles);
    const int type = in.count("photometric type", 1, 3);
    if (type != 1)
        throwInputError(in.at(in.line()), "photometric type ", type, type == 2 ? " (type B)" : " (type A)",
                        " is not supported: only type C (1)");
    const int units = in.count("units type (1 feet, 2 metres)", 1, 2);
    const double toMetres = units == 1 ? 0.3048 : 1.0;
    table.width = in.number("luminous width") * toMetres;
    table.length = in.number("luminous length") * toMetres;
    table.height = in.number("luminous height") * toMetres;
    const double ballast = in.number("ballast factor");
    if (!(ballast > 0)) throwInputError(in.at(in.line()), "ballast factor is ", ballast, ": must be positive");
    const double ballastLamp = in.number(futureUseField ? "future use field" : "ballast-lamp photometric factor");
    if (!futureUseField && !(ballastLamp > 0))
        throwInputError(in.at(in.line()), "ballast-lamp photometric factor is ", ballastLamp, ": must be positive");
    in.number("input watts");
    const double scale = multiplier * ballast * tiltFactor * (futureUseField ? 1.0 : ballastLamp);

    table.gamma = photometric::readAngles(in, nv, "vertical angle", 0, 180);
    std::vector<double> storedC = photometric::readAngles(in, nh, "horizontal angle", 0, 360);
    const int hLine = in.line();
    CSymmetry symmetry = CSymmetry::Rotational;
    if (nh > 1) {
        const double first = storedC.front(), last = storedC.back();
        double widest = 0;
        for (size_t i = 1; i < storedC.size(); ++i) widest = std::max(widest, storedC[i] - storedC[i - 1]);
        if (first == 0 && last == 90) symmetry = CSymmetry::Quadrant;
        else if (first == 0 && last == 180) symmetry = CSymmetry::BilateralC0C180;
        else if (first == 90 && last == 270) symmetry = CSymmetry::BilateralC90C270;
        else if (first == 0 && last > 180 && 360 - last <= widest + 1e-9) symmetry = CSymmetry::Full;
        else
            throwInputError(in.at(hLine), "horizontal angles run from ", first, " to ", last,
                            ": type C needs a single angle (rotational symmetry), 0 to 90, 0 to 180, 90 to 270 "
                            "or 0 to 360");
    }

    const size_t total = size_t(nv) * size_t(nh);
    const std::vector<double> values = photometric::readIntensities(
        in, total, "candela value", scale, concat(nh, " horizontal × ", nv, " vertical angles = ", total));
    in.expectEnd(concat("the last of the ", total, " candela values (", nh, " horizontal × ", nv,
                        " vertical angles)"));
    expandCSymmetry(table, storedC, values, symmetry);
    return table;
}

}  // namespace ml
