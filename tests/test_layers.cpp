// What `render` hands over, through the binary: the multi-layer EXR (its
// layers add up to the beauty image, its illuminance is --quantity lux's,
// its header says where it comes from) and a walkthrough's one exposure.
// Every run has a --samples budget, so two runs make the same cache and
// their images can be compared pixel for pixel.
#include "RunCommand.h"
#include "TempDirTest.h"
#include "core/image/Image.h"
#include "core/image/ToneMap.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

using namespace ml;
using test::CommandResult;
using test::runMeshlight;

namespace {

class Layers : public test::TempDirTest {
protected:
    // Runs `render` with `args` and a small image; a failure unless it exits 0.
    void render(const std::string& args) const {
        const CommandResult r = runMeshlight("render " + args + " --width 32 --height 24");
        ASSERT_EQ(r.status, 0) << r.output;
    }
};

bool has(const std::vector<std::string>& names, const std::string& name) {
    return std::find(names.begin(), names.end(), name) != names.end();
}

// Σ parts against `whole`, pixel by pixel: equal up to float rounding of the
// parts' sum (a few ulps of the largest part, whatever their signs).
void expectSum(const ImageRgb& whole, const std::vector<ImageRgb>& parts, const std::string& what) {
    int bad = 0;
    double worst = 0;
    for (size_t i = 0; i < whole.data.size(); ++i) {
        double sum = 0, largest = 0;
        for (const ImageRgb& p : parts) {
            sum += p.data[i];
            largest = std::max(largest, std::abs(double(p.data[i])));
        }
        const double error = std::abs(sum - whole.data[i]);
        worst = std::max(worst, error / std::max(largest, 1e-30));
        if (error > 8 * std::numeric_limits<float>::epsilon() * std::max({largest, std::abs(double(whole.data[i])), 1e-30}))
            ++bad;
    }
    EXPECT_EQ(bad, 0) << what << ": worst relative difference " << worst;
}

double maxValue(const ImageRgb& image) { return *std::max_element(image.data.begin(), image.data.end()); }

// 8-bit RGB pixels of a PNG and its meshlight:exposure.
struct Png {
    int width = 0, height = 0;
    std::vector<unsigned char> rgb;
    double exposure = 0;
};

Png readPng(const std::string& path) {
    Png png;
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        ADD_FAILURE() << path << ": " << OIIO::geterror();
        return png;
    }
    png.width = in->spec().width;
    png.height = in->spec().height;
    png.rgb.resize(size_t(png.width) * png.height * 3);
    EXPECT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, png.rgb.data())) << path;
    const std::string exposure = in->spec().get_string_attribute("meshlight:exposure");
    EXPECT_FALSE(exposure.empty()) << path << " has no meshlight:exposure";
    png.exposure = exposure.empty() ? 0 : std::stod(exposure);
    return png;
}

}  // namespace

TEST_F(Layers, LayersAddUpToTheBeautyImage) {
    // Full global illumination on the Cornell box (one light).
    render("cornell --voxels 16 --gather-size 8 --samples 10000 --out " + path("o.exr"));
    const std::vector<std::string> names = readImageChannelNames(path("o.exr"));
    for (const char* c : {"R", "G", "B", "emission.R", "direct.G", "indirect.B", "light.light.R",
                          "noise.G", "reflectance.R", "illuminance.Y"})
        EXPECT_TRUE(has(names, c)) << c << " missing from " << testing::PrintToString(names);
    const ImageRgb beauty = readImageLinear(path("o.exr"));
    const ImageRgb emission = readImageLayer(path("o.exr"), "emission");
    const ImageRgb direct = readImageLayer(path("o.exr"), "direct");
    const ImageRgb indirect = readImageLayer(path("o.exr"), "indirect");
    const ImageRgb light = readImageLayer(path("o.exr"), "light.light");
    EXPECT_GT(maxValue(emission), 0.0) << "the light is in view";
    EXPECT_GT(maxValue(indirect), 0.0);
    EXPECT_GT(maxValue(direct), 0.0);
    expectSum(beauty, {emission, direct, indirect}, "beauty = emission + direct + indirect");
    expectSum(direct, {light}, "direct = light.light");
    const ImageRgb reflectance = readImageLayer(path("o.exr"), "reflectance");
    EXPECT_GT(maxValue(reflectance), 0.5);
    EXPECT_LE(maxValue(reflectance), 1.0);

    // The beauty image is what --layers none writes, bit for bit.
    render("cornell --voxels 16 --gather-size 8 --samples 10000 --layers none --out " + path("plain.exr"));
    EXPECT_EQ(readImageChannelNames(path("plain.exr")), (std::vector<std::string>{"R", "G", "B"}));
    EXPECT_EQ(readImageLinear(path("plain.exr")).data, beauty.data);
}

