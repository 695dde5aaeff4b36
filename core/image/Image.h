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
#include <optional>
#include <string>
#include <variant>
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

// Metadata stored in an image file's header beside the pixels, e.g.
// {"meshlight:spp", 256}. EXR keeps every attribute; HDR and PNG may drop them.
struct ImageAttribute {
    std::string name;
    std::variant<int, double, std::string> value;
};
using ImageAttributes = std::vector<ImageAttribute>;

// Writes a linear image as 32-bit float EXR or RGBE HDR, chosen by extension.
// Writes go to a temporary file in the same directory that is then renamed
// over `path`, so `path` is either the old file or the complete new one,
// never a partial file; the temporary is removed on failure.
void writeImageLinear(const std::string& path, const ImageRgb& image, const ImageAttributes& attributes = {});

// Writes one linear value per pixel (row 0 at the top), e.g. illuminance in
// lux: an EXR with the single 32-bit float channel `channel` ("Y"), or, as
// RGBE HDR has no single channel, an HDR with the value in all three.
// Atomic like writeImageLinear.
void writeImageChannel(const std::string& path, const std::vector<float>& values, int width, int height,
                       const std::string& channel, const ImageAttributes& attributes = {});

// Writes 8-bit sRGB (e.g. from toneMap) as PNG, with the same temporary-file
// guarantee as writeImageLinear. PNG keeps string attributes (text chunks);
// give numbers as text.
//   rgb: 3 * width * height bytes, RGB interleaved, row 0 at the top
void writeImage8(const std::string& path, const std::vector<std::uint8_t>& rgb, int width,
                 int height, const ImageAttributes& attributes = {});

// One layer of a multi-layer EXR (writeImageLayers), OpenEXR's naming: the
// channels of layer "direct" are "direct.R", "direct.G", "direct.B"; a
// layer named "" is the beauty image, channels "R", "G", "B".
struct ImageLayer {
    std::string name;                   // "" or letters, digits, '_' and '.' (e.g. "light.lamp_1")
    std::vector<std::string> channels;  // e.g. {"R", "G", "B"} or {"Y"}
    std::vector<float> values;          // channels.size() per pixel, interleaved, row 0 at the top

    static ImageLayer rgb(const std::string& name, const ImageRgb& image);
    static ImageLayer single(const std::string& name, const std::string& channel, std::vector<float> values);
    // "direct.R", or "R" for the beauty layer.
    std::string channelName(size_t channel) const;
};

// Writes `layers` (each width × height) as one 32-bit float EXR with every
// layer's channels, atomically like writeImageLinear. `path` must be .exr.
void writeImageLayers(const std::string& path, int width, int height, const std::vector<ImageLayer>& layers,
                      const ImageAttributes& attributes = {});

// Reads the channels R, G, B of an EXR or HDR file as linear float (the
// first three where they have other names), e.g. a reference image or a
// multi-layer EXR's beauty image. Other formats, fewer than three channels
// and non-finite pixels are InputErrors naming the file.
ImageRgb readImageLinear(const std::string& path);

// The RGB layer `layer` of a multi-layer EXR (channels LAYER.R, LAYER.G,
// LAYER.B; "" reads R, G, B). InputError naming the file when it lacks one.
ImageRgb readImageLayer(const std::string& path, const std::string& layer);

// Every channel name of an image file, in the order the file gives them.
std::vector<std::string> readImageChannelNames(const std::string& path);

// A one-channel image read back: the channel named `channel` of an EXR or
// HDR file ("Y" of writeImageChannel). InputError naming the file when it
// is missing, unreadable or has no such channel.
struct ImageChannel {
    int width = 0, height = 0;
    std::vector<float> values;  // row 0 at the top
};
ImageChannel readImageChannel(const std::string& path, const std::string& channel);

// An attribute of an image file's header as text (an int as its digits),
// e.g. "84" for meshlight:spp; none when the file lacks it. InputError
// naming the file when it cannot be read.
std::optional<std::string> readImageAttribute(const std::string& path, const std::string& name);

}  // namespace ml
