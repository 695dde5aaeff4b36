// The end every hemispherical gather shares (SliceGather, VoxelMarchGather,
// TriangleGather): its image read back and summed to the irradiance, its
// phases and its estimate booked, a non-finite result reported. Private to
// gpu_sampling/indirect: only its .cpp files include this.
#pragma once

#include "core/Math.h"

#include <chrono>
#include <functional>
#include <vector>

namespace ml {

struct GlApi;
struct GatherPhaseTimes;
struct IndirectStats;

// The clock of one gather, started when it is made: the gather's CPU part
// (near field, culling, uploads), its draws, then its read-back.
class GatherReadback {
public:
    // Books into `phases` and `stats`; with `timePhases` the GPU is waited
    // for before the draws are booked, so the parts add up to the whole.
    GatherReadback(GatherPhaseTimes& phases, IndirectStats& stats, bool timePhases);

    // The CPU part is over: books phases.nearField.
    void cpuDone();
    // The draws are issued into the bound framebuffer: books them, reads the
    // image back with `sum` (which returns its irradiance), binds the default
    // framebuffer again and books the read-back and the estimate. A
    // non-finite irradiance throws std::runtime_error naming x, after
    // checkGl(gl, what) has had the chance to name a GL error behind it.
    Rgb finish(const GlApi& gl, const std::function<Rgb()>& sum, const char* what, const Vec3& x);

private:
    using Clock = std::chrono::steady_clock;
    GatherPhaseTimes& phases_;
    IndirectStats& stats_;
    bool timePhases_;
    Clock::time_point start_, drawStart_;
};

// Reads the bound framebuffer's lower-left width × height pixels (RGBA32F,
// tightly packed, row 0 at the bottom) into `pixels`.
void readRgba(const GlApi& gl, int width, int height, std::vector<float>& pixels);

// Reads the bound framebuffer's N×N fish-eye image (into `pixels`) and
// returns its irradiance: each pixel covers (2/N)² of the unit disc, whose
// area π is the hemisphere's projected solid angle.
Rgb readFisheyeIrradiance(const GlApi& gl, int imageSize, std::vector<float>& pixels);

}  // namespace ml
