// Photometric luminaire files: IES LM-63 (.ies, IesLoader.h) and EULUMDAT
// (.ldt, EulumdatLoader.h), read into a CandelaTable.
#pragma once

#include "core/CandelaTable.h"
#include "core/Error.h"

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace ml {

// Where the loaders' files come from: fills `text` with the whole file at
// `path` and returns true, or returns false when it cannot be opened (tests
// and the fuzzer serve files from memory).
using PhotometricFileReader = std::function<bool(const std::string& path, std::string& text)>;

// The file system: reads the whole file in binary mode.
bool readPhotometricFileFromDisk(const std::string& path, std::string& text);

// Reads `path` by its extension, case-insensitive: .ies with loadIes, .ldt
// with loadEulumdat. Throws InputError naming the file for any other
// extension, a file that cannot be opened, and whatever the loader refuses
// (file:line: problem).
CandelaTable loadPhotometricFile(const std::string& path);
CandelaTable loadPhotometricFile(const std::string& path, const PhotometricFileReader& read);

// What the two loaders share: lines, tokens and strict numbers.
namespace photometric {

// Most angles (vertical, horizontal, C planes, tilt) a file may give; real
// files have at most a few hundred.
constexpr int kMaxAngles = 10000;
// Brightest candela value accepted after all multipliers (searchlights reach
// 1e9 cd): keeps every sum over a table finite.
constexpr double kMaxCandela = 1e15;
// Smallest step between two angles, degrees: closer ones are not ascending.
constexpr double kMinAngleStep = 1e-6;

// The file's lines without their ends (CR LF, LF or CR alone); a UTF-8 byte
// order mark is removed, a last empty line after the final line end dropped.
std::vector<std::string> splitLines(const std::string& text);

// A whole token as a finite number ("1.5", "-2e3", "+7", ".5"); false for
// anything else, NaN, infinities and values beyond double.
bool parseNumber(std::string_view token, double& value);

// Numbers spread over lines, as LM-63 and EULUMDAT's angle and intensity
// blocks write them. Separators: blanks, tabs, Ctrl-Z (DOS end of file) and,
// with commaSeparates, commas; otherwise a comma inside a token is a decimal
// comma (EULUMDAT written with a European locale).
class TokenStream {
public:
    // Reads lines[firstLine...] (0-based index; messages say firstLine + 1).
    TokenStream(const std::vector<std::string>& lines, size_t firstLine, std::string file, bool commaSeparates);

    // The next token and its 1-based line, or false at the end of the file.
    bool next(std::string& token, int& line);
    // The next token as a finite number; InputError at its line naming
    // `what`, or at the last line when the file ends first.
    double number(const std::string& what);
    // The next token as a whole number in [lo, hi].
    int count(const std::string& what, int lo, int hi);
    // Anything but blanks left is an error: counts and values disagree.
    // `after` says what came last ("the last of the 12 candela values").
    void expectEnd(const std::string& after);
    // The line of the last token read (the last line before any).
    int line() const { return line_; }
    // The file's last line, where "the file ends before ..." is reported.
    int lastLine() const { return int(lines_.size()); }
    const std::string& file() const { return file_; }
    SourceLocation at(int line) const { return SourceLocation{file_, line}; }

private:
    const std::vector<std::string>& lines_;
    size_t row_;
    size_t col_ = 0;
    std::string file_;
    bool commaSeparates_;
    int line_;
};

// Reads `n` angles in degrees, strictly ascending (steps of at least
// kMinAngleStep) within [lo, hi]; `what` names them in messages.
std::vector<double> readAngles(TokenStream& in, int n, const std::string& what, double lo, double hi);

// Reads `total` intensities, each × scale: finite, non-negative, at most
// kMaxCandela once scaled. `what` names one ("candela value"); when the file
// ends first, the message says how many came and `expected` (what the counts
// ask for, e.g. "5 horizontal × 37 vertical angles = 185").
std::vector<double> readIntensities(TokenStream& in, size_t total, const std::string& what, double scale,
                                    const std::string& expected);

// A token as messages quote it: at most 40 characters. Call it qualified
// (photometric::quoted): for a std::string, argument-dependent lookup also
// finds std::quoted wherever <iomanip> is visible (<filesystem> includes it).
std::string quoted(const std::string& token);

}  // namespace photometric

}  // namespace ml
