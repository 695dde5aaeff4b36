// The view options `render` and `reference` share (so their images compare
// pixel for pixel), declared and read in one place.
#pragma once

#include "Options.h"
#include "core/Scene.h"

namespace ml {

// --width, --height, --camera-pos, --camera-target, --camera-up, --fov.
void declareViewOptions(Options& options);
// --camera-pos, --camera-target, --camera-up, --fov only (`view` has its own window size).
void declareCameraOptions(Options& options);
// The scene's camera (or a framing one) with the options applied; validated.
Camera cameraFromOptions(const Options& options, const Scene& scene, double aspect);

}  // namespace ml
