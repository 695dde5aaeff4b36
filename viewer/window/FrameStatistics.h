// What the viewer measures of its own frames: each frame's record (for the
// bench), moving averages for the panel, when the first frame and the first
// lit frame reached the screen, the latency of light changes, the status
// line and the summary printed at the end.
#pragma once

#include "ViewSession.h"

#include <cstdint>
#include <string>
#include <vector>

namespace ml {

class FrameStatistics {
public:
    // A frame that ended `end` seconds after the session started (it was
    // lit if frame.snapshot).
    void add(const FrameRecord& frame, double end);
    void addLightLatency(double seconds) { lightLatencies_.push_back(seconds); }

    const std::vector<FrameRecord>& frames() const { return frames_; }
    double firstFrame() const { return firstFrame_; }          // s, −1: none yet
    double firstLitFrame() const { return firstLitFrame_; }    // s, −1: none yet
    const std::vector<double>& lightLatencies() const { return lightLatencies_; }
    double frameMsAverage() const { return frameMsAverage_; }  // moving average
    double composeMsAverage() const { return composeMsAverage_; }

    // "view 12.3 s: N vertices, M samples, estimated error E%, F frames/s",
    // on stderr, at most once a second unless `now`; redrawn in place on a
    // terminal.
    // `lights`: what the lights give as set now ("925.6 lm, 2 of 3 lights on").
    void printStatus(double seconds, size_t vertices, uint64_t samples, double estimatedError,
                     const std::string& lights, bool now = false);
    // Frames drawn, median and 95th percentile, first (lit) frame, on stdout.
    void printSummary() const;

private:
    std::vector<FrameRecord> frames_;
    double firstFrame_ = -1, firstLitFrame_ = -1;
    std::vector<double> lightLatencies_;
    double frameMsAverage_ = 0, composeMsAverage_ = 0;
    double lastStatus_ = -1e30;
};

}  // namespace ml
