#include "Image.h"

#include "core/io/AtomicFile.h"

#include <OpenImageIO/imageio.h>
#include <unistd.h>  // access(): is the output directory writable?

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <system_error>

namespace ml {

namespace fs = std::filesystem;

ImageRgb::ImageRgb(int w, int h, const Rgb& fill) : width(w), height(h) {
    ML_ASSERT(w >= 0 && h >= 0, "size ", w, "x", h);
    data.resize(3 * pixelCount());
    for (std::size_t i = 0; i < data.size(); i += 3) {
        data[i] = float(fill.r);
        data[i + 1] = float(fill.g);
        data[i + 2] = float(fill.b);
    }
}

ImageRgb boxDownsample(const ImageRgb& image, int factor) {
    ML_ASSERT(factor >= 1 && image.width % factor == 0 && image.height % factor == 0,
              "factor ", factor, " for ", image.width, "x", image.height);
    ImageRgb out(image.width / factor, image.height / factor);
    // Divide rather than multiply by 1/n: 1/n is inexact unless n is a power of two.
    const double n = double(factor) * double(factor);
    for (int y = 0; y < out.height; ++y) {
        for (int x = 0; x < out.width; ++x) {
            Rgb sum(0.0);
            for (int dy = 0; dy < factor; ++dy)
                for (int dx = 0; dx < factor; ++dx) sum += image.at(x * factor + dx, y * factor + dy);
            out.set(x, y, sum / n);
        }
    }
    return out;
}

namespace {

const char* const kSupportedFormats = "use .exr, .hdr or .png";


// OpenImageIO plugin name of each format: the temporary's name has no
// meaningful extension, so the writer is chosen explicitly.
const char* oiioFormatName(ImageFormat format) {
    switch (format) {
        case ImageFormat::Exr: return "openexr";
        case ImageFormat::Hdr: return "hdr";
        case ImageFormat::Png: return "png";
    }
    throw std::logic_error(concat("unknown ImageFormat ", int(format)));
}

// Opens a writer for `spec` on a temporary, lets `write` write the pixels
// (false on failure), then renames the temporary over `path`.
void writeAtomically(const std::string& path, ImageFormat format, const OIIO::ImageSpec& spec,
                     const std::function<bool(OIIO::ImageOutput&)>& write) {
    checkOutputDirectory(path);
    AtomicOutput temp(path);
    // Declared after `temp` so that the file is closed before it is removed.
    auto out = OIIO::ImageOutput::create(oiioFormatName(format));
    if (!out)
        throwInputError(SourceLocation{path}, "no ", oiioFormatName(format),
                        " writer: ", OIIO::geterror());
    if (!out->open(temp.path().string(), spec) || !write(*out) || !out->close())
        throwInputError(SourceLocation{path}, "cannot write: ", out->geterror());
    temp.commit();
}

// Writes `pixels` (laid out as `spec`, of type `pixelType`) through a temporary.
void writeAtomically(const std::string& path, ImageFormat format, const OIIO::ImageSpec& spec,
                     OIIO::TypeDesc pixelType, const void* pixels) {
    writeAtomically(path, format, spec,
                    [&](OIIO::ImageOutput& out) { return out.write_image(pixelType, pixels); });
}

void addAttributes(OIIO::ImageSpec& spec, const ImageAttributes& attributes) {
    for (const ImageAttribute& a : attributes) {
        if (const int* i = std::get_if<int>(&a.value))
            spec.attribute(a.name, *i);
        else if (const double* d = std::get_if<double>(&a.value))
            spec.attribute(a.name, OIIO::TypeDesc::DOUBLE, d);
        else
            spec.attribute(a.name, std::get<std::string>(a.value));
    }
}

OIIO::ImageInput::unique_ptr openImage(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throwInputError(SourceLocation{path}, "cannot read image: ", OIIO::geterror());
    return in;
}

}  // namespace

ImageFormat outputFormat(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    if (ext.empty())
        throwInputError(SourceLocation{path}, "no extension to tell the output format (",
                        kSupportedFormats, ")");
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (ext == ".exr") return ImageFormat::Exr;
    if (ext == ".hdr") return ImageFormat::Hdr;
    if (ext == ".png") return ImageFormat::Png;
    throwInputError(SourceLocation{path}, "unsupported output format '", ext, "' (",
                    kSupportedFormats, ")");
}

void checkOutputPath(const std::string& path) {
    outputFormat(path);
    checkOutputDirectory(path);
    std::error_code ec;
    if (fs::is_directory(path, ec)) throwInputError(SourceLocation{path}, "is a directory");
    // access() also reports read-only mounts; the effective/real uid
    // distinction it ignores does not arise for a command-line renderer.
    const fs::path dir = directoryOf(path);
    if (::access(dir.c_str(), W_OK) != 0)
        throwInputError(SourceLocation{path}, "output directory '", dir.string(),
                        "' is not writable");
}

void writeImageLinear(const std::string& path, const ImageRgb& image, const ImageAttributes& attributes) {
    const ImageFormat format = outputFormat(path);
    ML_ASSERT(format != ImageFormat::Png, "'", path, "' is 8-bit: tone map and use writeImage8");
    ML_ASSERT(image.width > 0 && image.height > 0 && image.data.size() == 3 * image.pixelCount(),
              image.width, "x", image.height, " image with ", image.data.size(), " floats");
    // FLOAT rather than HALF: references and their comparisons need the
    // renderer's full precision (half has 11 bits and overflows at 65504).
    OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::FLOAT);
    spec.attribute("oiio:ColorSpace", "Linear");
    addAttributes(spec, attributes);
    writeAtomically(path, format, spec, OIIO::TypeDesc::FLOAT, image.data.data());
}

