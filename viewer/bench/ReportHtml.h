// Small HTML building blocks for the bench report: escaping, CSV tables
// and the subset of Markdown the benches' summaries use. Plain HTML with no
// script, so the page reads the same in any browser or none.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace ml {

// Text as HTML character data or a quoted attribute value: & < > " ' escaped.
std::string htmlEscape(std::string_view text);

// A parsed CSV file: a header row and rows of as many cells.
struct CsvTable {
    std::vector<std::string> header;
    std::vector<std::vector<std::string>> rows;

    // Index of a header cell; throws InputError naming `name` when absent.
    size_t column(const std::string& name) const;
};

// RFC 4180 CSV: comma-separated, optionally double-quoted cells ("" is a
// quote inside one), LF or CRLF line ends, the first row the header. Throws
// InputError "FILE:LINE: ..." for a row with a different number of cells or
// an unterminated quote; `file` only names the source in messages.
CsvTable parseCsv(const std::string& text, const std::string& file);

// An HTML <table> of the given columns of `csv`, in that order (all when
// `columns` is empty); a column missing from the CSV is an InputError.
// Cells that read as numbers are right-aligned (class "num").
std::string htmlTable(const CsvTable& csv, const std::vector<std::string>& columns = {});

// The Markdown of the bench summaries as HTML: "#"-headings (shifted down by
// `headingShift` levels, at most <h6>), "- " bullet lists, pipe tables with
// a |---| separator row, paragraphs, and inline `code` and **bold**.
// Everything else is text, escaped: no raw HTML passes through.
std::string markdownToHtml(const std::string& markdown, int headingShift = 0);

}  // namespace ml