// The noise layer: the cache's standard errors composited. Never negative;
// zero where every vertex was sampled once (the exact method: one sample, no
// spread measured); with the jittered sampler, vertices the cache sampled
// again (penumbrae, noisy gathers) show their spread, and the layer stays a
// small fraction of the image.
TEST_F(Layers, NoiseLayerIsTheCachesStandardError) {
    render("cornell --direct-only --samples 12000 --out " + path("j.exr"));
    const ImageRgb noise = readImageLayer(path("j.exr"), "noise");
    const ImageRgb direct = readImageLayer(path("j.exr"), "direct");
    double sumNoise = 0, sumDirect = 0;
    for (size_t i = 0; i < noise.data.size(); ++i) {
        ASSERT_GE(noise.data[i], 0.0f) << "value " << i;
        sumNoise += noise.data[i];
        sumDirect += direct.data[i];
    }
    EXPECT_GT(maxValue(noise), 0.0) << "some vertex was sampled twice";
    EXPECT_LT(sumNoise, 0.05 * sumDirect) << "the cache's noise is a small part of its light";
    render("cornell --direct-only --method exact --samples 3000 --out " + path("e.exr"));
    EXPECT_EQ(maxValue(readImageLayer(path("e.exr"), "noise")), 0.0);
}

TEST_F(Layers, ManyLightsSharedMeshAndLightsPastTheCap) {
    // Six panels that share a mesh where they matter little; two with a layer of their own.
    render("office:panels=3x2,desks=1,cabinets=0,partitions=0 --direct-only --samples 3000 --max-light-layers 2 "
           "--out " +
           path("o.exr"));
    const std::vector<std::string> names = readImageChannelNames(path("o.exr"));
    std::vector<ImageRgb> parts;
    int lightLayers = 0;
    for (const std::string& n : names) {
        if (n.size() > 2 && n.compare(n.size() - 2, 2, ".R") == 0 &&
            (n.rfind("light.", 0) == 0 || n.rfind("direct_", 0) == 0)) {
            parts.push_back(readImageLayer(path("o.exr"), n.substr(0, n.size() - 2)));
            lightLayers += n.rfind("light.", 0) == 0;
        }
    }
    EXPECT_EQ(lightLayers, 2) << testing::PrintToString(names);
    EXPECT_TRUE(has(names, "direct_rest.R")) << testing::PrintToString(names);
    const ImageRgb direct = readImageLayer(path("o.exr"), "direct");
    expectSum(direct, parts, "direct = light.* + direct_shared + direct_rest");
    expectSum(readImageLinear(path("o.exr")),
              {readImageLayer(path("o.exr"), "emission"), direct, readImageLayer(path("o.exr"), "indirect")},
              "beauty = emission + direct + indirect");
    EXPECT_EQ(maxValue(readImageLayer(path("o.exr"), "indirect")), 0.0) << "--direct-only";
}

TEST_F(Layers, TheLastImagesPassesAreBudgetedOverEveryLayer) {
    // `render --time` gives its last image as many sub-pixel passes as a
    // tenth of the refinement pays for, over every composite the image takes
    // at those passes: the estimate's beauty, and each RGB layer of a
    // layered EXR (a composite apiece; illuminance.Y is one pass). The count
    // printed must be what the file holds, for an EXR and for a PNG. A
    // layered EXR's pass is timed, its cost printed in whole images (of the
    // beauty pass's time); a PNG's is the beauty image alone: 1.
    for (const std::string& out : {std::string("o.exr"), std::string("o.png")}) {
        const std::string layers = out == "o.exr" ? " --max-light-layers 2" : "";
        const CommandResult r = runMeshlight("render office:panels=3x2,desks=1,cabinets=0,partitions=0 --time 1" +
                                             layers + " --width 32 --height 24 --out " + path(out));
        ASSERT_EQ(r.status, 0) << r.output;
        const size_t at = r.output.find(" composites, ");
        ASSERT_NE(at, std::string::npos) << r.output;
        const size_t from = r.output.rfind(", ", at);
        ASSERT_NE(from, std::string::npos) << r.output;
        const int printed = std::stoi(r.output.substr(from + 2, at - from - 2));
        const size_t wholeAt = at + std::string(" composites, ").size();
        const size_t wholeEnd = r.output.find(" whole images", wholeAt);
        ASSERT_NE(wholeEnd, std::string::npos) << r.output;
        const double whole = std::stod(r.output.substr(wholeAt, wholeEnd - wholeAt));
        int expected = 1;
        if (out == "o.exr")
            for (const std::string& n : readImageChannelNames(path(out)))
                expected += n.size() >= 1 && n.back() == 'R' && (n == "R" || n.compare(n.size() - 2, 2, ".R") == 0);
        EXPECT_EQ(printed, expected) << out << "\n" << r.output;
        EXPECT_GT(whole, 0.0) << r.output;
        if (out == "o.png") EXPECT_EQ(whole, 1.0) << r.output;
        if (out == "o.exr") EXPECT_GT(expected, 8) << "a layered EXR: beauty, noise, reflectance and the parts";
    }
}

