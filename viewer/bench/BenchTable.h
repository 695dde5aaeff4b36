// A bench table: printed aligned on stdout, written as CSV and shown as a
// Markdown table in a summary, all from the same cells, so they never
// disagree; and the number formats benches share.
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
    // A pipe table with a |---| separator row under the header, as
    // ReportHtml's markdownToHtml reads it.
    std::string markdown() const;

private:
    std::vector<std::string> header_;
    std::vector<std::vector<std::string>> rows_;
};

// Four significant digits ("0.09712", "1.234e+05"): far finer than the
// run-to-run noise of timings.
std::string benchNumber(double v);
// The cells of the "_pct" and "_ms" columns, four significant digits: a
// fraction as a percentage (0.01234 -> "1.234"), seconds as milliseconds
// (0.01234 -> "12.34").
std::string benchPct(double fraction);
std::string benchMs(double seconds);
// "yes" or "no": a table's answer to a target or a condition.
std::string benchYesNo(bool b);

// One row of a bench's targets table: the target, what was
// measured, and whether it is met (or why not judged).
struct BenchTarget {
    std::string target, value, status;
};
// The table of `rows`: columns target, value, status.
BenchTable targetsTable(const std::vector<BenchTarget>& rows);

}  // namespace ml
