// Camera paths for walkthroughs: one camera per line of a CSV file.
#pragma once

#include "Camera.h"

#include <string>
#include <vector>

namespace ml {

// Reads "px,py,pz,tx,ty,tz,ux,uy,uz,fov" per line (position, target, up,
// vertical field of view in degrees). Blank lines and lines starting with
// '#' are skipped; so is a first line that starts with a letter (a header).
// Anything else wrong is an InputError naming the file and line: a missing
// or extra field, a number that does not parse or is not finite, a
// degenerate camera. An empty path is an error too.
std::vector<Camera> loadCameraPath(const std::string& path);

}  // namespace ml