TEST_F(Layers, IlluminanceIsRenderQuantityLux) {
    render("cornell --samples 3000 --direct-only --out " + path("o.exr"));
    render("cornell --samples 3000 --direct-only --quantity lux --out " + path("lux.exr"));
    const ImageChannel layer = readImageChannel(path("o.exr"), "illuminance.Y");
    const ImageChannel lux = readImageChannel(path("lux.exr"), "Y");
    EXPECT_EQ(layer.values, lux.values);
    EXPECT_GT(*std::max_element(layer.values.begin(), layer.values.end()), 1.0);
}

TEST_F(Layers, HeaderSaysSceneSettingsSamplesTimeAndError) {
    render("cornell --samples 2000 --direct-only --out " + path("o.exr"));
    auto attribute = [&](const char* name) {
        const std::optional<std::string> v = readImageAttribute(path("o.exr"), name);
        EXPECT_TRUE(v) << name;
        return v.value_or("");
    };
    EXPECT_EQ(attribute("meshlight:scene"), "cornell");
    EXPECT_NE(attribute("meshlight:command").find("--samples 2000"), std::string::npos);
    EXPECT_NE(attribute("meshlight:direct").find("jittered"), std::string::npos) << attribute("meshlight:direct");
    EXPECT_NE(attribute("meshlight:cache").find("split tolerance"), std::string::npos);
    EXPECT_EQ(attribute("meshlight:indirect"), "none (--direct-only)");
    EXPECT_GE(std::stod(attribute("meshlight:samples")), 2000);
    EXPECT_GT(std::stod(attribute("meshlight:seconds")), 0);
    const double error = std::stod(attribute("meshlight:estimated_error"));
    EXPECT_GT(error, 0);
    EXPECT_LE(error, 1);
    EXPECT_NE(attribute("meshlight:layers").find("emission + direct + indirect"), std::string::npos);
}

TEST_F(Layers, OnlyForAnExrOfRadiance) {
    for (const std::string& args : {"--layers all --out " + path("o.png"), "--layers all --out " + path("o.hdr"),
                                    "--layers all --quantity lux --out " + path("o.exr"),
                                    "--layers some --out " + path("o.exr"),
                                    "--max-light-layers 3 --layers none --out " + path("o.exr")}) {
        const CommandResult r = runMeshlight("render cornell --samples 10 " + args);
        EXPECT_EQ(r.status, 2) << args << "\n" << r.output;
    }
    EXPECT_EQ(files(), 0u);
}

// Two views of very different brightness: the Cornell box from its camera,
// then the light from just below it. Metered per frame, the second would be
// several times darker; one exposure for the path keeps it as the first's.
TEST_F(Layers, WalkthroughHasOneExposure) {
    std::ofstream(path("path.csv")) << "278,273,-800,278,273,0,0,1,0,39\n"
                                       "278,420,279.5,278,548.8,279.5,0,0,1,60\n";
    const std::string common = "cornell --direct-only --samples 3000 --camera-path " + path("path.csv");
    render(common + " --tonemap clamp --out " + path("f#.png"));
    render(common + " --layers none --out " + path("f#.exr"));
    const ImageRgb linear[2] = {readImageLinear(path("f0.exr")), readImageLinear(path("f1.exr"))};
    const double own[2] = {autoExposureScale(linear[0]), autoExposureScale(linear[1])};
    ASSERT_GT(own[0] / own[1], 3) << "the two views must differ in brightness for the test to mean anything";
    for (int f = 0; f < 2; ++f) {
        const Png png = readPng(path(concat("f", f, ".png")));
        EXPECT_NEAR(png.exposure / own[0], 1.0, 1e-6) << "frame " << f << " (its own exposure: " << own[f] << ")";
        // Clamp: each pixel is the sRGB of exposure × radiance, clipped.
        int off = 0;
        for (size_t i = 0; i < png.rgb.size() && i < linear[f].data.size(); ++i)
            off += std::abs(int(png.rgb[i]) - int(toSrgb8(own[0] * linear[f].data[i]))) > 1;
        EXPECT_EQ(off, 0) << "frame " << f;
    }
}
