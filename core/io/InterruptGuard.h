// Ctrl-C and `kill` for long runs: while a guard lives, the first SIGINT or
// SIGTERM asks the work to end cleanly (the loop polls interrupted() or
// hands flag() to a cancellable loop) so that what is done so far is
// written; a second one ends the process at once with status 130, after
// removing the temporaries of the output files being written
// (removePendingOutputs, AtomicFile.h), so no partial file is left.
//
// A second signal counts only kSecondSignalSeconds or more after the first:
// `timeout` sends its signal to the process and again to its group, and a
// shell may do the same, microseconds apart; that is one request, not two.
//
// It lives in core/io, beside AtomicFile, because the two work together
// (the handler removes the pending temporaries), and because `render`,
// `reference` (viewer/cli) and the viewer's frame loop (viewer/window) all
// use it: core is what both link.
#pragma once

#include <atomic>
#include <csignal>

namespace ml {

class InterruptGuard {
public:
    // Seconds after the first signal from which another one ends the process.
    static constexpr double kSecondSignalSeconds = 0.25;

    InterruptGuard();   // installs the handler for SIGINT and SIGTERM; no interrupt seen yet
    ~InterruptGuard();  // puts the previous handlers back
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;

    bool interrupted() const { return flag().load(); }
    // The flag the handler sets, for loops that take a stop flag
    // (RenderControl::stop). Valid while the guard lives.
    const std::atomic<bool>& flag() const;
    // "SIGINT" or "SIGTERM": the first signal seen; "" before any.
    const char* signalName() const;

private:
    struct sigaction previousInt_ {};
    struct sigaction previousTerm_ {};
};

}  // namespace ml
