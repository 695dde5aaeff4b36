// `meshlight bench scenes`: the public scenes of ../shared/scenes as a user
// renders them, each rendered by `meshlight render --time T` and by
// `meshlight reference --spp N` from the same view, side by side in one
// picture (the same exposure for both), with the relative RMSE
// (ImageMetrics.h) and the mean ratio of the two: what the issues' "put the
// image in the report" asks of the mirror and glass spheres, the water and
// the glTF back rooms.
//
// Scenes (skipped, with a note, when the folder is missing; the folder is
// $MESHLIGHT_SCENES_DIR, else ../shared/scenes from the current directory):
//   sphere     mcguire-cornellbox/CornellBox-Sphere.obj (a mirror and a glass ball)
//   water      mcguire-cornellbox/CornellBox-Water.obj  (a water surface: caustics)
//   backrooms  backrooms-gltf/scene.gltf                (glTF, textures, 16 lights, 6 glowing walls)
// Full: 256×256 (backrooms 240×135), 60 s against 1024 spp. Quick (CI):
// 64 pixels wide, 2 s against 64 spp.
// Each run is the meshlight binary itself, as a user types it: the
// commands are in the summary. Writes scenes.csv, scenes_<id>.png,
// scenes_summary.md. Errors are reported, never asserted.
#pragma once

#include "BenchOptions.h"

namespace ml {

int runBenchScenes(const BenchOptions& options);

}  // namespace ml
