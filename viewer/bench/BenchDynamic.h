// The moving-things bench (issue 17): what it costs, and how fast the cache
// is back, when a light or an object moves (core/SceneChange.h,
// cache/CacheInvalidation.h).
//
// Scene: the built-in Cornell box with full global illumination (the plan's
// gather and bounce count, cache defaults, the production direct sampler).
// Motions, each from a cache converged for the start (a fresh session
// refined for `settle` seconds first):
//   light   the ceiling light moved in steps along x across the ceiling
//           (and back towards the middle), 2 mm below the ceiling;
//   block   the short block moved in steps across the floor (+z).
// While moving, this thread plays the viewer's frame loop: each frame
// composites the latest snapshot at the display size (1280×720; 320×180
// quick; Compositor::render, which also reads the image back: a frame in
// the window costs less) while each step is applied on a helper thread as
// the viewer does (ViewRefinement::beginChange: the worker stopped,
// ProgressiveSession::applyChange), then a new worker is started and the
// compositor made again for the moved geometry. A step is applied every
// 0.25 s of the loop, or when the one before is done.
// After the last step, the latest snapshot is composited at the error size
// every 0.25 s until `limit` seconds; then a cold start (a fresh session on
// the final pose) runs the same way to `cold` seconds, and its last image
// is the converged one both are measured against.
// Columns: frame times while moving (median, 95th percentile, worst), the
// helper's time per step; relative RMSE (core/image/ImageMetrics.h) 0.5 s
// and 5 s after the motion stops against the converged image and against
// the path tracer (PathTracer, max depth 8, `spp` samples per pixel, its
// own noise in the table); the time until within 2% of the converged image
// (and staying there) after the motion and from a cold start. The
// converged image is the cold start's own last one, which favours the cold
// start (its last images share that image's refinement and jitter).
// Writes dynamic_frames.csv (every frame while moving), dynamic_curves.csv
// (the error curves, with each image's samples, bounces finished and the
// cache's estimated error), dynamic_summary.csv, dynamic_targets.csv,
// dynamic_plots.gp and its PNG, dynamic_summary.md. Times are measured and
// reported, never asserted.
//
// quick: CI size: 320×180 frames, errors at 64×36 against a 64-spp
// reference, 3 steps per motion, 8 s after the motion and 12 s for the cold
// start. Full: 1280×720, errors at 160×90 against 256 spp, 6 steps, 20 s
// and 40 s. seed: the worker's jitter and the path tracer's streams.
#pragma once

#include "BenchOptions.h"

namespace ml {

int runBenchDynamic(const BenchOptions& options);

}  // namespace ml