void writeImageChannel(const std::string& path, const std::vector<float>& values, int width, int height,
                       const std::string& channel, const ImageAttributes& attributes) {
    const ImageFormat format = outputFormat(path);
    ML_ASSERT(format != ImageFormat::Png, "'", path, "' is 8-bit: map the values to colours and use writeImage8");
    ML_ASSERT(width > 0 && height > 0 && values.size() == size_t(width) * size_t(height), width, "x", height,
              " image with ", values.size(), " values");
    if (format == ImageFormat::Hdr) {
        ImageRgb grey(width, height);
        for (size_t i = 0; i < values.size(); ++i)
            grey.data[3 * i] = grey.data[3 * i + 1] = grey.data[3 * i + 2] = values[i];
        writeImageLinear(path, grey, attributes);
        return;
    }
    OIIO::ImageSpec spec(width, height, 1, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {channel};
    spec.attribute("oiio:ColorSpace", "Linear");
    addAttributes(spec, attributes);
    writeAtomically(path, format, spec, OIIO::TypeDesc::FLOAT, values.data());
}

void writeImage8(const std::string& path, const std::vector<std::uint8_t>& rgb, int width,
                 int height, const ImageAttributes& attributes) {
    const ImageFormat format = outputFormat(path);
    ML_ASSERT(format == ImageFormat::Png, "'", path, "' is linear: use writeImageLinear");
    ML_ASSERT(width > 0 && height > 0 && rgb.size() == 3 * std::size_t(width) * std::size_t(height),
              width, "x", height, " image with ", rgb.size(), " bytes");
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    addAttributes(spec, attributes);
    writeAtomically(path, format, spec, OIIO::TypeDesc::UINT8, rgb.data());
}

ImageLayer ImageLayer::rgb(const std::string& name, const ImageRgb& image) {
    return ImageLayer{name, {"R", "G", "B"}, image.data};
}

ImageLayer ImageLayer::single(const std::string& name, const std::string& channel, std::vector<float> values) {
    return ImageLayer{name, {channel}, std::move(values)};
}

std::string ImageLayer::channelName(size_t channel) const {
    return name.empty() ? channels[channel] : name + "." + channels[channel];
}

void writeImageLayers(const std::string& path, int width, int height, const std::vector<ImageLayer>& layers,
                      const ImageAttributes& attributes) {
    ML_ASSERT(outputFormat(path) == ImageFormat::Exr, "'", path, "': layers need an EXR");
    ML_ASSERT(width > 0 && height > 0 && !layers.empty(), width, "x", height, " image with ", layers.size(),
              " layers");
    const size_t pixels = size_t(width) * size_t(height);
    std::vector<std::string> names;
    for (const ImageLayer& layer : layers) {
        ML_ASSERT(!layer.channels.empty() && layer.values.size() == pixels * layer.channels.size(), "layer '",
                  layer.name, "': ", layer.values.size(), " values for ", layer.channels.size(), " channels of ",
                  width, "x", height);
        for (size_t c = 0; c < layer.channels.size(); ++c) names.push_back(layer.channelName(c));
    }
    std::vector<std::string> sorted = names;
    std::sort(sorted.begin(), sorted.end());
    const auto twice = std::adjacent_find(sorted.begin(), sorted.end());
    ML_ASSERT(twice == sorted.end(), "channel '", *twice, "' twice");
    OIIO::ImageSpec spec(width, height, int(names.size()), OIIO::TypeDesc::FLOAT);
    spec.channelnames = names;
    spec.alpha_channel = -1;
    spec.attribute("oiio:ColorSpace", "Linear");
    addAttributes(spec, attributes);
    // Scanline by scanline: the layers are not copied into one buffer.
    writeAtomically(path, ImageFormat::Exr, spec, [&](OIIO::ImageOutput& out) {
        std::vector<float> row(size_t(width) * names.size());
        for (int y = 0; y < height; ++y) {
            size_t channel = 0;
            for (const ImageLayer& layer : layers) {
                const size_t n = layer.channels.size();
                for (int x = 0; x < width; ++x)
                    for (size_t c = 0; c < n; ++c)
                        row[size_t(x) * names.size() + channel + c] =
                            layer.values[(size_t(y) * size_t(width) + size_t(x)) * n + c];
                channel += n;
            }
            if (!out.write_scanline(y, 0, OIIO::TypeDesc::FLOAT, row.data())) return false;
        }
        return true;
    });
}

ImageChannel readImageChannel(const std::string& path, const std::string& channel) {
    const SourceLocation where{path};
    auto in = openImage(path);
    const OIIO::ImageSpec& spec = in->spec();
    const int index = spec.channelindex(channel);
    if (index < 0) throwInputError(where, "has no channel '", channel, "'");
    ImageChannel out;
    out.width = spec.width;
    out.height = spec.height;
    out.values.resize(size_t(spec.width) * size_t(spec.height));
    if (!in->read_image(0, 0, index, index + 1, OIIO::TypeDesc::FLOAT, out.values.data()))
        throwInputError(where, "cannot read image: ", in->geterror());
    return out;
}

std::optional<std::string> readImageAttribute(const std::string& path, const std::string& name) {
    auto in = openImage(path);
    const OIIO::ParamValue* p = in->spec().find_attribute(name);
    if (!p) return std::nullopt;
    return std::string(p->get_string());
}

std::vector<std::string> readImageChannelNames(const std::string& path) {
    return openImage(path)->spec().channelnames;
}

namespace {

// Channels `names` (R, G, B of one layer) of an open linear image, or its
// first three when `firstThree` and it lacks them.
ImageRgb readRgbChannels(const std::string& path, OIIO::ImageInput& in, const std::array<std::string, 3>& names,
                         bool firstThree) {
    const SourceLocation where{path};
    const std::string format = in.format_name();
    if (format != "openexr" && format != "hdr")
        throwInputError(where, "is a ", format, " file; expected linear EXR or HDR");
    const OIIO::ImageSpec& spec = in.spec();
    std::array<int, 3> index{};
    for (int c = 0; c < 3; ++c) index[size_t(c)] = spec.channelindex(names[size_t(c)]);
    const bool named = index[0] >= 0 && index[1] >= 0 && index[2] >= 0;
    if (!named && !firstThree)
        throwInputError(where, "has no channels ", names[0], ", ", names[1], ", ", names[2]);
    if (!named && spec.nchannels < 3)
        throwInputError(where, "has ", spec.nchannels, " channels; expected R, G, B");
    if (!named) index = {0, 1, 2};

    ImageRgb image(spec.width, spec.height);
    std::vector<float> plane(image.pixelCount());
    for (int c = 0; c < 3; ++c) {
        const int i = index[size_t(c)];
        if (!in.read_image(0, 0, i, i + 1, OIIO::TypeDesc::FLOAT, plane.data()))
            throwInputError(where, "cannot read image: ", in.geterror());
        for (size_t p = 0; p < plane.size(); ++p) image.data[3 * p + size_t(c)] = plane[p];
    }
    for (std::size_t i = 0; i < image.data.size(); ++i) {
        if (!std::isfinite(image.data[i])) {
            const std::size_t pixel = i / 3;
            throwInputError(where, "pixel (", pixel % std::size_t(image.width), ", ",
                            pixel / std::size_t(image.width), ") is not finite");
        }
    }
    return image;
}

}  // namespace

ImageRgb readImageLayer(const std::string& path, const std::string& layer) {
    const std::string prefix = layer.empty() ? "" : layer + ".";
    return readRgbChannels(path, *openImage(path), {prefix + "R", prefix + "G", prefix + "B"}, false);
}

ImageRgb readImageLinear(const std::string& path) {
    return readRgbChannels(path, *openImage(path), {"R", "G", "B"}, true);
}

}  // namespace ml
