// The many-lights bench: how Meshlight's cost to a given image error grows
// with the number of lights, against the reference path tracer at equal
// wall-clock time, with full global illumination.
//
// Scenes: the built-in office (core/scenes/OfficeScene.h) with 3, 12, 48 and
// 192 ceiling panels (3×1, 4×3, 8×6 with the default 0.6 m panels; 16×12
// with 0.4 m ones, the largest that fit), all of the same total power, seen
// from the office's own camera at 320×180. Per scene, in the order they run:
//   reference    the path tracer (PathTracer, max depth 8, every core), as
//                `meshlight reference` renders it, at a fixed number of
//                samples per pixel, with its standard-error image (from the
//                even and odd samples). Untimed.
//   meshlight    the production progressive loop: a ProgressiveSession
//                (cache defaults, the production direct sampler, the
//                indirect gather and bounce count of the plan, one sampling
//                thread per core), the clock started before the cache is
//                made; this thread composites the latest snapshot (direct
//                and indirect meshes, 4×4 sub-pixels) at fixed elapsed
//                times up to the budget.
//   path tracer  the same path tracer with other streams at doubling
//                samples per pixel (2, 4, 8, ...; its time includes the BVH
//                build) until its time passes Meshlight's budget.
// Error: relative RMSE (core/image/ImageMetrics.h) against the reference,
// corrected for the reference's own noise: sqrt(max(0, mean((x − r)² − σ²)
// / (r² + 0.01))), σ the reference's standard error per pixel and channel.
// The raw value is kept beside it. From each curve: the time to reach 10%,
// 5% and 2% (interpolated in log-log between images), the path tracer's
// time over Meshlight's at each level, and the exponent of the time to a
// level against the number of lights (PowerLawFit). Memory per scene: the
// cache's vertices and bytes, the indirect caches', the peak resident set.
//
// Then a walkthrough of the 12-panel office (OfficeWalkRun.h): 30 views of
// 160×90 along OfficeWalkthrough.h's path, each with its own 512-spp
// reference; one session from cold walks them, each view shown until its
// composite is within 5%; the path tracer's time for the same views at the
// same error is its reference's time scaled by (noise / error)².
//
// Writes into outDir: lights_checkpoints.csv (every image of both methods),
// lights_summary.csv (time to each level, ratios), lights_scenes.csv
// (references, memory, final errors), lights_fits.csv, lights_targets.csv,
// lights_walkthrough.csv (a row per view) and each view's last image and
// reference (lights_walk_NN_*.exr), lights_plots.gp and its PNGs (when gnuplot is installed), the references
// and Meshlight's last image as EXR, and lights_summary.md; prints the
// tables. Times are measured and reported, never asserted.
//
// quick: CI size (well under a minute on 2 cores): 3 and 12 panels at
// 96×54, 3 s each, a 256-spp reference; a walkthrough of 3 views of 64×36. seed: the worker's jitter and the
// path tracer's streams (the reference's and the curve's differ); the
// cache runs against the clock, so runs repeat only as far as timing allows.
#pragma once

#include "BenchOptions.h"

namespace ml {

// Runs every scene. Returns the exit code: 0, also when a target is not met
// (the tables say so) or gnuplot is missing (plots skipped with a note).
// Throws InputError when outDir cannot be made or written,
// std::runtime_error when no headless context can be made, the worker fails
// or gnuplot fails on its script.
int runBenchLights(const BenchOptions& options);

}  // namespace ml
