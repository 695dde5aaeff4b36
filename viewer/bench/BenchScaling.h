// How the cost of direct light grows with the scene: with its number of
// triangles and with its number of lights.
//
// Sweeps, in the order they run:
//   triangles  the bench scene (its occluder is in view of every shadowed
//              receiver: the worst case for culling) and the Cornell box
//              (most triangles are culled), each non-emissive triangle split
//              into 4 recursively (subdivideScene); per size:
//                setup       constructing the sampler: occluder BVH and upload
//                per sample  median time of one sample at fixed receivers,
//                            the same points at every size, with its phases
//                            and the occluder triangles drawn after culling
//                cache       building the irradiance cache, `render`'s first
//                            refinement round with a fixed budget of
//                            estimates, compositing an image from it
//   lights     the Cornell box with N ceiling lights of constant total power
//              (makeCornellLightGrid); per N: sampler setup, cache build,
//              the cost per cache vertex of sampling all N lights (a fixed
//              number of vertices spread through the mesh), compositing,
//              their total, and the time to sample every vertex once
//              (extrapolated)
// The growth exponent b of each cost ≈ a·x^b is fitted by least squares in
// log-log (PowerLawFit). Prints aligned tables and writes, into outDir:
// scaling_triangles.csv, scaling_lights.csv, scaling_fits.csv,
// scaling_plots.gp and its PNGs (when gnuplot is installed) and
// scaling_summary.md.
//
// quick: CI size (well under a minute on a CPU rasteriser): bench scene 1k
// to 64k triangles, Cornell box 2k to 31k, 1 to 8 lights, 64 receivers and
// 96 cache estimates per point. The full run goes to 1M triangles and 64
// lights, with 200 receivers and 400 cache estimates. seed: jitter and
// receiver placement; runs repeat bit for bit.
#pragma once

#include "BenchOptions.h"

namespace ml {

// Runs both sweeps. Returns the exit code: 0, also when gnuplot is missing
// (plots skipped with a note). Throws InputError when outDir cannot be made
// or written, std::runtime_error when no headless context can be made or
// gnuplot fails on its script.
int runBenchScaling(const BenchOptions& options);

}  // namespace ml
