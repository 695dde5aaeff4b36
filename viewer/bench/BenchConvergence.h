// The convergence bench (issue 4): how fast `render`'s progressive image
// approaches the exact direct-light image, against the reference path
// tracer at equal wall-clock time, on the Cornell box, direct light only.
//
// Parts, in the order they run:
//   still        one view (the box's camera). The exact image (ExactDirect-
//                Image: the compositor's sub-pixel grid) once; then the
//                production progressive loop (one cache, the worker thread
//                with its GPU sampler, the view set to the camera, this
//                thread compositing snapshots) for a time budget, the latest
//                snapshot composited at fixed elapsed times; then the path
//                tracer (depth 1, every core, box filter) at doubling samples
//                per pixel until it has used the same budget. Error is the
//                relative RMSE against the exact image for both, over the
//                whole image and without the pixels that see the light. The
//                path tracer integrates each pixel's area where the exact
//                image averages S×S sub-pixel centres: its floor, and an 8×8
//                exact image against the 4×4 one on a crop around the light,
//                say how much of its last error is that approximation.
//   walkthrough  views along a smooth path inside the box; one cache that
//                keeps refining: per view, setView, then wait for a snapshot
//                made for that view whose estimated error is at most a
//                target, or a time limit. Then, per view, the samples per
//                pixel the path tracer needs to match Meshlight's error on
//                that view, and their time.
//   memory       bytes per cached vertex: the cache's own estimate, its
//                accounting, the growth of the process's resident set over
//                the still run, and what freeing the cache gives back.
// Prints aligned tables and writes, into outDir: convergence_still.csv,
// convergence_walkthrough.csv, convergence_targets.csv,
// convergence_memory.csv, convergence_plots.gp and its PNGs (when gnuplot is
// installed) and convergence_summary.md. Times are measured and reported,
// never asserted: other processes on the machine disturb them.
//
// quick: CI size (under a minute on 2 cores): still 64×64 for 3 s,
// walkthrough of 3 views at 32×32. The full run: still 256×256 for 30 s, 30
// views at 48×48 (their exact references set the size; see Workload in
// BenchConvergence.cpp). seed: jitter of the cache's sampler and the path
// tracer's streams; the cache runs against the clock, so runs repeat only
// as far as timing allows.
#pragma once

#include "BenchOptions.h"

namespace ml {

// Runs the three parts. Returns the exit code: 0, also when a target is not
// met (the tables say so) or gnuplot is missing (plots skipped with a note).
// Throws InputError when outDir cannot be made or written,
// std::runtime_error when no headless context can be made, the worker fails
// or gnuplot fails on its script.
int runBenchConvergence(const BenchOptions& options);

}  // namespace ml
