// `meshlight bench gi` (issue 14, "Converge to the right answer"): the
// issue's measured targets on the built-in Cornell box with full global
// illumination (path depth 8 = emission, direct light and 7 bounces; Cycles
// "7 bounces", viewer/bench/cycles/README.md), against Blender Cycles.
//
// Parts, in the order they run (each timed part alone, as far as this
// process goes):
//   reference    the path tracer (PathTracer, depth 8, every core) at N spp
//                (B), then the path tracer's own curve (A): doubling samples
//                per pixel (2, 4, ... N, fresh streams each step, averaged),
//                timed, each image measured against B. The reference is the
//                mean of A and B (2N spp, other streams), its standard error
//                combined from theirs.
//   meshlight    the progressive session as `meshlight render` runs it (the
//                production direct sampler, the plan's gather and bounces,
//                cache defaults, refinement tightened up to
//                IrradianceCache::kMaxRefinementLevel, one sampling thread
//                per core), its snapshot copied at fixed times and
//                composited as `render` composites (4×4 sub-pixels, 4
//                rook-shifted passes) once the worker has stopped; an image's
//                time is its checkpoint (from before the session is made)
//                plus its composite. The full run also times `meshlight
//                render --time 10` as typed, as a check of the curve.
//   cycles       Blender Cycles (CyclesRunner.h: one Blender process, its
//                start-up timed apart and not counted) at doubling samples
//                per pixel from 1, each render on its own, until it reaches
//                0.5% or a render passes the time cap; its time is Cycles'
//                render wall time. Skipped, with a line saying why, when
//                Blender is not on PATH.
//   walkthrough  views along the Cornell walkthrough (CornellWalkthrough.h),
//                each with a path-traced reference. Meshlight: one cache
//                from cold, refined while the views are shown as a user
//                walking through gets them (setCamera per view), each view
//                composited from the latest snapshot until its measured error
//                (against its reference) is within 3% or a time limit; the
//                view's time counts every composite made for it. Cycles: per
//                view, samples per pixel doubled or halved (from a count
//                predicted by the previous view) until two counts bracket
//                the error Meshlight reached on that view (floored at a
//                quarter of the view reference's noise), the time at that
//                error interpolated in log-log between them, or extrapolated
//                as 1/√spp past 256 spp; likewise at 3%.
// Error: relative RMSE (ml::relativeRmse) with the reference's noise taken
// out in quadrature (NoisyReference.h); the raw value is kept beside it.
//
// Writes into outDir: gi_curves.csv (every image of every method),
// gi_levels.csv (time to 5, 2, 1, 0.5%), gi_walkthrough.csv (per view),
// gi_targets.csv, gi_plots.gp and its PNGs (gi_error_vs_time.png,
// gi_walkthrough.png) when gnuplot is installed, the reference (and its
// noise) and the last images as EXR, cycles.log (Blender's output) and
// gi_summary.md; prints the tables. Times are measured and reported, never
// asserted; a target not met says so.
//
// quick: CI size (seconds): 64×64 still, 3 s of Meshlight against a 2×128-spp
// reference, Cycles up to 64 spp; 3 views of 32×32. Full (about 17 minutes
// on 2 shared cores): 256×256, 120 s against 2×1024 spp; 30 views of
// 128×128 against 256 spp each. seed: the
// cache's jitter and the path tracer's streams (Cycles' seed is fixed).
#pragma once

#include "BenchOptions.h"

namespace ml {

// Runs every part. Returns the exit code: 0, also when a target is not met
// (the tables say so), Blender is missing (Cycles skipped with a line) or
// gnuplot is missing (plots skipped with a note). Throws InputError when
// outDir cannot be made or written, std::runtime_error when no headless
// context can be made, the worker fails or gnuplot fails on its script.
int runBenchGi(const BenchOptions& options);

}  // namespace ml
