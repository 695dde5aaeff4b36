#include "FrameStatistics.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace ml {

void FrameStatistics::add(const FrameRecord& f, double end) {
    if (firstFrame_ < 0) firstFrame_ = end;
    if (firstLitFrame_ < 0 && f.snapshot) firstLitFrame_ = end;
    frameMsAverage_ = frameMsAverage_ > 0 ? 0.9 * frameMsAverage_ + 0.1 * f.seconds * 1e3 : f.seconds * 1e3;
    composeMsAverage_ = composeMsAverage_ > 0 ? 0.9 * composeMsAverage_ + 0.1 * f.composeMs : f.composeMs;
    frames_.push_back(f);
}

void FrameStatistics::printStatus(double seconds, size_t vertices, uint64_t samples, double estimatedError,
                                  const std::string& lights, bool now) {
    if (!now && seconds - lastStatus_ < 1.0) return;
    static const bool terminal = ::isatty(STDERR_FILENO) != 0;
    lastStatus_ = seconds;
    // The cache reads 100% until every light and every bounce has its first
    // pass: not an error of the image shown (which the stand-in or the old
    // light fill), but none estimated yet.
    char error[48];
    if (estimatedError >= 1)
        std::snprintf(error, sizeof error, "error not estimated yet");
    else
        std::snprintf(error, sizeof error, "estimated error %.3g%%", 100 * estimatedError);
    std::fprintf(stderr, "%sview %.1f s: %zu vertices, %llu samples, %s, %.0f frames/s; %s%s", terminal ? "\r" : "",
                 seconds, vertices, static_cast<unsigned long long>(samples), error,
                 frameMsAverage_ > 0 ? 1e3 / frameMsAverage_ : 0.0, lights.c_str(), terminal ? "   " : "\n");
    std::fflush(stderr);
}

void FrameStatistics::printSummary() const {
    if (frames_.empty()) return;
    std::vector<double> ms;
    for (const FrameRecord& f : frames_) ms.push_back(1e3 * f.seconds);
    std::sort(ms.begin(), ms.end());
    std::printf("view: %zu frames drawn, median %.1f ms, 95th percentile %.1f ms; first frame after %.2f s, "
                "first lit frame after %.2f s\n",
                ms.size(), ms[ms.size() / 2], ms[std::min(ms.size() - 1, ms.size() * 95 / 100)], firstFrame_,
                firstLitFrame_);
}

}  // namespace ml
