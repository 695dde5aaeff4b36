// Photometric files (IES LM-63, EULUMDAT) into CandelaTable: every symmetry
// reproduces its file, flux against closed forms, multipliers and units, and
// every error names the file and the line.
//
// The files in tests/data/photometric hold value(plane, angle) = 100 + 10 ×
// plane + angle index for the planes they store, so a test knows every value
// without a copy of the table.
#include "core/CandelaTable.h"
#include "core/Error.h"
#include "core/Math.h"
#include "core/loaders/EulumdatLoader.h"
#include "core/loaders/IesLoader.h"
#include "core/loaders/PhotometricFile.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <ostream>
#include <string>
#include <vector>

using namespace ml;
using ::testing::HasSubstr;

namespace {

std::string dataFile(const std::string& name) {
    return std::string(MESHLIGHT_TEST_DATA) + "/photometric/" + name;
}

double fileValue(size_t plane, size_t angle) { return 100.0 + 10.0 * double(plane) + double(angle); }

void expectRelative(double actual, double expected, double tolerance, const std::string& where) {
    EXPECT_LE(std::abs(actual - expected), tolerance * std::abs(expected)) << where << ": " << actual << " vs "
                                                                           << expected;
}

// The promises of CandelaTable.h about a table a loader returns.
void expectWellFormed(const CandelaTable& t) {
    ASSERT_GE(t.gamma.size(), 2u);
    ASSERT_FALSE(t.c.empty());
    EXPECT_EQ(t.c.front(), 0.0);
    EXPECT_LT(t.c.back(), 360.0);
    EXPECT_EQ(t.candela.size(), t.c.size() * t.gamma.size());
    for (size_t i = 1; i < t.c.size(); ++i) EXPECT_LT(t.c[i - 1], t.c[i]);
    for (size_t i = 1; i < t.gamma.size(); ++i) EXPECT_LT(t.gamma[i - 1], t.gamma[i]);
    for (double v : t.candela) EXPECT_TRUE(std::isfinite(v) && v >= 0);
}

using Mirror = std::function<double(double)>;

struct SymmetryCase {
    std::string file;
    std::vector<double> storedC;  // the planes the file stores, in order
    double scale;                 // multipliers from file values to cd
    std::vector<Mirror> mirrors;  // the directions each stored one stands for
    double ratedLumens;
};

// ctest and failures name the case by its file.
void PrintTo(const SymmetryCase& k, std::ostream* os) { *os << k.file; }

const Mirror aboutC0 = [](double c) { return 360 - c; };
const Mirror aboutC90 = [](double c) { return 180 - c; };
const Mirror both = [](double c) { return 180 + c; };
// Rotational symmetry: any c, including ones outside [0, 360).
const std::vector<Mirror> anyC = {[](double) { return 77.0; }, [](double) { return 200.5; },
                                  [](double) { return -45.0; }, [](double) { return 719.0; }};

class Reproduces : public ::testing::TestWithParam<SymmetryCase> {};

TEST_P(Reproduces, EveryTabulatedAndMirroredDirection) {
    const SymmetryCase& k = GetParam();
    const CandelaTable t = loadPhotometricFile(dataFile(k.file));
    expectWellFormed(t);
    EXPECT_EQ(t.source, dataFile(k.file));
    EXPECT_EQ(t.ratedLumens, k.ratedLumens);
    double largest = 0;
    for (size_t ci = 0; ci < k.storedC.size(); ++ci) {
        for (size_t gi = 0; gi < t.gamma.size(); ++gi) {
            const double expected = fileValue(ci, gi) * k.scale;
            largest = std::max(largest, expected);
            const double g = t.gamma[gi], c = k.storedC[ci];
            expectRelative(t.intensity(g, c), expected, 1e-12, concat(k.file, " gamma ", g, " c ", c));
            for (const Mirror& m : k.mirrors)
                expectRelative(t.intensity(g, m(c)), expected, 1e-12, concat(k.file, " gamma ", g, " mirrored c ", m(c)));
        }
    }
    EXPECT_DOUBLE_EQ(t.maxIntensity(), largest);
    // Outside the vertical range: nothing.
    if (t.gamma.front() > 0) {
        EXPECT_EQ(t.intensity(t.gamma.front() - 1, 0), 0.0);
    }
    if (t.gamma.back() < 180) {
        EXPECT_EQ(t.intensity(t.gamma.back() + 1, 0), 0.0);
    }
    EXPECT_EQ(t.intensity(std::nan(""), 0), 0.0);
    EXPECT_EQ(t.intensity(t.gamma.front(), std::nan("")), 0.0);
}

INSTANTIATE_TEST_SUITE_P(
    Photometric, Reproduces,
    ::testing::Values(
        // IES: candela multiplier 2 × ballast factor 0.9.
        SymmetryCase{"rotational.ies", {0}, 2 * 0.9, anyC, 1000},
        // IES 1995: the ballast-lamp photometric factor 0.5 applies.
        SymmetryCase{"quadrant.ies", {0, 30, 60, 90}, 0.5, {aboutC0, aboutC90, both}, 1000},
        SymmetryCase{"bilateral.ies", {0, 45, 90, 135, 180}, 1, {aboutC0}, -1},
        SymmetryCase{"bilateral90.ies", {90, 135, 180, 225, 270}, 1, {aboutC90}, -1},
        SymmetryCase{"full.ies", {0, 90, 180, 270}, 1, {[](double c) { return c + 360; }}, -1},
        SymmetryCase{"full_periodic.ies", {0, 90, 180, 270}, 1, {}, -1},
        // EULUMDAT: cd/klm × 2000 lm / 1000.
        SymmetryCase{"isym0.ldt", {0, 90, 180, 270}, 2, {}, 2000},
        // Conversion factor 1.5.
        SymmetryCase{"isym1.ldt", {0}, 3, anyC, 2000},
        // Decimal commas.
        SymmetryCase{"isym2.ldt", {0, 45, 90, 135, 180}, 2, {aboutC0}, 2000},
        SymmetryCase{"isym3.ldt", {90, 135, 180, 225, 270}, 2, {aboutC90}, 2000},
        // Absolute photometry (-1 lamps): the flux is the luminaire's, same conversion.
        SymmetryCase{"isym4.ldt", {0, 45, 90}, 2, {aboutC0, aboutC90, both}, -1}),
    [](const ::testing::TestParamInfo<SymmetryCase>& info) {
        std::string name = info.param.file;
        for (char& ch : name)
            if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
        return name;
    });

TEST(Photometric, FullCircleDropsThe360PlaneAndWrapsPeriodically) {
    const CandelaTable full = loadIes(dataFile("full.ies"));
    EXPECT_EQ(full.c, (std::vector<double>{0, 90, 180, 270}));
    const CandelaTable periodic = loadIes(dataFile("full_periodic.ies"));
    // Between C270 and C360 = C0: halfway is the mean.
    for (size_t gi = 0; gi < periodic.gamma.size(); ++gi)
        EXPECT_DOUBLE_EQ(periodic.intensity(periodic.gamma[gi], 315), (fileValue(3, gi) + fileValue(0, gi)) / 2);
    // Bilinear in between: the mean of four corners at the cell's centre.
    EXPECT_DOUBLE_EQ(periodic.intensity(45, 45),
                     (fileValue(0, 0) + fileValue(0, 1) + fileValue(1, 0) + fileValue(1, 1)) / 4);
}

// ---- Text builders for in-memory files -------------------------------------

// An IES file, one part per line: line 1 version, 2 luminaire, 3 TILT, 4 the
// ten numbers, 5 the next three, 6 vertical angles, 7 horizontal angles,
// 8... candela values one plane per line.
std::vector<std::string> iesLines(const std::vector<double>& gamma, const std::vector<double>& c,
                                  const std::function<double(double, double)>& value, double lumens = -1) {
    std::vector<std::string> lines = {"IESNA:LM-63-2002", "[LUMINAIRE] made by the test", "TILT=NONE",
                                      concat("1 ", lumens, " 1 ", gamma.size(), " ", c.size(), " 1 2 0 0 0"),
                                      "1 1 10"};
    std::string g, h;
    for (double x : gamma) g += concat(x, " ");
    for (double x : c) h += concat(x, " ");
    lines.push_back(g);
    lines.push_back(h);
    for (double cc : c) {
        std::string row;
        for (double gg : gamma) row += concat(value(gg, cc), " ");
        lines.push_back(row);
    }
    return lines;
}

std::string join(const std::vector<std::string>& lines, const std::string& end = "\n") {
    std::string text;
    for (const std::string& l : lines) text += l + end;
    return text;
}

std::vector<double> steps(double from, double to, double step) {
    std::vector<double> v;
    for (int i = 0; from + i * step <= to + 1e-9; ++i) v.push_back(from + i * step);
    return v;
}

// Fuzzer finding: 90..270 without a 180 plane mirrors to no C0 plane; one is
// added, interpolated across 360, and the symmetry holds everywhere.
TEST(Photometric, Bilateral90WithoutC180GetsAnInterpolatedC0) {
    const auto value = [](double g, double c) { return 10 + g + c; };
    const CandelaTable t = parseIes(join(iesLines({90, 180}, {90, 135, 140, 225, 270}, value)), "b.ies");
    expectWellFormed(t);
    EXPECT_EQ(t.c.front(), 0.0);
    for (double c : {0.0, 10.0, 40.0, 45.0, 90.0, 100.0, 140.0, 180.0, 200.0, 300.0, 359.0})
        for (double g : {90.0, 120.0, 180.0}) {
            const double mirrored = 180 - c < 0 ? 540 - c : 180 - c;
            EXPECT_NEAR(t.intensity(g, c), t.intensity(g, mirrored), 1e-9) << "c " << c << " gamma " << g;
        }
    // C0 mirrors C180, halfway between the stored 140 and 225 (at 40 and -45).
    EXPECT_NEAR(t.intensity(90, 0), value(90, 140) + (value(90, 225) - value(90, 140)) * 40 / 85, 1e-9);
}

// ---- Flux -------------------------------------------------------------------

TEST(PhotometricFlux, IsotropicIsFourPiI) {
    // Uneven angles: the integral of the interpolant is exact for any grid.
    const auto constant = [](double, double) { return 123.0; };
    const CandelaTable t = parseIes(join(iesLines({0, 10, 35, 90, 170, 180}, {0, 20, 90}, constant)), "iso.ies");
    expectRelative(t.flux(), 4 * kPi * 123, 1e-12, "isotropic");
    const CandelaTable rot = parseIes(join(iesLines(steps(0, 180, 7.5), {0}, constant)), "rot.ies");
    expectRelative(rot.flux(), 4 * kPi * 123, 1e-12, "rotational");
}

TEST(PhotometricFlux, LowerHemisphereOnlyIsHalf) {
    const auto constant = [](double, double) { return 50.0; };
    // The table stops at 90: nothing above.
    const CandelaTable lower = parseIes(join(iesLines({0, 45, 90}, {0, 90}, constant)), "lower.ies");
    expectRelative(lower.flux(), 2 * kPi * 50, 1e-12, "0..90");
    // A full 0..180 table whose upper half is 0 (a 1e-4 degree ramp at 90).
    const auto halfZero = [](double g, double) { return g <= 90 ? 50.0 : 0.0; };
    const CandelaTable half = parseIes(join(iesLines({0, 45, 90, 90.0001, 135, 180}, {0}, halfZero)), "half.ies");
    expectRelative(half.flux(), 2 * kPi * 50, 1e-4, "upper half zero");
    // And the upper hemisphere alone (90..180) is the other half.
    const CandelaTable upper = parseIes(join(iesLines({90, 135, 180}, {0}, constant)), "upper.ies");
    expectRelative(upper.flux(), 2 * kPi * 50, 1e-12, "90..180");
}

TEST(PhotometricFlux, CosineDistributionMatchesItsRatedLumens) {
    // I = I0 cos γ over the lower hemisphere emits π I0; the file says so.
    const double i0 = 1000;
    const auto cosine = [&](double g, double) { return i0 * std::cos(g * kPi / 180); };
    const CandelaTable t =
        parseIes(join(iesLines(steps(0, 90, 5), {0, 45, 90}, cosine, kPi * i0)), "cosine.ies");
    expectRelative(t.ratedLumens, kPi * i0, 1e-8, "rated lumens");
    expectRelative(t.flux(), t.ratedLumens, 0.01, "cosine against its file's lumens");

    // EULUMDAT: (1000/π) cos γ cd/klm with a 3000 lm lamp and LORL 100: 3000 lm.
    std::vector<std::string> l = {"co", "1", "1", "1", "0", "19", "5", "r", "cosine", "n", "f", "d",
                                  "0", "0", "0", "0", "0", "0", "0", "0", "0", "100", "100", "1", "0", "1",
                                  "1", "LED", "3000", "3000K", "80", "30"};
    for (int k = 0; k < 10; ++k) l.push_back("0.5");
    l.push_back("0");
    for (double g : steps(0, 90, 5)) l.push_back(concat(g));
    for (double g : steps(0, 90, 5)) l.push_back(concat(1000 / kPi * std::cos(g * kPi / 180)));
    const CandelaTable e = parseEulumdat(join(l), "cosine.ldt");
    EXPECT_EQ(e.ratedLumens, 3000);
    expectRelative(e.flux(), e.ratedLumens * 100 / 100, 0.01, "EULUMDAT cosine, LORL 100 %");
}

// The closed form against a fine midpoint rule over the sphere, on a table
// with every symmetry's expansion and uneven angles.
TEST(PhotometricFlux, ClosedFormAgreesWithNumericalIntegration) {
    for (const char* file : {"quadrant.ies", "bilateral90.ies", "full_periodic.ies", "isym3.ldt"}) {
        const CandelaTable t = loadPhotometricFile(dataFile(file));
        const int ng = 1800, nc = 720;
        double sum = 0;
        for (int i = 0; i < ng; ++i) {
            const double g = (i + 0.5) * 180.0 / ng;
            double ring = 0;
            for (int j = 0; j < nc; ++j) ring += t.intensity(g, (j + 0.5) * 360.0 / nc);
            sum += ring * std::sin(g * kPi / 180);
        }
        const double numeric = sum * (kPi / ng) * (2 * kPi / nc);
        expectRelative(t.flux(), numeric, 1e-4, file);
    }
}

// ---- Multipliers, units, header ---------------------------------------------

TEST(Photometric, MultipliersUnitsAndDescription) {
    const CandelaTable rot = loadIes(dataFile("rotational.ies"));
    EXPECT_EQ(rot.description, "Meshlight Downlight 5");
    EXPECT_DOUBLE_EQ(rot.width, 0.3048);  // feet → metres
    EXPECT_DOUBLE_EQ(rot.length, 2 * 0.3048);
    EXPECT_DOUBLE_EQ(rot.height, 0.5 * 0.3048);
    const CandelaTable quad = loadIes(dataFile("quadrant.ies"));
    EXPECT_EQ(quad.description, "Quad");  // keyword in lower case
    EXPECT_DOUBLE_EQ(quad.width, 0.6);    // metres as they are
    EXPECT_DOUBLE_EQ(quad.height, 0.1);

    // 2002: the 12th number is "future use" and multiplies nothing.
    std::vector<std::string> l = iesLines({0, 90}, {0}, [](double, double) { return 10.0; });
    l[3] = "1 -1 3 2 1 1 2 0 0 0";  // candela multiplier 3
    l[4] = "0.5 0.25 10";           // ballast factor 0.5, future use 0.25
    EXPECT_DOUBLE_EQ(parseIes(join(l), "m.ies").intensity(0, 0), 10 * 3 * 0.5);
    l[0] = "IESNA:LM-63-1995";  // 1995: the ballast-lamp factor multiplies
    EXPECT_DOUBLE_EQ(parseIes(join(l), "m.ies").intensity(0, 0), 10 * 3 * 0.5 * 0.25);

    // EULUMDAT: circular luminous area (width 0) in the IES convention, mm → m.
    const CandelaTable ldt = loadEulumdat(dataFile("isym1.ldt"));
    EXPECT_EQ(ldt.description, "Test luminaire Isym 1");
    EXPECT_DOUBLE_EQ(ldt.length, -0.5);
    EXPECT_DOUBLE_EQ(ldt.width, -0.5);
    EXPECT_DOUBLE_EQ(ldt.height, 0.015);
    const CandelaTable rect = loadEulumdat(dataFile("isym0.ldt"));
    EXPECT_DOUBLE_EQ(rect.length, 0.5);
    EXPECT_DOUBLE_EQ(rect.width, 0.3);
}

TEST(Photometric, NegativeDimensionsAnd1986) {
    const CandelaTable t = loadIes(dataFile("circular_1986.ies"));
    EXPECT_DOUBLE_EQ(t.width, -0.3048);
    EXPECT_DOUBLE_EQ(t.length, -0.3048);
    EXPECT_EQ(t.height, 0.0);
    EXPECT_EQ(t.description, "Meshlight test luminaire, 1986 style");
    EXPECT_EQ(t.ratedLumens, 1000);
    // 1986 has the ballast-lamp factor: 1 here.
    EXPECT_DOUBLE_EQ(t.intensity(45, 0), fileValue(0, 1));
}

TEST(Photometric, TiltIncludeAndTiltFile) {
    // Factor at tilt 0 between -10 (0.6) and 30 (1.0): 0.7.
    const CandelaTable inc = loadIes(dataFile("tilt_include.ies"));
    for (size_t gi = 0; gi < inc.gamma.size(); ++gi)
        EXPECT_DOUBLE_EQ(inc.intensity(inc.gamma[gi], 0), fileValue(0, gi) * 0.7);
    // lamp.tlt beside the IES file: first angle 0, factor 0.5.
    const CandelaTable file = loadIes(dataFile("tilt_file.ies"));
    for (size_t gi = 0; gi < file.gamma.size(); ++gi)
        EXPECT_DOUBLE_EQ(file.intensity(file.gamma[gi], 0), fileValue(0, gi) * 0.5);
}

TEST(Photometric, CrlfCommasLongLinesAndTrailingBlanks) {
    const auto value = [](double g, double c) { return 1 + g + 2 * c; };
    const std::vector<double> gamma = steps(0, 180, 2.5), c = steps(0, 360, 5);
    const std::vector<std::string> lines = iesLines(gamma, c, value);
    const CandelaTable lf = parseIes(join(lines), "lf.ies");
    // CRLF, commas between numbers, all candela values on one long line
    // (73 × 73 values), Ctrl-Z and blank lines at the end.
    std::vector<std::string> odd(lines.begin(), lines.begin() + 7);
    for (std::string& l : odd)
        for (size_t p = l.find(' '); p != std::string::npos; p = l.find(' ', p + 2)) l.replace(p, 1, ", ");
    std::string all;
    for (size_t k = 7; k < lines.size(); ++k) all += lines[k] + ",";
    odd.push_back(all);
    odd.push_back("   ");
    odd.push_back("\x1A");
    const CandelaTable crlf = parseIes(join(odd, "\r\n"), "crlf.ies");
    EXPECT_EQ(crlf.gamma, lf.gamma);
    EXPECT_EQ(crlf.c, lf.c);
    EXPECT_EQ(crlf.candela, lf.candela);
    EXPECT_EQ(lf.c.size(), 72u);  // C360 dropped
    EXPECT_DOUBLE_EQ(lf.intensity(2.5, 5), value(2.5, 5));
    // Keywords and TILT in any case, blanks around '='.
    std::vector<std::string> lower = lines;
    lower[1] = "[luminaire] lower case";
    lower[2] = "  tilt = none";
    EXPECT_EQ(parseIes(join(lower), "lower.ies").description, "lower case");
    // CRLF EULUMDAT.
    std::string ldt;
    readPhotometricFileFromDisk(dataFile("isym2.ldt"), ldt);
    std::string crlfLdt;
    for (char ch : ldt) crlfLdt += ch == '\n' ? std::string("\r\n") : std::string(1, ch);
    EXPECT_EQ(parseEulumdat(crlfLdt, "crlf.ldt").candela, loadEulumdat(dataFile("isym2.ldt")).candela);
}

TEST(Photometric, DispatchOnExtension) {
    std::map<std::string, std::string> files;
    readPhotometricFileFromDisk(dataFile("quadrant.ies"), files["dir/LAMP.IES"]);
    readPhotometricFileFromDisk(dataFile("isym4.ldt"), files["dir/lamp.Ldt"]);
    const PhotometricFileReader read = [&](const std::string& path, std::string& text) {
        const auto it = files.find(path);
        if (it == files.end()) return false;
        text = it->second;
        return true;
    };
    EXPECT_EQ(loadPhotometricFile("dir/LAMP.IES", read).description, "Quad");
    EXPECT_EQ(loadPhotometricFile("dir/lamp.Ldt", read).description, "Test luminaire Isym 4");
    try {
        loadPhotometricFile("dir/lamp.txt", read);
        FAIL() << "no error for .txt";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), HasSubstr("dir/lamp.txt"));
        EXPECT_THAT(e.what(), HasSubstr(".ies"));
    }
    EXPECT_THROW(loadPhotometricFile("dir.ies/noextension", read), InputError);
    try {
        loadPhotometricFile(dataFile("missing.ies"));
        FAIL() << "no error for a missing file";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), HasSubstr("missing.ies: cannot open"));
    }
}

