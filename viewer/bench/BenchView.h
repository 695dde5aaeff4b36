// The viewer bench (issue 6): what `meshlight view` costs on this machine,
// run in a real GLFW window through the viewer's own scripted sessions.
//
// Scenarios, in the order they run (Cornell box, 1280×720, one sub-pixel
// per pixel, no frame cap):
//   walk-paused     a walk through the box (camera keyframes) with
//                   refinement paused: what a frame costs by itself;
//   walk-refining   the same walk while the worker refines: the frame rate
//                   must not depend on refinement (both share 2 cores here);
//   million         the same walk with the cache's base mesh cut to about a
//                   million triangles (--cache-edge 0.003), refining;
//   lights          a still camera while refining; a light is switched off,
//                   on, dimmed and tinted every 0.3 s: the time from each
//                   change to the end of the frame that shows it.
// The first frame's latency (session start to the first frame on screen,
// and to the first frame showing a snapshot) comes from walk-refining.
// Writes view_frames.csv (every frame), view_scenarios.csv, view_latency.csv,
// view_targets.csv, view_plots.gp and its PNGs, view_summary.md. Times are
// reported, never asserted.
//
// quick: CI size, 2.5 s per walk instead of 15, 8 light changes instead
// of 20. seed: the worker's jitter. options.backend is not read: the bench
// draws in a GLFW window, as `view` does.
#pragma once

#include "BenchOptions.h"

namespace ml {

// Needs a display; without one, runs itself again under xvfb-run when it is
// installed. Returns the exit code; throws std::runtime_error when no window
// can be opened.
int runBenchView(const BenchOptions& options);

}  // namespace ml
