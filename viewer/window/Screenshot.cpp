#include "Screenshot.h"

#include "GlfwWindow.h"
#include "core/image/Image.h"
#include "core/io/AtomicFile.h"
#include "gpu_sampling/gl/GlObjects.h"
#include "viewer/compositor/Compositor.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace ml {

void writeScreenshot(const std::string& path, const GlfwWindow& window, Compositor& compositor, int width,
                     int height) {
    checkOutputPath(path);
    if (outputFormat(path) != ImageFormat::Png) {
        writeImageLinear(path, compositor.readImage());
        return;
    }
    // What the window shows, read from the back buffer before the swap.
    const GlApi& gl = window.gl();
    std::vector<uint8_t> rgb(size_t(width) * height * 3), rows(rgb.size());
    gl.BindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    gl.ReadBuffer(GL_BACK);
    gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
    gl.ReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
    checkGl(gl, "reading the window for a screenshot");
    const size_t row = size_t(width) * 3;
    for (int y = 0; y < height; ++y)  // GL rows start at the bottom
        std::copy_n(&rgb[size_t(height - 1 - y) * row], row, &rows[size_t(y) * row]);
    writeImage8(path, rows, width, height);
}

}  // namespace ml