// ---- Errors: file:line and the problem -------------------------------------

// Expects InputError from `load`, "name:line: ..." holding `problem`.
void expectError(const std::function<void()>& load, const std::string& name, int line, const std::string& problem) {
    try {
        load();
        ADD_FAILURE() << "no error; expected " << name << ":" << line << ": ..." << problem;
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), HasSubstr(concat(name, ":", line, ": "))) << "expected line " << line;
        EXPECT_THAT(e.what(), HasSubstr(problem));
    }
}

struct LineError {
    int line;           // 1-based line to replace (0: none)
    std::string text;   // its new text
    int errorLine;      // where the message points
    std::string problem;
};

// Each case: `good` with one line replaced, parsed as `name`, must fail there.
void expectLineErrors(const std::vector<std::string>& good, const std::vector<LineError>& cases,
                      const std::string& name, const std::function<void(const std::string&)>& parse) {
    for (const LineError& k : cases) {
        std::vector<std::string> lines = good;
        lines[size_t(k.line - 1)] = k.text;
        SCOPED_TRACE(k.text);
        expectError([&] { parse(join(lines)); }, name, k.errorLine, k.problem);
    }
}

TEST(PhotometricErrors, Ies) {
    const std::vector<std::string> good = iesLines({0, 45, 90}, {0}, [](double g, double) { return 100 - g; });
    ASSERT_NO_THROW(parseIes(join(good), "bad.ies"));
    ASSERT_EQ(good.size(), 8u);
    const std::vector<LineError> cases = {
        {3, "[NOTILT]", 8, "without a TILT= line"},
        {3, "TILT=", 3, "TILT= names nothing"},
        {3, "TILT=missing.tlt", 3, "TILT file 'missing.tlt' cannot be read"},
        {4, "1 -1 x 3 1 1 2 0 0 0", 4, "candela multiplier: expected a finite number, found 'x'"},
        {4, "1 -1 1e999 3 1 1 2 0 0 0", 4, "candela multiplier: expected a finite number, found '1e999'"},
        {4, "1 -1 nan 3 1 1 2 0 0 0", 4, "found 'nan'"},
        {4, "1 -1 0 3 1 1 2 0 0 0", 4, "candela multiplier is 0: must be positive"},
        {4, "1 -1 1 -3 1 1 2 0 0 0", 4, "number of vertical angles is -3"},
        {4, "1 -1 1 3 20000 1 2 0 0 0", 4, "number of horizontal angles is 20000: expected a whole number from 1 to 10000"},
        {4, "1 -1 1 3.5 1 1 2 0 0 0", 4, "number of vertical angles is 3.5"},
        {4, "-1 -1 1 3 1 1 2 0 0 0", 4, "number of lamps is -1"},
        {4, "1 0 1 3 1 1 2 0 0 0", 4, "lumens per lamp is 0"},
        {4, "1 -1 1 3 1 2 2 0 0 0", 4, "photometric type 2 (type B) is not supported"},
        {4, "1 -1 1 3 1 3 2 0 0 0", 4, "photometric type 3 (type A) is not supported"},
        {4, "1 -1 1 3 1 1 3 0 0 0", 4, "units type (1 feet, 2 metres) is 3"},
        {5, "0 1 10", 5, "ballast factor is 0: must be positive"},
        {6, "0 90 45", 6, "vertical angle 3 of 3 is 45 after 90: angles must ascend"},
        {6, "0 45 190", 6, "vertical angle 3 of 3 is 190: outside [0, 180]"},
        {6, "0 45 -1", 6, "vertical angle 3 of 3 is -1: outside"},
        {7, "400", 7, "horizontal angle 1 of 1 is 400: outside [0, 360]"},
        {8, "100 55", 8, "the file ends before candela value 3 of 3: found 2, expected 1 horizontal × 3 vertical"},
        {8, "100 -55 10", 8, "candela value 2 of 3 is negative: -55"},
        {8, "100 55 10 junk", 8, "unexpected 'junk' after the last of the 3 candela values"},
        {8, "100 55 10 11", 8, "unexpected '11' after the last of the 3 candela values"},
    };
    expectLineErrors(good, cases, "bad.ies", [](const std::string& text) { parseIes(text, "bad.ies"); });
    // The 1e15 case above: 1e15 × the candela multiplier (1) is allowed, 2e15 is not.
    std::vector<std::string> bright = good;
    bright[7] = "100 1e15 10";
    bright[3] = "1 -1 2 3 1 1 2 0 0 0";
    expectError([&] { parseIes(join(bright), "bad.ies"); }, "bad.ies", 8, "above 1e15 cd");

    // Numbers spread over lines: the error names the line of the bad one.
    std::vector<std::string> spread = {"TILT=NONE", "1", "-1", "1 3", "1 1 2 0", "0", "0 1 1 10 0 45 90", "0",
                                       "100 55", "10 -1"};
    expectError([&] { parseIes(join(spread), "spread.ies"); }, "spread.ies", 10, "unexpected '-1'");
    spread[3] = "1 3 ";
    spread[4] = "1 1 2 0 0 0 1 1 10 0 45 45";
    expectError([&] { parseIes(join(spread), "spread.ies"); }, "spread.ies", 5, "vertical angle 3 of 3 is 45 after 45");

    // Horizontal angles that are no type C symmetry.
    std::vector<std::string> sym = iesLines({0, 90}, {0, 45}, [](double, double) { return 1.0; });
    expectError([&] { parseIes(join(sym), "sym.ies"); }, "sym.ies", 7, "horizontal angles run from 0 to 45");
    sym = iesLines({0, 90}, {10, 90}, [](double, double) { return 1.0; });
    expectError([&] { parseIes(join(sym), "sym.ies"); }, "sym.ies", 7, "horizontal angles run from 10 to 90");

    // TILT=INCLUDE with bad tilt data; a tilt file's error names the tilt file.
    std::vector<std::string> tilt = good;
    tilt[2] = "TILT=INCLUDE";
    tilt.insert(tilt.begin() + 3, {"1", "-2"});
    expectError([&] { parseIes(join(tilt), "tilt.ies"); }, "tilt.ies", 5, "number of tilt angles is -2");
    tilt[4] = "2 0 30 1 -0.5";
    expectError([&] { parseIes(join(tilt), "tilt.ies"); }, "tilt.ies", 5, "tilt multiplying factor 2 of 2 is -0.5");
    tilt[3] = "4";
    expectError([&] { parseIes(join(tilt), "tilt.ies"); }, "tilt.ies", 4, "lamp-to-luminaire geometry (TILT) is 4");
    std::vector<std::string> named = good;
    named[2] = "TILT=lamp.tlt";
    const PhotometricFileReader read = [](const std::string& path, std::string& text) {
        if (path != "dir/lamp.tlt") return false;
        text = "1\n2\n0 30\n1 0.5\n0.7\n";
        return true;
    };
    expectError([&] { parseIes(join(named), "dir/tilt.ies", read); }, "dir/lamp.tlt", 5,
                "unexpected '0.7' after the tilt data");
    expectError([&] { parseIes(join(named), "other/tilt.ies", read); }, "other/tilt.ies", 3,
                "looked for 'other/lamp.tlt'");
    // An empty file.
    expectError([&] { parseIes("", "empty.ies"); }, "empty.ies", 1, "without a TILT= line");
}

