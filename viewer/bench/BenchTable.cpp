#include "BenchTable.h"

#include "core/Error.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace ml {

namespace {

void checkCell(const std::string& cell) {
    ML_ASSERT(cell.find_first_of(",\"\n\r") == std::string::npos, "bench table cell '", cell,
              "' holds a comma, quote or line break");
}

}  // namespace

BenchTable::BenchTable(std::vector<std::string> header) : header_(std::move(header)) {
    for (const std::string& h : header_) checkCell(h);
}

void BenchTable::addRow(std::vector<std::string> cells) {
    ML_ASSERT(cells.size() == header_.size(), cells.size(), " cells for ", header_.size(), " columns");
    for (const std::string& c : cells) checkCell(c);
    rows_.push_back(std::move(cells));
}

std::string BenchTable::aligned() const {
    std::vector<size_t> width(header_.size());
    for (size_t c = 0; c < header_.size(); ++c) {
        width[c] = header_[c].size();
        for (const auto& row : rows_) width[c] = std::max(width[c], row[c].size());
    }
    std::ostringstream os;
    auto line = [&](const std::vector<std::string>& cells) {
        for (size_t c = 0; c < cells.size(); ++c) {
            const std::string pad(width[c] - cells[c].size(), ' ');
            os << (c ? "  " : "") << (c ? pad + cells[c] : cells[c] + pad);
        }
        os << "\n";
    };
    line(header_);
    for (const auto& row : rows_) line(row);
    return os.str();
}

std::string BenchTable::csv() const {
    std::ostringstream os;
    auto line = [&](const std::vector<std::string>& cells) {
        for (size_t c = 0; c < cells.size(); ++c) os << (c ? "," : "") << cells[c];
        os << "\n";
    };
    line(header_);
    for (const auto& row : rows_) line(row);
    return os.str();
}

std::string benchNumber(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

}  // namespace ml
