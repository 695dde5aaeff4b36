// Running a command from a test, the `meshlight` binary above all: its exit
// status and everything it printed, for tests that check what a user sees
// (test_cli.cpp, test_path_tracer.cpp, test_view_window.cpp).
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace ml::test {

// What a finished command left behind.
struct CommandResult {
    // The exit status, 0..255 (meshlight: 0 done, 2 input refused, 1 any
    // other failure); -1 when the command could not be started or was ended
    // by a signal instead of exiting.
    int status = -1;
    // Standard output and standard error together, interleaved in the order
    // the command wrote them (both go to one pipe).
    std::string output;
};

// Runs `command` through /bin/sh (so quoting, redirections and wrappers such
// as `env -u DISPLAY` or `timeout` work) and waits for it to exit. There is
// no time limit of its own: wrap a command that may hang in `timeout`.
inline CommandResult runCommand(const std::string& command) {
    CommandResult r;
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (!pipe) return r;
    std::array<char, 4096> buffer;
    size_t n;
    while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) r.output.append(buffer.data(), n);
    const int s = pclose(pipe);
    r.status = s != -1 && WIFEXITED(s) ? WEXITSTATUS(s) : -1;
    return r;
}

// The shell command that runs the binary under test (MESHLIGHT_BINARY, set
// by tests/CMakeLists.txt) with `args`, e.g. "render cornell --out x.png".
inline std::string meshlightCommand(const std::string& args) { return std::string(MESHLIGHT_BINARY) + " " + args; }

// Runs the binary under test with `args`: runCommand(meshlightCommand(args)).
inline CommandResult runMeshlight(const std::string& args) { return runCommand(meshlightCommand(args)); }

}  // namespace ml::test
