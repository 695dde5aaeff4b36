// What every bench does at its start and at its end, in one place: make its
// output folder before minutes of work (a bad path fails at once), open its
// headless context, keep its clock and the machine's load, write its tables,
// plots and summary whole into the folder, and end with its wall time.
#pragma once

#include "BenchOptions.h"
#include "BenchTable.h"
#include "Gnuplot.h"

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace ml {

class GlContext;

class BenchRun {
public:
    // Starts the clock, reads the load average and makes options.outDir;
    // throws InputError naming it when it cannot be made.
    explicit BenchRun(const BenchOptions& options);

    // A headless context on options.backend, current on this thread. Prints
    // "OpenGL: ..." and keeps the description for glDescription(). Throws
    // std::runtime_error when none can be made.
    std::unique_ptr<GlContext> openContext();
    const std::string& glDescription() const { return gl_; }  // "" before openContext()

    const BenchOptions& options() const { return options_; }
    const char* mode() const { return options_.quick ? "quick" : "full"; }
    const std::filesystem::path& dir() const { return dir_; }
    double seconds() const;  // wall-clock seconds since the run started
    const std::string& loadAtStart() const { return loadAtStart_; }

    // "[  12.3 s] " and then `format` as printf writes it, on stderr:
    // progress, kept off the tables on stdout.
    void progress(const char* format, ...) const __attribute__((format(printf, 2, 3)));

    // Writes dir()/name whole (AtomicOutput) or not at all.
    void write(const std::string& name, const std::string& text) const;
    void writeCsv(const std::string& name, const BenchTable& table) const { write(name, table.csv()); }
    // runGnuplotScript (Gnuplot.h) in dir(): false, after a note, when gnuplot is missing.
    bool plot(const std::string& scriptName, const std::string& script,
              const std::vector<GnuplotOutput>& outputs) const;

    // "Wall time 12.3 s; files in DIR" and a line break on stdout: every bench's last line.
    void printWallTime(double wallSeconds) const;

private:
    BenchOptions options_;
    std::filesystem::path dir_;
    std::chrono::steady_clock::time_point start_;
    std::string loadAtStart_;
    std::string gl_;
};

// Seconds from `start` to now.
double secondsSince(std::chrono::steady_clock::time_point start);

// The 1-minute load average (/proc/loadavg), "" when unreadable: other
// processes on the machine slow every timing, so summaries state it.
std::string loadAverage();

// Runs this binary (/proc/self/exe) with `args` (already shell-quoted where
// needed) as a user types it, its output into `log`; throws
// std::runtime_error naming the log unless it exits 0.
void runSelf(const std::string& args, const std::filesystem::path& log);

// A summary bullet, "- timings come from Mesa's software rasteriser on the
// CPU, not from a GPU" and a line break, when `glDescription` names llvmpipe
// or softpipe; "" otherwise.
std::string softwareRasteriserNote(const std::string& glDescription);

// "CPU model, N hardware threads, M GiB memory, Linux 6.1.0 x86_64": what
// the report's header says of the machine. Parts that cannot be read are
// left out ("unknown CPU" for the model).
std::string describeMachine();

}  // namespace ml
