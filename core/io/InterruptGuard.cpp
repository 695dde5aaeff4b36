#include "InterruptGuard.h"

#include "AtomicFile.h"

#include <unistd.h>

#include <ctime>

namespace ml {

namespace {

// Only async-signal-safe calls in the handler.
std::atomic<bool> gInterrupted{false};
std::atomic<int> gFirstSignal{0};
std::atomic<long long> gFirstInterruptNs{0};

long long monotonicNs() {
    timespec t{};
    ::clock_gettime(CLOCK_MONOTONIC, &t);
    return (long long)t.tv_sec * 1000000000LL + t.tv_nsec;
}

extern "C" void onInterrupt(int signal) {
    const long long now = monotonicNs();
    if (!gInterrupted.exchange(true)) {
        gFirstSignal.store(signal);
        gFirstInterruptNs.store(now);
        return;
    }
    if (now - gFirstInterruptNs.load() >= (long long)(InterruptGuard::kSecondSignalSeconds * 1e9)) {
        removePendingOutputs();
        ::_exit(130);
    }
}

}  // namespace

InterruptGuard::InterruptGuard() {
    static_assert(std::atomic<long long>::is_always_lock_free && std::atomic<int>::is_always_lock_free,
                  "the handler needs lock-free atomics");
    gInterrupted.store(false);
    gFirstSignal.store(0);
    struct sigaction sa {};
    sa.sa_handler = onInterrupt;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;
    sigaction(SIGINT, &sa, &previousInt_);
    sigaction(SIGTERM, &sa, &previousTerm_);
}

InterruptGuard::~InterruptGuard() {
    sigaction(SIGINT, &previousInt_, nullptr);
    sigaction(SIGTERM, &previousTerm_, nullptr);
}

const std::atomic<bool>& InterruptGuard::flag() const { return gInterrupted; }

const char* InterruptGuard::signalName() const {
    switch (gFirstSignal.load()) {
        case SIGINT: return "SIGINT";
        case SIGTERM: return "SIGTERM";
        default: return "";
    }
}

}  // namespace ml
