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

// The header line, then `afterHeader` as it is, then a line per row: each
// line's cells written by `cells`, then a line break. Every format of a
// table is this, with its own way of writing the cells of one line.
template <typename Cells>
std::string tableText(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
                      const std::string& afterHeader, Cells cells) {
    std::ostringstream os;
    cells(os, header);
    os << "\n" << afterHeader;
    for (const auto& row : rows) {
        cells(os, row);
        os << "\n";
    }
    return os.str();
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
    return tableText(header_, rows_, "", [&](std::ostream& os, const std::vector<std::string>& cells) {
        for (size_t c = 0; c < cells.size(); ++c) {
            const std::string pad(width[c] - cells[c].size(), ' ');
            os << (c ? "  " : "") << (c ? pad + cells[c] : cells[c] + pad);
        }
    });
}

std::string BenchTable::csv() const {
    return tableText(header_, rows_, "", [](std::ostream& os, const std::vector<std::string>& cells) {
        for (size_t c = 0; c < cells.size(); ++c) os << (c ? "," : "") << cells[c];
    });
}

std::string BenchTable::markdown() const {
    std::string separator = "|";
    for (size_t c = 0; c < header_.size(); ++c) separator += "---|";
    return tableText(header_, rows_, separator + "\n", [](std::ostream& os, const std::vector<std::string>& cells) {
        os << "| ";
        for (size_t c = 0; c < cells.size(); ++c) os << (c ? " | " : "") << cells[c];
        os << " |";
    });
}

std::string benchNumber(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

std::string benchPct(double fraction) { return benchNumber(100 * fraction); }

std::string benchMs(double seconds) { return benchNumber(1e3 * seconds); }

std::string benchYesNo(bool b) { return b ? "yes" : "no"; }

BenchTable targetsTable(const std::vector<BenchTarget>& rows) {
    BenchTable t({"target", "value", "status"});
    for (const BenchTarget& r : rows) t.addRow({r.target, r.value, r.status});
    return t;
}

}  // namespace ml
