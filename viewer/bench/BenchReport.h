// `meshlight bench report`: runs the benches and gathers what they wrote
// into one HTML page, DIR/index.html, readable without JavaScript.
//
// The page is a list of sections, one per bench. Each bench writes its CSVs,
// plots and summary into its own folder DIR/<id>/; the section says which
// of those files to show: its Markdown summary, its plots (each with links
// to the CSVs behind it) and its tables (from CSVs). A bench joins the report
// by adding one ReportSection to reportSections(); a bench that does not
// exist yet is simply not listed, and the page names the benches that ran.
#pragma once

#include "BenchOptions.h"

#include <functional>
#include <string>
#include <vector>

namespace ml {

// outDir: index.html and one folder per bench (made if missing); quick:
// every bench in its CI size (seconds, not minutes); backend and seed:
// passed to every bench.
struct BenchReportOptions : BenchOptions {
    BenchReportOptions() { outDir = "bench-report"; }
    std::string commandLine;  // shown in the page's header, as typed
};

// A plot a bench wrote, and the data behind it. File names are relative to
// the bench's folder.
struct ReportFigure {
    std::string png;
    std::string caption;            // plain text
    std::vector<std::string> data;  // CSVs holding the plotted values
};

// A CSV a bench wrote, shown as an HTML table.
struct ReportTable {
    std::string csv;
    std::string caption;               // plain text
    std::vector<std::string> columns;  // shown, in this order; empty: all
};

struct ReportSection {
    std::string id;     // folder and anchor: lower-case letters, digits and '-'
    std::string title;  // plain text
    std::string about;  // one paragraph on what the bench measures, plain text
    // Runs the bench with the report's options, outDir its own folder
    // (outDir/<id>, made if missing), and returns its exit code; may throw.
    std::function<int(const BenchOptions&)> run;
    std::string summary;  // a Markdown file the bench writes, shown first; "" for none
    std::vector<ReportFigure> figures;
    std::vector<ReportTable> tables;
};

// The benches of the report, in page order.
std::vector<ReportSection> reportSections();

// Runs `sections` in order, each into outDir/<id>/, then writes
// outDir/index.html (atomically). A section that throws or returns non-zero
// is reported on the page as failed, with its message, and the others still
// run. Returns 0 when every section ran, 1 otherwise. Throws InputError when
// outDir cannot be made or written.
int runBenchReport(const BenchReportOptions& options, const std::vector<ReportSection>& sections);
inline int runBenchReport(const BenchReportOptions& options) { return runBenchReport(options, reportSections()); }

}  // namespace ml
