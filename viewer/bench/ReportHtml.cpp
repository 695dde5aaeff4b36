#include "ReportHtml.h"

#include "core/Error.h"

#include <algorithm>
#include <cstdlib>
#include <sstream>

namespace ml {

std::string htmlEscape(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (char c : text) {
        switch (c) {
            case '&': out += "&amp;"; break;
            case '<': out += "&lt;"; break;
            case '>': out += "&gt;"; break;
            case '"': out += "&quot;"; break;
            case '\'': out += "&#39;"; break;
            default: out += c;
        }
    }
    return out;
}

// --- CSV ----------------------------------------------------------------------------

size_t CsvTable::column(const std::string& name) const {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw InputError(concat("CSV has no column '", name, "'"));
    return size_t(it - header.begin());
}

CsvTable parseCsv(const std::string& text, const std::string& file) {
    std::vector<std::vector<std::string>> rows;
    std::vector<int> rowLines;  // line each row starts on, for messages
    std::vector<std::string> row;
    std::string cell;
    bool quoted = false, rowHasContent = false;
    int line = 1, rowLine = 1;
    auto endCell = [&] {
        row.push_back(std::move(cell));
        cell.clear();
    };
    auto endRow = [&] {
        endCell();
        // A blank line is no row (a file's last line end included).
        if (rowHasContent || row.size() > 1) {
            rows.push_back(std::move(row));
            rowLines.push_back(rowLine);
        }
        row.clear();
        rowHasContent = false;
    };
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (quoted) {
            if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
                cell += '"';
                ++i;
            } else if (c == '"') {
                quoted = false;
            } else {
                if (c == '\n') ++line;
                cell += c;
            }
            continue;
        }
        if (c == '"') {
            quoted = true;
            rowHasContent = true;
        } else if (c == ',') {
            endCell();
        } else if (c == '\n' || c == '\r') {
            if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
            endRow();
            rowLine = ++line;
        } else {
            cell += c;
            rowHasContent = true;
        }
    }
    if (quoted) throwInputError(SourceLocation{file, rowLine}, "unterminated quoted cell");
    endRow();
    if (rows.empty()) throwInputError(SourceLocation{file}, "empty CSV: no header row");
    CsvTable table;
    table.header = std::move(rows.front());
    for (size_t r = 1; r < rows.size(); ++r) {
        if (rows[r].size() != table.header.size())
            throwInputError(SourceLocation{file, rowLines[r]}, rows[r].size(), " cells, but the header has ",
                            table.header.size());
        table.rows.push_back(std::move(rows[r]));
    }
    return table;
}

namespace {

bool looksNumeric(const std::string& s) {
    if (s.empty()) return false;
    char* end = nullptr;
    std::strtod(s.c_str(), &end);
    return end && *end == '\0';
}

// A header cell may break after an underscore ("per_<wbr>sample_<wbr>ms"):
// wide CSV tables then fit the page instead of scrolling.
std::string breakAfterUnderscores(const std::string& html) {
    std::string out;
    for (char c : html) {
        out += c;
        if (c == '_') out += "<wbr>";
    }
    return out;
}

std::string cellTag(const char* tag, const std::string& html, bool numeric) {
    return concat("<", tag, numeric ? " class=\"num\"" : "", ">", html, "</", tag, ">");
}

}  // namespace

std::string htmlTable(const CsvTable& csv, const std::vector<std::string>& columns) {
    std::vector<size_t> picked;
    if (columns.empty())
        for (size_t c = 0; c < csv.header.size(); ++c) picked.push_back(c);
    else
        for (const std::string& name : columns) picked.push_back(csv.column(name));
    std::ostringstream os;
    os << "<table>\n<thead><tr>";
    for (size_t c : picked) os << cellTag("th", breakAfterUnderscores(htmlEscape(csv.header[c])), false);
    os << "</tr></thead>\n<tbody>\n";
    for (const auto& row : csv.rows) {
        os << "<tr>";
        for (size_t c : picked) os << cellTag("td", htmlEscape(row[c]), looksNumeric(row[c]));
        os << "</tr>\n";
    }
    os << "</tbody>\n</table>\n";
    return os.str();
}

// --- Markdown subset -------------------------------------------------------------------

