#include "InterruptGuard.h"

#include <unistd.h>

#include <atomic>
#include <ctime>

namespace ml {

namespace {

// Only async-signal-safe calls in the handler.
std::atomic<bool> gInterrupted{false};
std::atomic<long long> gFirstInterruptNs{0};

long long monotonicNs() {
    timespec t{};
    ::clock_gettime(CLOCK_MONOTONIC, &t);
    return (long long)t.tv_sec * 1000000000LL + t.tv_nsec;
}

extern "C" void onSigint(int) {
    const long long now = monotonicNs();
    if (!gInterrupted.exchange(true)) {
        gFirstInterruptNs.store(now);
        return;
    }
    if (now - gFirstInterruptNs.load() > 1000000000LL) ::_exit(130);
}

}  // namespace

InterruptGuard::InterruptGuard() {
    static_assert(std::atomic<long long>::is_always_lock_free, "the handler needs lock-free atomics");
    gInterrupted.store(false);
    struct sigaction sa {};
    sa.sa_handler = onSigint;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;
    sigaction(SIGINT, &sa, &previous_);
}

InterruptGuard::~InterruptGuard() { sigaction(SIGINT, &previous_, nullptr); }

bool InterruptGuard::interrupted() const { return gInterrupted.load(); }

}  // namespace ml
