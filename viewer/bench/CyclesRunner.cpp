#include "CyclesRunner.h"

#include "BenchRun.h"  // secondsSince

#include "core/Error.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <vector>

#ifndef MESHLIGHT_SOURCE_DIR
#define MESHLIGHT_SOURCE_DIR "."
#endif

extern char** environ;

namespace ml {

namespace fs = std::filesystem;

namespace {

// `name` as execvp would find it: itself when it holds a '/', else the first
// executable file of that name on PATH; "" when none.
std::string onPath(const std::string& name) {
    if (name.find('/') != std::string::npos) return ::access(name.c_str(), X_OK) == 0 ? name : std::string();
    const char* path = std::getenv("PATH");
    std::stringstream dirs(path ? path : "");
    for (std::string dir; std::getline(dirs, dir, ':');) {
        const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
        std::error_code ec;
        if (fs::is_regular_file(candidate, ec) && ::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    }
    return {};
}

// "key=value" among the words of an answer, as a number; throws when missing.
double field(const std::string& answer, const std::string& key) {
    const size_t at = answer.find(" " + key + "=");
    if (at == std::string::npos) throw std::runtime_error(concat("Blender's answer '", answer, "' has no ", key));
    return std::atof(answer.c_str() + at + key.size() + 2);
}

std::string cameraArgument(const Camera& c) {
    std::ostringstream s;
    s.precision(17);
    s << c.position.x << "," << c.position.y << "," << c.position.z << "," << c.target.x << "," << c.target.y << ","
      << c.target.z << "," << c.up.x << "," << c.up.y << "," << c.up.z << "," << c.fovYDegrees;
    return s.str();
}

}  // namespace

std::optional<CyclesSetup> findCycles(std::string& why) {
    const char* env = std::getenv("MESHLIGHT_BLENDER");
    std::string name = "blender";
    if (env) {
        name = env;
        if (name.empty() || name == "none") {
            why = "MESHLIGHT_BLENDER is empty or 'none'";
            return std::nullopt;
        }
    }
    CyclesSetup setup;
    setup.blender = onPath(name);
    if (setup.blender.empty()) {
        why = env ? concat("MESHLIGHT_BLENDER names '", name, "', which is not an executable")
                  : std::string("'blender' is not on PATH (Debian: apt-get install blender)");
        return std::nullopt;
    }
    const fs::path source(MESHLIGHT_SOURCE_DIR);
    setup.script = source / "viewer/bench/cycles/cornell_cycles.py";
    setup.obj = source / "data/cornell_box.obj";
    std::error_code ec;
    for (const fs::path& p : {setup.script, setup.obj})
        if (!fs::is_regular_file(p, ec)) {
            why = concat(p.string(), " is missing (the source tree this binary was built from)");
            return std::nullopt;
        }
    return setup;
}

CyclesRunner::CyclesRunner(const CyclesSetup& setup, int bounces, int threads, const fs::path& log) {
    log_ = std::fopen(log.c_str(), "w");
    if (!log_) throw std::runtime_error(concat("cannot write ", log.string()));
    int in[2], out[2];
    if (::pipe(in) != 0) throw std::runtime_error("pipe failed");
    if (::pipe(out) != 0) {
        ::close(in[0]);
        ::close(in[1]);
        throw std::runtime_error("pipe failed");
    }
    // The parent's ends are not inherited.
    ::fcntl(in[1], F_SETFD, FD_CLOEXEC);
    ::fcntl(out[0], F_SETFD, FD_CLOEXEC);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, in[0], 0);
    posix_spawn_file_actions_adddup2(&actions, out[1], 1);
    posix_spawn_file_actions_adddup2(&actions, out[1], 2);
    const std::vector<std::string> args = {setup.blender,
                                           "-b",
                                           "--factory-startup",
                                           "--python",
                                           setup.script.string(),
                                           "--",
                                           "--obj",
                                           setup.obj.string(),
                                           "--out",
                                           (log.parent_path() / "cycles_unused.exr").string(),
                                           "--bounces",
                                           std::to_string(bounces),
                                           "--threads",
                                           std::to_string(threads),
                                           "--serve"};
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    std::fprintf(log_, "+");
    for (const std::string& a : args) std::fprintf(log_, " %s", a.c_str());
    std::fprintf(log_, "\n");
    const auto start = std::chrono::steady_clock::now();
    const int rc = posix_spawn(&pid_, setup.blender.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(in[0]);
    ::close(out[1]);
    if (rc != 0) {
        ::close(in[1]);
        ::close(out[0]);
        pid_ = -1;
        std::fclose(log_);
        throw std::runtime_error(concat("cannot start ", setup.blender, ": ", std::strerror(rc)));
    }
    toBlender_ = in[1];
    fromBlender_ = ::fdopen(out[0], "r");
    // A Blender that ends early must not end the bench by SIGPIPE.
    oldSigpipe_ = ::signal(SIGPIPE, SIG_IGN);
    try {
        const std::string ready = nextAnswer();
        if (ready.rfind("ready", 0) != 0) throw std::runtime_error(concat("Blender answered '", ready, "'"));
        const size_t v = ready.find("blender=");
        version_ = v == std::string::npos ? std::string("?") : ready.substr(v + 8, ready.find(' ', v) - v - 8);
    } catch (...) {
        shutdown();
        throw;
    }
    startup_ = secondsSince(start);
}

CyclesRunner::~CyclesRunner() { shutdown(); }

void CyclesRunner::shutdown() {
    if (toBlender_ >= 0) {
        const char quit[] = "quit\n";
        [[maybe_unused]] const ssize_t n = ::write(toBlender_, quit, sizeof quit - 1);
        ::close(toBlender_);
        toBlender_ = -1;
    }
    if (fromBlender_) {
        // Blender's last words go to the log.
        char buffer[4096];
        while (std::fgets(buffer, sizeof buffer, fromBlender_))
            if (log_) std::fputs(buffer, log_);
        std::fclose(fromBlender_);
        fromBlender_ = nullptr;
    }
    if (pid_ > 0) {
        int status = 0;
        ::waitpid(pid_, &status, 0);
        pid_ = -1;
    }
    if (log_) {
        std::fclose(log_);
        log_ = nullptr;
    }
    if (oldSigpipe_) {
        ::signal(SIGPIPE, oldSigpipe_);
        oldSigpipe_ = nullptr;
    }
}

std::string CyclesRunner::nextAnswer() {
    char buffer[8192];
    while (fromBlender_ && std::fgets(buffer, sizeof buffer, fromBlender_)) {
        if (log_) {
            std::fputs(buffer, log_);
            std::fflush(log_);
        }
        std::string line(buffer);
        while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
        const std::string prefix = "@@cycles ";
        if (line.rfind(prefix, 0) != 0) continue;
        line = line.substr(prefix.size());
        if (line.rfind("error", 0) == 0) throw std::runtime_error(concat("Blender: ", line));
        return line;
    }
    throw std::runtime_error("Blender ended before it answered; its output is in the bench's cycles log");
}

CyclesRender CyclesRunner::render(const Camera& camera, int width, int height, int spp, uint32_t seed,
                                  const fs::path& exr) {
    const std::string job =
        concat("render ", exr.string(), " ", spp, " ", width, " ", height, " ", cameraArgument(camera), " ", seed, "\n");
    if (exr.string().find(' ') != std::string::npos)
        throw std::runtime_error(concat("Cycles' output path '", exr.string(), "' holds a space"));
    if (::write(toBlender_, job.data(), job.size()) != ssize_t(job.size()))
        throw std::runtime_error("Blender stopped reading its jobs; its output is in the bench's cycles log");
    const std::string done = nextAnswer();
    if (done.rfind("done ", 0) != 0) throw std::runtime_error(concat("Blender answered '", done, "'"));
    CyclesRender r;
    r.spp = spp;
    r.seconds = field(done, "wall");
    r.cpuSeconds = field(done, "cpu");
    r.pathSeconds = field(done, "path");
    r.saveSeconds = field(done, "save");
    r.image = readImageLinear(exr.string());
    if (r.image.width != width || r.image.height != height)
        throw std::runtime_error(concat(exr.string(), ": ", r.image.width, "x", r.image.height, ", not ", width, "x",
                                        height));
    return r;
}

}  // namespace ml
