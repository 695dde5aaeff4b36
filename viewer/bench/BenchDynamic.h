// The moving-things bench (issue 17): what it costs, and how fast the image
// is back, when a light or an object moves (core/SceneChange.h,
// cache/CacheInvalidation.h), with the real-time stand-in for indirect light
// the viewer shows while the cache catches up (cache/RealtimeIndirect.h).
//
// Scenes: the built-in Cornell box and (not quick) the built-in office of
// 12 panels, with full global illumination (each scene's plan: its gather
// and bounce count; cache defaults, the production direct sampler).
// Motions, each from a cache converged for the start (a fresh session
// refined for `settle` seconds first):
//   light   the Cornell box's ceiling light moved in steps along x across
//           the ceiling, 2 mm below it: its only light, so nothing of
//           direct light is kept and a warm start is a cold one but for
//           the geometry's structures;
//   block   the Cornell box's short block moved in steps across the floor
//           (+z);
//   panel   (not quick) one of the office's 12 ceiling panels, in the
//           middle of the view, moved 0.6 m along x in steps (a luminaire
//           moved by its own width): the other lights' direct light is
//           kept, as a lighting designer's scene has many.
// Sessions run as the viewer's: sampling threads at the viewer's niceness
// (ViewRefinement::kWorkerNice) below this thread and the stand-in's, and
// the worker told a stand-in shows (WorkerSettings::indirectStandIn) unless
// --realtime off.
// While moving, this thread plays the viewer's frame loop: each frame
// composites the latest snapshot, with the indirect light the viewer shows
// (RealtimeIndirect::display; every new snapshot offered to the stand-in),
// at the display size (1280×720; 320×180 quick; Compositor::render, which
// also reads the image back: a frame in the window costs less) while each
// step is applied on a helper thread as the viewer does
// (ViewRefinement::beginChange: the worker stopped,
// ProgressiveSession::applyChange), then a new worker is started and the
// compositor made again for the moved geometry. A step is applied every
// 0.25 s of the loop, or when the one before is done.
// After the last step, the latest snapshot is composited at the error size
// every 0.05 s for 2 s, then every 0.25 s, until `limit` seconds (each image
// timed when its snapshot is read: later than due where composites take
// longer than that, as the office's do; new snapshots offered to the stand-in
// every 20 ms meanwhile, as frames would); then a cold start (a fresh
// session and stand-in on the final pose) runs the same way to `cold`
// seconds. The converged image both are measured against is a third
// session's on the final pose, with a seed of its own, refined `cold`
// seconds: no curve is measured against its own images (the cold start's
// own last image favoured it; its time against itself is still printed).
// Columns: frame times while moving (median, 95th percentile, worst), the
// helper's time per step; relative RMSE (core/image/ImageMetrics.h) 0.5 s
// and 5 s after the motion stops against the converged image and against
// the path tracer (PathTracer, max depth 8, `spp` samples per pixel, its
// own noise in the table); the time until within 2% of the converged image
// (and staying there) after the motion and from a cold start, for the image
// shown and for the cache's own indirect light without the stand-in.
// Then the stand-in's methods (volume, vpl, lpv, each at its default
// resolution and, full, a coarser or finer one; 1 to every bounce
// estimated) on the final pose from the converged direct light: time per
// update on this thread with nothing else of the bench running, and the
// image's error against the converged one (with the direct light alone for
// scale): what --realtime's default is chosen by.
// Writes dynamic_frames.csv (every frame while moving), dynamic_curves.csv
// (the error curves, with each image's samples, bounces finished, the
// cache's estimated error and what indirect light it showed),
// dynamic_realtime.csv (the methods), dynamic_summary.csv,
// dynamic_targets.csv, dynamic_plots.gp and its PNG, dynamic_summary.md.
// Times are measured and reported, never asserted.
//
// quick: CI size: the Cornell box's motions only, 320×180 frames, errors
// at 64×36 against a 64-spp reference, 3 steps per motion, 8 s after the
// motion and 12 s for the cold start, the methods at their defaults only. Full: 1280×720, errors at
// 160×90 against 256 spp, 6 steps, 20 s and 40 s. seed: the worker's jitter
// and the path tracer's streams.
#pragma once

#include "BenchOptions.h"
#include "gpu_sampling/SamplerFactory.h"

#include <string>
#include <vector>

namespace ml {

struct BenchDynamicOptions : BenchOptions {
    // The stand-in for indirect light while the cache catches up, as `view`
    // shows it (--realtime); off: the cache's old bounces.
    RealtimeChoice realtime;
    // The motions to run, by name (light, block, panel); empty: every one
    // the mode runs (quick: light and block). --motions.
    std::vector<std::string> motions;
};

int runBenchDynamic(const BenchDynamicOptions& options);

}  // namespace ml
