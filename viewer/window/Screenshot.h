// A viewer screenshot: a PNG is the window as shown (read from the back
// buffer before the swap, the panel included unless hidden); an EXR or HDR
// is the linear image of the display mode, box-filtered on the CPU exactly
// as `render` does (Compositor::readImage).
#pragma once

#include <string>

namespace ml {

class Compositor;
class GlfwWindow;

// Writes `path` (checked first: an unwritable folder throws InputError) from
// the frame of width × height pixels just composited and drawn.
void writeScreenshot(const std::string& path, const GlfwWindow& window, Compositor& compositor, int width,
                     int height);

}  // namespace ml
