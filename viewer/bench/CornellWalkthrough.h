// The walkthrough through the built-in Cornell box that the benches share
// (bench convergence, bench gi): a smooth camera path inside the box.
#pragma once

#include "core/Camera.h"
#include "core/Scene.h"

#include <vector>

namespace ml {

// `views` cameras from the box's own view, moved in to just inside its open
// front: the eye dollies in and rises towards the short block while the
// view pans down to the gap between the blocks, where the penumbrae are.
// Smoothstep timing: it starts and ends at rest. Coordinates are the
// Cornell box's millimetres (x = 0 is the green wall, y up, the open front
// at z = 0); the field of view is the box's camera's.
std::vector<Camera> walkthroughCameras(const Scene& scene, int views);

}  // namespace ml
