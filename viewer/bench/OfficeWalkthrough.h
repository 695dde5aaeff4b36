// The walkthrough through the built-in office that bench lights times (the
// many-lights issue's 30 views): a walk at eye height along the room's
// front aisle and down its left side, turning to look across the room.
#pragma once

#include "core/Camera.h"
#include "core/scenes/OfficeScene.h"

#include <vector>

namespace ml {

// `views` cameras in `office`, the scene makeOfficeScene(settings) made
// (OfficeScene.h; metres, y up, the floor's centre at the origin), at its
// camera's eye height and field of view. The eye starts at the office's own camera (the (+x, +z)
// corner), walks along the front (+z) wall to 1 m from the left (−x) wall
// and then towards the back (−z) wall; it looks first at the room's centre,
// halfway at the back-left corner, at the end across the room at the
// front-right corner, turning the shortest way between them at a steady
// rate; its pitch goes from the office camera's to 12° below the horizon
// by halfway. The first view is the office camera's. Smoothstep timing: it starts and ends at rest. The eye is above
// every piece of furniture (validate() keeps the partition, 1.5 m, and the
// cabinets, 1.2 m, below it), so the path crosses nothing.
std::vector<Camera> officeWalkthroughCameras(const Scene& office, const OfficeSettings& settings, int views);

}  // namespace ml
