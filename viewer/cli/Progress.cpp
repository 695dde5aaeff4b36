#include "Progress.h"

#include <unistd.h>

#include <cstdio>

namespace ml {

Progress::Progress(std::string label, size_t total)
    : label_(std::move(label)), total_(total), terminal_(::isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()) {}

void Progress::update(size_t done) {
    const double fraction = total_ ? double(done) / double(total_) : 1.0;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (terminal_) {
        const int width = 30, filled = int(fraction * width);
        std::fprintf(stderr, "\r%s [%s%s] %3d%% %zu/%zu %.1f s", label_.c_str(), std::string(size_t(filled), '#').c_str(),
                     std::string(size_t(width - filled), ' ').c_str(), int(fraction * 100), done, total_, elapsed);
        std::fflush(stderr);
        return;
    }
    const int decile = int(fraction * 10);
    if (decile > lastDecile_) {
        lastDecile_ = decile;
        std::fprintf(stderr, "%s: %d%% (%zu/%zu, %.1f s)\n", label_.c_str(), decile * 10, done, total_, elapsed);
    }
}

void Progress::finish() {
    if (finished_) return;
    finished_ = true;
    update(total_);
    if (terminal_) std::fputc('\n', stderr);
}

void Progress::abandon() {
    if (finished_) return;
    finished_ = true;
    if (terminal_) std::fputc('\n', stderr);
}

}  // namespace ml
