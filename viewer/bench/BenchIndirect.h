// The indirect-light bench of Fournier & Péroche §6.2: the same hemispherical
// gather done six ways, on the Cornell box, for accuracy against time.
//
//   slices             the paper's voxel slices (SliceGather, faces walked per pixel)
//   slice-quads        the same, one full-screen quad per slice face (§5.4 as written)
//   raymarch           the same voxels as a 3D texture, ray-marched (VoxelMarchGather)
//   fisheye-triangles  the proxy's triangles, fish-eye projection in the vertex stage
//   perspective        the proxy's triangles, one 160° perspective image
//   hemicube           the proxy's triangles, five hemicube faces
//
// Every method gathers from the same source: the direct irradiance of a
// cache over the scene sampled exactly (ExactDirect) at its vertices, turned
// into exitant radiance on the radiance proxy (RadianceProxy); the bench
// times the gather alone. Each configuration (method × image size × voxel or
// proxy resolution) gathers once at each point (phase-timed, glFinish
// between phases), then K − 1 more times with fresh jitter (untimed by
// phase: the real cost per gather), and its error is measured against
//   - the path tracer's one-bounce indirect irradiance (`probe --method path
//     --max-depth 2`) at the same points, and
//   - the exact-geometry gather of the same source (cosine-weighted Embree
//     rays, the cache's irradiance where they land): what a perfect gather
//     of this source gives. Its own error against the path tracer is the
//     floor under every method (the cache's interpolation), and errors
//     against it are the gathers' own.
// Points: random by area over the box's surfaces (none inside a block) and
// fixed ones in corners, along contacts and beside the light.
// Prints aligned tables and writes, into outDir: indirect_methods.csv,
// indirect_equal_error.csv, indirect_points.csv, indirect_plots.gp and its
// PNGs (when gnuplot is installed) and indirect_summary.md.
//
// quick: CI size (well under a minute on a CPU rasteriser): fewer points,
// passes and configurations, coarse voxels and proxies. seed: points,
// jitter and path tracer; runs repeat.
#pragma once

#include "BenchOptions.h"

namespace ml {

// Runs the whole bench. Returns the exit code: 0, also when gnuplot is
// missing. Throws InputError when outDir cannot be made or written,
// std::runtime_error when no headless context can be made or gnuplot fails.
int runBenchIndirect(const BenchOptions& options);

}  // namespace ml
