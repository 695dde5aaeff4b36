// Linear RGB images and their files.
//
// Renders are kept as linear float RGB (ImageRgb) until the very end: written
// as-is to EXR/HDR, or tone mapped (core/image/ToneMap.h) to 8-bit sRGB for PNG.
// File I/O goes through OpenImageIO, which stays inside Image.cpp.
#pragma once

#include "core/Error.h"
#include "core/Math.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ml {

// A linear RGB image: float RGB interleaved, row 0 at the top, x to the right.
// Values are radiance or irradiance (see Rgb in Math.h), never display-encoded.
struct ImageRgb {
    int width = 0;            // pixels
    int height = 0;           // pixels
    std::vector<float> data;  // 3 * width * height floats

    ImageRgb() = default;
    // A width x height image filled with `fill`.
    ImageRgb(int width, int height, const Rgb& fill = Rgb(0.0));

    std::size_t pixelCount() const { return std::size_t(width) * std::size_t(height); }
    // Index in `data` of pixel (x, y)'s red value.
    std::size_t offset(int x, int y) const {
        ML_ASSERT(x >= 0 && x < width && y >= 0 && y < height, "pixel (", x, ", ", y, ") of ",
                  width, "x", height);
        return 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
    }
    Rgb at(int x, int y) const {
        const std::size_t i = offset(x, y);
        return Rgb(data[i], data[i + 1], data[i + 2]);
    }
    void set(int x, int y, const Rgb& c) {
        const std::size_t i = offset(x, y);
        data[i] = float(c.r);
        data[i + 1] = float(c.g);
        data[i + 2] = float(c.b);
    }
};

// The box pixel filter: each output pixel is the exact average of a
// factor x factor block. `factor` >= 1 must divide width and height (render
// at factor times the output resolution, then call this).
ImageRgb boxDownsample(const ImageRgb& image, int factor);

// Image files. Linear formats (EXR, HDR) store ImageRgb as-is; PNG stores
// tone-mapped 8-bit sRGB. Every failure a user can cause (bad extension,
// missing or read-only directory, unreadable file) is an InputError naming
// the file.

enum class ImageFormat { Exr, Hdr, Png };

// The format of an output path, by its extension (case-insensitive). Throws
// InputError: "unsupported output format '.xyz' (use .exr, .hdr or .png)".
ImageFormat outputFormat(const std::string& path);

// Checks, before any rendering, that `path` can be written: a supported
// extension, an existing writable directory, and not itself a directory.
// The command line calls this first so that a long render never ends in an
// error that was knowable at the start.
void checkOutputPath(const std::string& path);

// Writes a linear image as 32-bit float EXR or RGBE HDR, chosen by extension.
// Writes go to a temporary file in the same directory that is then renamed
// over `path`, so `path` is either the old file or the complete new one,
// never a partial file; the temporary is removed on failure.
void writeImageLinear(const std::string& path, const ImageRgb& image);

// Writes 8-bit sRGB (e.g. from toneMap) as PNG, with the same temporary-file
// guarantee as writeImageLinear.
//   rgb: 3 * width * height bytes, RGB interleaved, row 0 at the top
void writeImage8(const std::string& path, const std::vector<std::uint8_t>& rgb, int width,
                 int height);

// Reads the first three channels (R, G, B) of an EXR or HDR file as linear
// float, e.g. a reference image. Other formats, fewer than three channels
// and non-finite pixels are InputErrors naming the file.
ImageRgb readImageLinear(const std::string& path);

}  // namespace ml
