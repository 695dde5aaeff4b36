// bench lights' walkthrough (the many-lights issue): 30 views through the
// office (OfficeWalkthrough.h), each shown until within 5% of its
// path-traced reference, from one cache made cold, against the time the
// path tracer needs for the same views at the same error.
#pragma once

#include "BenchTable.h"
#include "NoisyReference.h"
#include "SessionCheckpoints.h"

#include "core/raytrace/PathTracer.h"
#include "core/scenes/OfficeScene.h"
#include "viewer/compositor/Compositor.h"

#include <string>
#include <vector>

namespace ml {

class BenchRun;
class GlContext;

struct OfficeWalkSettings {
    OfficeSettings office;             // the scene walked through
    int views = 30;
    int width = 160, height = 90;      // pixels of every view
    int referenceSpp = 512;            // per view
    PathTracerSettings tracer;         // the references' (its seed is the base of each view's)
    CompositorSettings composite;      // width and height are set from the above
    double level = 0.05;               // each view is shown until within this relative RMSE
    double firstViewSeconds = 60;      // the first view's limit, the cache's making included
    double viewSeconds = 20;           // every other view's
    double speedup = 5;                // the target: the path tracer's total time over Meshlight's
};

// Meshlight's view (ViewShown: from setCamera, the first view's from
// before the session is made, to the composite within the level or the
// time limit), its reference, and the path tracer's time.
struct OfficeWalkView : ViewShown {
    double referenceSeconds = 0, referenceNoise = 0;
    // The path tracer at Meshlight's error (floored at a quarter of the
    // reference's noise) and at the level: the reference's time scaled by
    // (its noise / the error)², as an unbiased estimator's error falls.
    double pathLevel = 0;  // the error the first is taken at
    double pathAtMeshlight = 0, pathAtLevel = 0;
};

struct OfficeWalkResult {
    OfficeWalkSettings settings;
    std::vector<OfficeWalkView> views;
    double cacheBuildSeconds = 0;
    double referenceSeconds = 0, referenceNoiseMax = 0;

    double meshlightTotal() const;
    double pathTotal(bool atLevel) const;
    bool allReached() const;
    double maxError() const;

    BenchTable table() const;                 // a row per view
    std::vector<BenchTarget> targets() const;  // each view within the level; the speedup
    std::string markdown() const;              // the section of lights_summary.md
};

// Renders the references first (nothing else running), then one session as
// `render` makes it (RenderLikeSession.h) walks the views, compositing each
// new snapshot on `context`'s thread until the view is within the level.
// Writes each view's last composite and its reference into run.dir() as
// lights_walk_NN_meshlight.exr and lights_walk_NN_reference.exr (after the
// view's time is taken).
OfficeWalkResult runOfficeWalk(const BenchRun& run, GlContext& context, const OfficeWalkSettings& settings);

}  // namespace ml
