// When `render --until-error E` should next ask the image's estimated error
// (RenderCommand.cpp): each ask composites the image while the worker
// refines, so it is asked sparingly, but as soon as the estimates so far
// say the error reaches E.
#pragma once

#include "core/Math.h"

#include <algorithm>
#include <cmath>

namespace ml {

// The estimates asked so far: the last two, each with the time it was asked
// (the session's seconds).
struct UntilErrorSchedule {
    double t0 = 0, e0 = 0, t1 = 0, e1 = 0;
    int count = 0;

    void add(double t, double e) {
        t0 = t1, e0 = e1, t1 = t, e1 = e;
        ++count;
    }
    // The time at which the error reaches `target`, on a power law
    // e ∝ t^-α through the last two estimates (α within 0.25..2: a run that
    // stalls still asks now and then, one that falls fast is not trusted to
    // fall faster); from the first alone, α = 1. The last one's time once it
    // is at or below `target`; infinite before any estimate.
    double crossing(double target) const {
        if (count == 0 || !(t1 > 0) || !(e1 > 0) || !(target > 0)) return kInf;
        if (e1 <= target) return t1;
        double alpha = 1;
        if (count >= 2 && t0 > 0 && e0 > 0 && t1 > t0) alpha = std::log(e0 / e1) / std::log(t1 / t0);
        alpha = std::clamp(std::isfinite(alpha) ? alpha : 0.25, 0.25, 2.0);
        return t1 * std::pow(e1 / target, 1 / alpha);
    }
};

}  // namespace ml