// A EULUMDAT file for the error cases: Isym 2, Mc 4 (0 90 180 270), Ng 3
// (0 90 180); lines 27-32 the lamp set, 33-42 the DRs, 43-46 the C angles,
// 47-49 the gammas, 50-58 the intensities (3 planes × 3).
std::vector<std::string> ldtLines() {
    std::vector<std::string> l = {"company", "3", "2", "4", "90", "3", "90", "r", "name", "no", "f.ldt", "d",
                                  "100", "100", "50", "80", "80", "5", "5", "5", "5", "100", "90", "1", "0", "1",
                                  "2", "T5", "1000", "840", "1B", "30"};
    for (int k = 0; k < 10; ++k) l.push_back("0.4");
    for (const char* a : {"0", "90", "180", "270", "0", "90", "180"}) l.push_back(a);
    for (int k = 0; k < 9; ++k) l.push_back(concat(200 - 10 * k));
    return l;
}

TEST(PhotometricErrors, Eulumdat) {
    const std::vector<std::string> good = ldtLines();
    ASSERT_EQ(good.size(), 58u);
    const CandelaTable ok = parseEulumdat(join(good), "bad.ldt");
    EXPECT_DOUBLE_EQ(ok.intensity(0, 0), 200.0);  // 1000 lm: cd/klm = cd
    EXPECT_DOUBLE_EQ(ok.intensity(0, 270), ok.intensity(0, 90));
    const std::vector<LineError> cases = {
        {2, "7", 2, "Ityp (type indicator) is 7"},
        {3, "5", 3, "Isym (symmetry indicator) is 5: expected a whole number from 0 to 4"},
        {4, "-3", 4, "Mc (number of C planes) is -3"},
        {4, "3", 4, "Mc (number of C planes) is 3: Isym 2 needs an even number"},
        {6, "1", 6, "Ng (number of gamma angles) is 1"},
        {6, "x", 6, "Ng (number of gamma angles): expected a finite number, found 'x'"},
        {5, "-90", 5, "Dc (distance between C planes) is -90"},
        {16, "-80", 16, "length/diameter of the luminous area (mm) is -80"},
        {22, "101", 22, "DFF (downward flux fraction, %) is 101"},
        {23, "abc", 23, "LORL (light output ratio of the luminaire, %): expected a finite number, found 'abc'"},
        {24, "0", 24, "conversion factor for luminous intensities is 0"},
        {26, "0", 26, "n (number of lamp sets) is 0"},
        {27, "0", 27, "number of lamps of lamp set 1 is 0"},
        {29, "-1000", 29, "total luminous flux (lm) of lamp set 1 is -1000"},
        {29, "0", 29, "total luminous flux (lm) of lamp set 1 is 0: must be positive"},
        {35, "inf", 35, "DR (direct ratio) 3 of 10: expected a finite number, found 'inf'"},
        {45, "90", 45, "C angle 3 of 4 is 90 after 90: angles must ascend"},
        {46, "360", 46, "C angle 4 of 4 is 360: outside"},
        {45, "170", 46, "Isym 2 needs C angle 3 of 4 to be 180, found 170"},
        {43, "10", 46, "Isym 2 needs C angle 1 of 4 to be 0, found 10"},
        {49, "200", 49, "gamma angle 3 of 3 is 200: outside [0, 180]"},
        {52, "-5", 52, "intensity 3 of 9 is negative: -5"},
        {58, "1e300", 58, "above 1e15 cd"},
        {58, "", 58, "the file ends before intensity 9 of 9: found 8, expected Isym 2 with Mc 4 stores 3 C planes"},
        {58, "120 7", 58, "unexpected '7' after the last of the 9 intensities"},
    };
    expectLineErrors(good, cases, "bad.ldt", [](const std::string& text) { parseEulumdat(text, "bad.ldt"); });
    // Cut short in the header.
    const std::vector<std::string> cut(good.begin(), good.begin() + 19);
    expectError([&] { parseEulumdat(join(cut), "cut.ldt"); }, "cut.ldt", 19,
                "the file ends before line 20 (height of the luminous area at C180 (mm))");
    // Isym 3 needs C90 and C270 Mc/2 planes apart; Isym 4 a multiple of 4.
    std::vector<std::string> isym = good;
    isym[2] = "3";
    isym[43] = "100";
    expectError([&] { parseEulumdat(join(isym), "i3.ldt"); }, "i3.ldt", 46, "the C angles have no 90");
    isym[2] = "4";
    isym[3] = "6";
    expectError([&] { parseEulumdat(join(isym), "i4.ldt"); }, "i4.ldt", 4, "Isym 4 needs a multiple of 4");
}

}  // namespace
