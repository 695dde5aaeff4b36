// Ctrl-C for the frame loop: while a guard lives, the first SIGINT asks
// the loop to end cleanly (it polls interrupted()); a second one, a second
// or more later, ends the process at once with status 130. (Not sooner:
// `timeout` and some shells send one interrupt to the process and again to
// its group, which would otherwise count as two.)
#pragma once

#include <csignal>

namespace ml {

class InterruptGuard {
public:
    InterruptGuard();   // installs the handler; no interrupt seen yet
    ~InterruptGuard();  // puts the previous handler back
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;

    bool interrupted() const;

private:
    struct sigaction previous_ {};
};

}  // namespace ml
