#include "GatherReadback.h"

#include "cache/IndirectEstimator.h"
#include "core/Error.h"
#include "gpu_sampling/gl/GlApi.h"
#include "gpu_sampling/indirect/SliceGather.h"

#include <stdexcept>

namespace ml {

GatherReadback::GatherReadback(GatherPhaseTimes& phases, IndirectStats& stats, bool timePhases)
    : phases_(phases), stats_(stats), timePhases_(timePhases), start_(Clock::now()), drawStart_(start_) {}

void GatherReadback::cpuDone() {
    drawStart_ = Clock::now();
    phases_.nearField += std::chrono::duration<double>(drawStart_ - start_).count();
}

Rgb GatherReadback::finish(const GlApi& gl, const std::function<Rgb()>& sum, const char* what, const Vec3& x) {
    if (timePhases_) gl.Finish();
    const auto readStart = Clock::now();
    phases_.draw += std::chrono::duration<double>(readStart - drawStart_).count();

    const Rgb e = sum();
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
    const auto end = Clock::now();
    phases_.readback += std::chrono::duration<double>(end - readStart).count();
    stats_.estimates += 1;
    stats_.estimateSeconds += std::chrono::duration<double>(end - start_).count();
    if (!isFinite(e)) {
        checkGl(gl, what);
        throw std::runtime_error(concat("non-finite indirect irradiance at (", x.x, ", ", x.y, ", ", x.z, ")"));
    }
    return e;
}

void readRgba(const GlApi& gl, int width, int height, std::vector<float>& pixels) {
    pixels.resize(size_t(width) * height * 4);
    gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
    gl.ReadPixels(0, 0, width, height, GL_RGBA, GL_FLOAT, pixels.data());
}

Rgb readFisheyeIrradiance(const GlApi& gl, int imageSize, std::vector<float>& pixels) {
    readRgba(gl, imageSize, imageSize, pixels);
    Rgb sum(0.0);
    for (size_t q = 0; q < size_t(imageSize) * imageSize; ++q)
        sum += Rgb(pixels[4 * q], pixels[4 * q + 1], pixels[4 * q + 2]);
    return sum * (4.0 / (double(imageSize) * imageSize));
}

}  // namespace ml
