// How well an image's own estimate of its error (viewer/compositor/
// ImageErrorEstimate.h: what `render --until-error` stops on) agrees with
// the error measured against a reference, over the images of a curve whose
// measured error lies in a range. Issue 14 asks for a factor of 1.5 from 10%
// down to 1% on the Cornell box and the office (bench gi, bench lights).
#pragma once

#include "BenchTable.h"

#include <string>
#include <vector>

namespace ml {

// Issue 14's: within 1.5 times, from 10% down to 1%.
constexpr double kEstimateFactor = 1.5;
constexpr double kEstimateRange[2] = {0.10, 0.01};  // high, low

struct EstimatePoint {
    double seconds = 0;
    double measured = 0;   // relative RMSE against the reference (its noise taken out)
    double estimate = -1;  // the image's estimate; <= 0 or >= 1: none (not made, or unknown)
};

struct EstimateAgreement {
    int images = 0;      // in the range, with an estimate
    double worst = 0;    // the largest factor between the two, max(e/m, m/e)
    double worstAt = 0;  // that image's seconds
};

// Over the points whose measured error lies in [low, high] (relative).
EstimateAgreement estimateAgreement(const std::vector<EstimatePoint>& points, double high, double low);

// A target row named `name`: met when every image in the range is within
// `factor`; "not measured" when none is.
BenchTarget estimateTarget(const std::string& name, const EstimateAgreement& a, double factor);

// Issue 14's row over `points`: kEstimateFactor over kEstimateRange, its
// name after `prefix` (the scene, or empty).
BenchTarget issueEstimateTarget(const std::string& prefix, const std::vector<EstimatePoint>& points);

}  // namespace ml
