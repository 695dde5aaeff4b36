// A bench table: printed aligned on stdout and written as CSV from the same
// cells, so the two never disagree; and the number format benches share.
#pragma once

#include <string>
#include <vector>

namespace ml {

class BenchTable {
public:
    explicit BenchTable(std::vector<std::string> header);

    // As many cells as header columns; no cell may contain a comma, a quote
    // or a line break (they are CSV cells and gnuplot labels as they are).
    void addRow(std::vector<std::string> cells);

    // First column left-aligned (labels), the others right-aligned (numbers).
    std::string aligned() const;
    std::string csv() const;

private:
    std::vector<std::string> header_;
    std::vector<std::vector<std::string>> rows_;
};

// Four significant digits ("0.09712", "1.234e+05"): far finer than the
// run-to-run noise of timings.
std::string benchNumber(double v);

}  // namespace ml