namespace {

// `code` and **bold**; an unmatched marker is text.
std::string inlineHtml(std::string_view s) {
    std::string out;
    for (size_t i = 0; i < s.size();) {
        if (s[i] == '`') {
            const size_t close = s.find('`', i + 1);
            if (close != std::string_view::npos) {
                out += "<code>" + htmlEscape(s.substr(i + 1, close - i - 1)) + "</code>";
                i = close + 1;
                continue;
            }
        } else if (s.compare(i, 2, "**") == 0) {
            const size_t close = s.find("**", i + 2);
            if (close != std::string_view::npos) {
                out += "<strong>" + inlineHtml(s.substr(i + 2, close - i - 2)) + "</strong>";
                i = close + 2;
                continue;
            }
        }
        out += htmlEscape(s.substr(i, 1));
        ++i;
    }
    return out;
}

std::string trim(const std::string& s) {
    const size_t a = s.find_first_not_of(" \t\r");
    if (a == std::string::npos) return {};
    const size_t b = s.find_last_not_of(" \t\r");
    return s.substr(a, b - a + 1);
}

// "| a | b |" -> {"a", "b"}
std::vector<std::string> pipeCells(const std::string& line) {
    std::string s = trim(line);
    if (!s.empty() && s.front() == '|') s.erase(0, 1);
    if (!s.empty() && s.back() == '|') s.pop_back();
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream is(s);
    while (std::getline(is, cell, '|')) cells.push_back(trim(cell));
    if (!s.empty() && s.back() == '|') cells.push_back({});
    return cells;
}

bool isSeparatorRow(const std::vector<std::string>& cells) {
    if (cells.empty()) return false;
    for (const std::string& c : cells)
        if (c.empty() || c.find_first_not_of("-: ") != std::string::npos) return false;
    return true;
}

}  // namespace

std::string markdownToHtml(const std::string& markdown, int headingShift) {
    std::ostringstream os;
    enum class Block { None, Paragraph, List, Table } block = Block::None;
    bool tableHeaderDone = false;
    auto close = [&] {
        if (block == Block::Paragraph) os << "</p>\n";
        if (block == Block::List) os << "</ul>\n";
        if (block == Block::Table) os << "</tbody>\n</table>\n</div>\n";
        block = Block::None;
    };
    std::istringstream is(markdown);
    std::string raw;
    while (std::getline(is, raw)) {
        const std::string line = trim(raw);
        if (line.empty()) {
            close();
            continue;
        }
        const size_t hashes = line.find_first_not_of('#');
        if (hashes > 0 && hashes <= 6 && hashes != std::string::npos && line[hashes] == ' ') {
            close();
            const int level = std::min(6, int(hashes) + std::max(0, headingShift));
            os << "<h" << level << ">" << inlineHtml(trim(line.substr(hashes))) << "</h" << level << ">\n";
        } else if (line.rfind("- ", 0) == 0) {
            if (block != Block::List) {
                close();
                os << "<ul>\n";
                block = Block::List;
            }
            os << "<li>" << inlineHtml(line.substr(2)) << "</li>\n";
        } else if (line.front() == '|') {
            const std::vector<std::string> cells = pipeCells(line);
            if (block != Block::Table) {
                close();
                // Wide tables scroll inside their box rather than widen the page.
                os << "<div class=\"scroll\">\n<table>\n<thead><tr>";
                for (const std::string& c : cells) os << "<th>" << breakAfterUnderscores(inlineHtml(c)) << "</th>";
                os << "</tr></thead>\n<tbody>\n";
                block = Block::Table;
                tableHeaderDone = false;
            } else if (!tableHeaderDone && isSeparatorRow(cells)) {
                tableHeaderDone = true;
            } else {
                tableHeaderDone = true;
                os << "<tr>";
                for (const std::string& c : cells) os << cellTag("td", inlineHtml(c), looksNumeric(c));
                os << "</tr>\n";
            }
        } else {
            if (block != Block::Paragraph) {
                close();
                os << "<p>";
                block = Block::Paragraph;
            } else {
                os << "\n";
            }
            os << inlineHtml(line);
        }
    }
    close();
    return os.str();
}

}  // namespace ml
