#include "core/loaders/PhotometricFile.h"

#include "core/loaders/EulumdatLoader.h"
#include "core/loaders/IesLoader.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace ml {

bool readPhotometricFileFromDisk(const std::string& path, std::string& text) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return false;
    std::ostringstream all;
    all << in.rdbuf();
    text = all.str();
    return !in.bad();
}

CandelaTable loadPhotometricFile(const std::string& path) {
    return loadPhotometricFile(path, readPhotometricFileFromDisk);
}

CandelaTable loadPhotometricFile(const std::string& path, const PhotometricFileReader& read) {
    const size_t slash = path.find_last_of("/\\");
    const size_t dot = path.find_last_of('.');
    std::string extension = dot == std::string::npos || (slash != std::string::npos && dot < slash)
                                ? std::string()
                                : path.substr(dot);
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char ch) { return char(std::tolower(ch)); });
    if (extension == ".ies") return loadIes(path, read);
    if (extension == ".ldt") return loadEulumdat(path, read);
    throwInputError(SourceLocation{path, 0}, "not a photometric file: the name should end in .ies (IES LM-63) or ",
                    ".ldt (EULUMDAT), not '", extension, "'");
}

namespace photometric {

std::vector<std::string> splitLines(const std::string& text) {
    std::vector<std::string> lines;
    size_t start = text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
    size_t i = start;
    while (i < text.size()) {
        const char ch = text[i];
        if (ch == '\n' || ch == '\r') {
            lines.emplace_back(text, start, i - start);
            i += ch == '\r' && i + 1 < text.size() && text[i + 1] == '\n' ? 2 : 1;
            start = i;
        } else {
            ++i;
        }
    }
    if (start < text.size()) lines.emplace_back(text, start);
    return lines;
}

bool parseNumber(std::string_view token, double& value) {
    // from_chars takes no '+' sign; a lone or doubled sign is still refused.
    if (token.size() > 1 && token[0] == '+' && token[1] != '-' && token[1] != '+') token.remove_prefix(1);
    if (token.empty()) return false;
    const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
    return error == std::errc() && end == token.data() + token.size() && std::isfinite(value);
}

TokenStream::TokenStream(const std::vector<std::string>& lines, size_t firstLine, std::string file,
                         bool commaSeparates)
    : lines_(lines), row_(firstLine), file_(std::move(file)), commaSeparates_(commaSeparates),
      line_(int(std::min(firstLine, lines.size()))) {}

bool TokenStream::next(std::string& token, int& line) {
    const auto separator = [&](char ch) {
        return ch == ' ' || ch == '\t' || ch == '\f' || ch == '\v' || ch == '\x1A' || (commaSeparates_ && ch == ',');
    };
    while (row_ < lines_.size()) {
        const std::string& text = lines_[row_];
        while (col_ < text.size() && separator(text[col_])) ++col_;
        if (col_ == text.size()) {
            ++row_;
            col_ = 0;
            continue;
        }
        const size_t begin = col_;
        while (col_ < text.size() && !separator(text[col_])) ++col_;
        token.assign(text, begin, col_ - begin);
        if (!commaSeparates_) std::replace(token.begin(), token.end(), ',', '.');
        line = line_ = int(row_ + 1);
        return true;
    }
    return false;
}

double TokenStream::number(const std::string& what) {
    std::string token;
    int line = 0;
    if (!next(token, line)) throwInputError(at(lastLine()), "the file ends before ", what);
    double value = 0;
    if (!parseNumber(token, value))
        throwInputError(at(line), what, ": expected a finite number, found ", photometric::quoted(token));
    return value;
}

void TokenStream::expectEnd(const std::string& after) {
    std::string token;
    int line = 0;
    if (next(token, line)) throwInputError(at(line), "unexpected ", photometric::quoted(token), " after ", after);
}

int TokenStream::count(const std::string& what, int lo, int hi) {
    const double value = number(what);
    if (value != std::floor(value) || value < lo || value > hi)
        throwInputError(at(line_), what, " is ", value, ": expected a whole number from ", lo, " to ", hi);
    return int(value);
}

std::vector<double> readAngles(TokenStream& in, int n, const std::string& what, double lo, double hi) {
    std::vector<double> angles;
    for (int i = 0; i < n; ++i) {
        const double a = in.number(concat(what, " ", i + 1, " of ", n));
        if (a < lo || a > hi)
            throwInputError(in.at(in.line()), what, " ", i + 1, " of ", n, " is ", a, ": outside [", lo, ", ", hi,
                            "] degrees");
        if (!angles.empty() && !(a - angles.back() >= kMinAngleStep))
            throwInputError(in.at(in.line()), what, " ", i + 1, " of ", n, " is ", a, " after ", angles.back(),
                            ": angles must ascend");
        angles.push_back(a);
    }
    return angles;
}

std::vector<double> readIntensities(TokenStream& in, size_t total, const std::string& what, double scale,
                                    const std::string& expected) {
    std::vector<double> values;
    std::string token;
    int line = 0;
    for (size_t k = 0; k < total; ++k) {
        if (!in.next(token, line))
            throwInputError(in.at(in.lastLine()), "the file ends before ", what, " ", k + 1, " of ", total, ": found ", k,
                            ", expected ", expected);
        double v = 0;
        if (!parseNumber(token, v))
            throwInputError(in.at(line), what, " ", k + 1, " of ", total, ": expected a finite number, found ",
                            photometric::quoted(token));
        if (v < 0) throwInputError(in.at(line), what, " ", k + 1, " of ", total, " is negative: ", v);
        v *= scale;
        if (!(v <= kMaxCandela))
            throwInputError(in.at(line), what, " ", k + 1, " of ", total, " is ", v,
                            " cd after the multipliers: above 1e15 cd, not a luminaire");
        values.push_back(v);
    }
    return values;
}

std::string quoted(const std::string& token) {
    return "'" + (token.size() > 40 ? token.substr(0, 40) + "..." : token) + "'";
}

}  // namespace photometric

}  // namespace ml
