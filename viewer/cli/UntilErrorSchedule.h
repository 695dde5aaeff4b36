// When `render --until-error E` should ask the image's estimated error of
// a fresh snapshot (RenderCommand.cpp): each ask composites the image while
// the worker refines, so it is asked sparingly, but at every snapshot near
// where the estimates so far say the error reaches E.
#pragma once

#include "core/Math.h"

#include <algorithm>
#include <cmath>

namespace ml {

// The estimates asked so far: the last two, each with the time of the
// snapshot it was asked of (the worker's seconds, CacheSnapshot::seconds);
// what the last ask cost, and the snapshots' spacing.
struct UntilErrorSchedule {
    double t0 = 0, e0 = 0, t1 = 0, e1 = 0;
    int count = 0;
    double lastAskStart = -kInf;  // session seconds when the last ask began
    double askCost = 0;           // its seconds
    double lastSnapshot = -kInf;  // the last fresh snapshot's seconds, asked or not
    double spacing = 0;           // between the last two fresh snapshots

    // A fresh snapshot made at `snapshot` (worker seconds) is here at `now`
    // (session seconds): whether to ask its estimate. Regularly, at most a
    // third of the time is spent asking (every max(0.5 s, 3 asks' cost));
    // besides, at any fresh snapshot where the estimates say the error
    // reaches `target` before the next snapshot is due (half a spacing
    // after this one): near the crossing every snapshot may be the one.
    // Asked every 0.5 s at least twice an ask's cost apart, the 256×256
    // Cornell box (0.1 s an ask, snapshots 0.28 s apart) asked every other
    // snapshot, and its error fell 2-3 times between two asks.
    bool shouldAsk(double now, double snapshot, double target) {
        if (snapshot > lastSnapshot && lastSnapshot > -kInf) spacing = snapshot - lastSnapshot;
        lastSnapshot = std::max(lastSnapshot, snapshot);
        const double since = now - lastAskStart;
        if (count == 0 || since >= std::max(0.5, 3 * askCost)) return true;
        return snapshot + 0.5 * spacing >= crossing(target);
    }
    // An ask began at `start` and ended at `end` (session seconds), of a
    // snapshot made at `snapshot` (worker seconds), and read `estimate`.
    void asked(double start, double end, double snapshot, double estimate) {
        lastAskStart = start, askCost = std::max(0.0, end - start);
        add(snapshot, estimate);
    }
    void add(double t, double e) {
        t0 = t1, e0 = e1, t1 = t, e1 = e;
        ++count;
    }
    // The time at which the error reaches `target`, on a power law
    // e ∝ t^-α through the last two estimates (α within 0.25..2: a run that
    // stalls still asks now and then, one that falls fast is not trusted to
    // fall faster); from the first alone, α = 2: as fast as it may, so that
    // the crossing is not missed while nothing has measured the fall (an ask
    // a snapshot at most, until the second). With α = 1 the 256×256 Cornell
    // box asked until 2% read 5.2% at 0.3 s, put 2% at 0.78 s, skipped the
    // snapshot at 0.56 s (2.15% measured, 1.5% estimated) and stopped at
    // 1.1 s on 1.16%. The last one's time once it is at or below `target`;
    // infinite before any estimate.
    double crossing(double target) const {
        if (count == 0 || !(t1 > 0) || !(e1 > 0) || !(target > 0)) return kInf;
        if (e1 <= target) return t1;
        double alpha = 2;
        if (count >= 2 && t0 > 0 && e0 > 0 && t1 > t0) alpha = std::log(e0 / e1) / std::log(t1 / t0);
        alpha = std::clamp(std::isfinite(alpha) ? alpha : 0.25, 0.25, 2.0);
        return t1 * std::pow(e1 / target, 1 / alpha);
    }
};

}  // namespace ml
