#include "BenchRun.h"

#include "core/Error.h"
#include "core/io/AtomicFile.h"
#include "gpu_sampling/gl/GlContext.h"

#include <sys/utsname.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <thread>

namespace ml {

namespace {

// The first "KEY : value" line of a /proc file with that key, or "".
std::string procField(const char* file, const std::string& key) {
    std::ifstream in(file);
    std::string line;
    while (std::getline(in, line)) {
        const size_t colon = line.find(':');
        if (colon == std::string::npos) continue;
        std::string k = line.substr(0, colon);
        k.erase(k.find_last_not_of(" \t") + 1);
        if (k != key) continue;
        const size_t v = line.find_first_not_of(" \t", colon + 1);
        return v == std::string::npos ? std::string() : line.substr(v);
    }
    return {};
}

}  // namespace

BenchRun::BenchRun(const BenchOptions& options)
    : options_(options), dir_(options.outDir), start_(std::chrono::steady_clock::now()), loadAtStart_(loadAverage()) {
    makeOutputDirectory(options.outDir);
}

std::unique_ptr<GlContext> BenchRun::openContext() {
    std::unique_ptr<GlContext> context = createHeadlessContext(options_.backend);
    gl_ = context->describe();
    std::printf("OpenGL: %s\n", gl_.c_str());
    return context;
}

double BenchRun::seconds() const { return secondsSince(start_); }

void BenchRun::progress(const char* format, ...) const {
    std::fprintf(stderr, "[%6.1f s] ", seconds());
    va_list args;
    va_start(args, format);
    std::vfprintf(stderr, format, args);
    va_end(args);
}

void BenchRun::write(const std::string& name, const std::string& text) const {
    writeTextFileAtomically((dir_ / name).string(), text);
}

bool BenchRun::plot(const std::string& scriptName, const std::string& script,
                    const std::vector<GnuplotOutput>& outputs) const {
    return runGnuplotScript(dir_, scriptName, script, outputs);
}

void BenchRun::printWallTime(double wallSeconds) const {
    std::printf("Wall time %.1f s; files in %s\n", wallSeconds, dir_.string().c_str());
}

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string loadAverage() {
    std::ifstream in("/proc/loadavg");
    std::string one;
    in >> one;
    return one;
}

void runSelf(const std::string& args, const std::filesystem::path& log) {
    const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
    const std::string command = shellQuoted(self) + " " + args + " > " + shellQuoted(log.string()) + " 2>&1";
    const int status = std::system(command.c_str());
    if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
        throw std::runtime_error(concat("'meshlight ", args, "' failed; its output is in ", log.string()));
}

std::string softwareRasteriserNote(const std::string& glDescription) {
    if (glDescription.find("llvmpipe") == std::string::npos && glDescription.find("softpipe") == std::string::npos)
        return {};
    return "- timings come from Mesa's software rasteriser on the CPU, not from a GPU\n";
}

std::string describeMachine() {
    std::string cpu = procField("/proc/cpuinfo", "model name");
    if (cpu.empty()) cpu = "unknown CPU";
    std::string machine = concat(cpu, ", ", std::thread::hardware_concurrency(), " hardware threads");
    const std::string mem = procField("/proc/meminfo", "MemTotal");  // "131900000 kB"
    if (!mem.empty()) machine += concat(", ", std::llround(std::atof(mem.c_str()) / 1048576.0), " GiB memory");
    utsname u{};
    if (::uname(&u) == 0) machine += concat(", ", u.sysname, " ", u.release, " ", u.machine);
    return machine;
}

}  // namespace ml
