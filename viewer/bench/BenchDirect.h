// The direct-light bench of Fournier & Péroche §6.1 (Figs. 7–9): how close
// each sampling scheme of §4 gets to the exact visible solid angle, and what
// each phase of a sample costs.
//
// Sections, in the order they run:
//   accuracy     every scheme (query, regular, jittered) × image size × bits
//                × estimator on the bench scene's receiver grid, one pass per
//                point: error against ExactDirect and median phase times
//   scenes       timings only, jittered 64×4, on the bench scene with a
//                7,200-triangle occluder and on the Water Cornell box
//   convergence  the error of the mean of K passes at penumbra points, for
//                jittered 64×4 (converges) and regular 64 (cannot: every pass
//                repeats the same value)
// Prints aligned tables and writes, into outDir: direct_accuracy.csv,
// direct_timing_scenes.csv, direct_convergence.csv, direct_plots.gp and its
// PNGs (when gnuplot is installed) and direct_summary.md.
#pragma once

#include "BenchOptions.h"

namespace ml {

// quick: CI size (seconds on a CPU rasteriser): 20×20 points, image sizes
// {32, 64}, bits {1, 4}, 40 convergence points and K ≤ 8, 300 points on the
// 7,200-triangle scene, no Water scene. seed: the jitter; runs repeat bit
// for bit.
struct BenchDirectOptions : BenchOptions {
    // Receivers per side of the bench floor grid; 100 gives the paper's
    // 10,000 points. Ignored in quick mode, which uses 20.
    int pointsPerSide = 100;
};

// Runs the whole bench. Returns the exit code: 0, also when gnuplot is
// missing (the plots are then skipped with a note). Throws InputError when
// outDir cannot be made or written, std::runtime_error when no headless
// context can be made or gnuplot fails on its script.
int runBenchDirect(const BenchDirectOptions& options);

}  // namespace ml
