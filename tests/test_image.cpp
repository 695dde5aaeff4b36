// Images: pixel filter, files (EXR/HDR/PNG, atomic writes, path checks),
// tone mapping and photometry, checked against values known exactly.
#include "core/image/Image.h"
#include "core/image/ImageMetrics.h"
#include "core/image/Photometry.h"
#include "core/image/ToneMap.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <set>
#include <stdexcept>
#include <string>

namespace fs = std::filesystem;
using namespace ml;

namespace {

// A fresh empty directory per test, removed afterwards.
class ImageFiles : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               concat("meshlight_test_image_", ::getpid(), "_", info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ignored;
        fs::permissions(dir_, fs::perms::owner_all, fs::perm_options::add, ignored);
        fs::remove_all(dir_, ignored);
    }

    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    // Names of everything in the test directory: shows stray temporaries.
    std::set<std::string> entries() const {
        std::set<std::string> names;
        for (const auto& e : fs::directory_iterator(dir_)) names.insert(e.path().filename().string());
        return names;
    }

    fs::path dir_;
};

ImageRgb randomImage(int w, int h, unsigned seed) {
    std::mt19937 rng(seed);
    // Spread over many binades, as radiance is, to exercise every float bit.
    std::uniform_real_distribution<float> mantissa(1.0f, 2.0f);
    std::uniform_int_distribution<int> exponent(-20, 20);
    ImageRgb img(w, h);
    for (float& v : img.data) v = std::ldexp(mantissa(rng), exponent(rng));
    return img;
}

// Width, height, bit depth and colour type from a PNG's IHDR chunk, read
// directly so the test does not depend on the reader it is checking.
struct PngHeader {
    std::uint32_t width = 0, height = 0;
    int bitDepth = 0, colourType = 0;
};

PngHeader readPngHeader(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_GE(bytes.size(), 26u);
    EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    EXPECT_EQ(bytes.substr(12, 4), "IHDR");
    auto be32 = [&](std::size_t at) {
        std::uint32_t v = 0;
        for (std::size_t i = 0; i < 4; ++i) v = (v << 8) | std::uint8_t(bytes[at + i]);
        return v;
    };
    return {be32(16), be32(20), std::uint8_t(bytes[24]), std::uint8_t(bytes[25])};
}

// Inverse of the sRGB OETF, to compare tone-mapped colours in linear terms.
double srgbDecode(std::uint8_t v) {
    const double e = v / 255.0;
    return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
}

}  // namespace

// --- ImageRgb and the box filter ---

TEST(ImageRgb, RowZeroIsTopAndRgbInterleaved) {
    ImageRgb img(3, 2, Rgb(0.5));
    ASSERT_EQ(img.data.size(), 18u);
    img.set(2, 1, Rgb(1.0, 2.0, 3.0));
    EXPECT_EQ(img.offset(2, 1), 15u);
    EXPECT_EQ(img.data[15], 1.0f);
    EXPECT_EQ(img.data[17], 3.0f);
    EXPECT_EQ(img.at(2, 1), Rgb(1.0, 2.0, 3.0));
    EXPECT_EQ(img.at(0, 0), Rgb(0.5));
    EXPECT_THROW(img.at(3, 0), std::logic_error);
}

TEST(BoxDownsample, AveragesBlocksExactly) {
    // Factor 3 (n = 9, not a power of two): block sums of 0..8 and 9..17 give 4 and 13 exactly.
    ImageRgb img(6, 3);
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 6; ++x) {
            const double v = (x / 3) * 9 + y * 3 + x % 3;
            img.set(x, y, Rgb(v, 2.0 * v, -v));
        }
    const ImageRgb out = boxDownsample(img, 3);
    ASSERT_EQ(out.width, 2);
    ASSERT_EQ(out.height, 1);
    EXPECT_EQ(out.at(0, 0), Rgb(4.0, 8.0, -4.0));
    EXPECT_EQ(out.at(1, 0), Rgb(13.0, 26.0, -13.0));
}

TEST(BoxDownsample, FactorOneIsIdentityAndNonDivisorIsABug) {
    const ImageRgb img = randomImage(4, 6, 1);
    EXPECT_EQ(boxDownsample(img, 1).data, img.data);
    EXPECT_THROW(boxDownsample(img, 4), std::logic_error);
    EXPECT_THROW(boxDownsample(img, 0), std::logic_error);
}

// --- Metrics ---

ImageRgb uniformImage(int w, int h, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    ImageRgb img(w, h);
    for (float& v : img.data) v = u(rng);
    return img;
}

ImageRgb scaled(ImageRgb img, float k) {
    for (float& v : img.data) v *= k;
    return img;
}

TEST(RelativeRmse, BrightImagesKeepTheFloorOfATenthExactly) {
    // A reference of 0.5 everywhere (mean above 0.1): the floor is 0.1².
    // Pixels are 32-bit floats (0.55 and 0.03 are not exact): 1e-7.
    const ImageRgb r(8, 4, Rgb(0.5));
    EXPECT_DOUBLE_EQ(relativeRmseFloor(r), 0.01);
    EXPECT_NEAR(relativeRmse(ImageRgb(8, 4, Rgb(0.55)), r), 0.05 / std::sqrt(0.26), 1e-7);
    EXPECT_NEAR(relativeRmsError(ImageRgb(8, 4, Rgb(0.03)), r), 0.03 / std::sqrt(0.26), 1e-7);
    // Black: the floor stays 0.1² (no division by zero).
    EXPECT_DOUBLE_EQ(relativeRmseFloor(ImageRgb(8, 4, Rgb(0.0))), 0.01);
    EXPECT_NEAR(relativeRmse(ImageRgb(8, 4, Rgb(0.02)), ImageRgb(8, 4, Rgb(0.0))), 0.2, 1e-7);
}

TEST(RelativeRmse, DimImagesMeasureTheSameAtAnyScale) {
    // Random images of mean 0.05 and under: the floor is the reference's
    // mean squared, so scaling an image and its reference by any factor
    // that keeps the mean under 0.1 leaves the error as it was (exactly,
    // up to rounding); a fixed floor made the dimmer one read 1,000 times
    // lower.
    const ImageRgb r = scaled(uniformImage(16, 8, 3), 0.1f), x = scaled(uniformImage(16, 8, 4), 0.1f);
    const double at1 = relativeRmse(x, r);
    ASSERT_GT(at1, 0.1);
    for (float k : {1e-3f, 1e-1f, 1.5f})
        EXPECT_NEAR(relativeRmse(scaled(x, k), scaled(r, k)), at1, 1e-5 * at1) << "scale " << k;
    EXPECT_NEAR(relativeRmsError(scaled(x, 1e-3f), scaled(r, 1e-3f)), relativeRmsError(x, r), 1e-5 * at1);
}

// --- Files ---

TEST_F(ImageFiles, ExrRoundTripIsExact) {
    const ImageRgb img = randomImage(7, 5, 42);  // not square: catches transposition
    writeImageLinear(path("a.exr"), img);
    const ImageRgb back = readImageLinear(path("a.exr"));
    EXPECT_EQ(back.width, 7);
    EXPECT_EQ(back.height, 5);
    EXPECT_EQ(back.data, img.data);
    EXPECT_EQ(entries(), std::set<std::string>{"a.exr"});
}

TEST_F(ImageFiles, HdrRoundTripWithinRgbePrecision) {
    const ImageRgb img = randomImage(5, 3, 7);
    writeImageLinear(path("a.HDR"), img);  // extensions are case-insensitive
    const ImageRgb back = readImageLinear(path("a.HDR"));
    ASSERT_EQ(back.data.size(), img.data.size());
    // RGBE shares one exponent per pixel: each channel keeps 8 bits relative
    // to the pixel's largest.
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const Rgb a = img.at(x, y), b = back.at(x, y);
            const double largest = std::max({a.r, a.g, a.b});
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(b[c], a[c], largest / 64.0);
        }
}

TEST_F(ImageFiles, OneChannelAndAttributesRoundTrip) {
    const std::vector<float> lux = {0.0f, 1.5f, 2e4f, 3.25f, 7.0f, 0.125f};  // 3 x 2, row 0 at the top
    writeImageChannel(path("lux.exr"), lux, 3, 2, "Y",
                      {{"meshlight:spp", 84}, {"meshlight:quantity", std::string("illuminance")},
                       {"meshlight:scale", 0.5}});
    const ImageChannel back = readImageChannel(path("lux.exr"), "Y");
    EXPECT_EQ(back.width, 3);
    EXPECT_EQ(back.height, 2);
    EXPECT_EQ(back.values, lux);
    EXPECT_EQ(readImageAttribute(path("lux.exr"), "meshlight:spp"), std::optional<std::string>("84"));
    EXPECT_EQ(readImageAttribute(path("lux.exr"), "meshlight:quantity"), std::optional<std::string>("illuminance"));
    EXPECT_EQ(readImageAttribute(path("lux.exr"), "meshlight:scale"), std::optional<std::string>("0.5"));
    EXPECT_EQ(readImageAttribute(path("lux.exr"), "meshlight:none"), std::nullopt);
    EXPECT_THROW(readImageChannel(path("lux.exr"), "R"), InputError);
    // RGBE has no single channel: the value goes to all three.
    writeImageChannel(path("lux.hdr"), lux, 3, 2, "Y");
    const ImageRgb grey = readImageLinear(path("lux.hdr"));
    EXPECT_NEAR(grey.at(1, 0).g, 1.5, 1.5 / 64);
    EXPECT_EQ(entries(), (std::set<std::string>{"lux.exr", "lux.hdr"}));
}

TEST_F(ImageFiles, PngHasTheRightSize) {
    std::vector<std::uint8_t> rgb(3 * 13 * 7, 200);
    writeImage8(path("a.png"), rgb, 13, 7);
    const PngHeader h = readPngHeader(path("a.png"));
    EXPECT_EQ(h.width, 13u);
    EXPECT_EQ(h.height, 7u);
    EXPECT_EQ(h.bitDepth, 8);
    EXPECT_EQ(h.colourType, 2);  // truecolour RGB, no alpha
    EXPECT_EQ(entries(), std::set<std::string>{"a.png"});
}

TEST_F(ImageFiles, OverwriteReplacesTheFileAndLeavesNoTemporary) {
    writeImageLinear(path("a.exr"), ImageRgb(2, 2, Rgb(1.0)));
    writeImageLinear(path("a.exr"), ImageRgb(3, 1, Rgb(2.0)));
    const ImageRgb back = readImageLinear(path("a.exr"));
    EXPECT_EQ(back.width, 3);
    EXPECT_EQ(back.at(2, 0), Rgb(2.0));
    EXPECT_EQ(entries(), std::set<std::string>{"a.exr"});
}

TEST_F(ImageFiles, UnsupportedExtensionThrowsAndWritesNothing) {
    try {
        checkOutputPath(path("a.xyz"));
        FAIL() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(
                      "unsupported output format '.xyz' (use .exr, .hdr or .png)"),
                  std::string::npos)
            << e.what();
        EXPECT_EQ(e.where().file, path("a.xyz"));
    }
    EXPECT_THROW(checkOutputPath(path("noextension")), InputError);
    EXPECT_THROW(writeImageLinear(path("a.xyz"), ImageRgb(1, 1)), InputError);
    EXPECT_THROW(writeImage8(path("a.jpg"), {0, 0, 0}, 1, 1), InputError);
    EXPECT_TRUE(entries().empty());
}

TEST_F(ImageFiles, MissingDirectoryThrowsAndWritesNothing) {
    const std::string target = path("missing/a.exr");
    try {
        checkOutputPath(target);
        FAIL() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
    }
    EXPECT_THROW(writeImageLinear(target, ImageRgb(1, 1)), InputError);
    EXPECT_THROW(writeImage8(path("missing/a.png"), {0, 0, 0}, 1, 1), InputError);
    EXPECT_TRUE(entries().empty());
}

TEST_F(ImageFiles, FailedWriteLeavesNoPartialFile) {
    // The target is a directory: the image is written in full to the
    // temporary, then the rename over the target fails.
    fs::create_directory(path("a.exr"));
    fs::create_directory(path("a.png"));
    EXPECT_THROW(checkOutputPath(path("a.exr")), InputError);
    EXPECT_THROW(writeImageLinear(path("a.exr"), randomImage(4, 4, 3)), InputError);
    EXPECT_THROW(writeImage8(path("a.png"), {0, 0, 0}, 1, 1), InputError);
    EXPECT_EQ(entries(), (std::set<std::string>{"a.exr", "a.png"}));
    EXPECT_TRUE(fs::is_empty(path("a.exr")));
    EXPECT_TRUE(fs::is_empty(path("a.png")));
}

TEST_F(ImageFiles, ReadOnlyDirectoryIsRejectedBeforeRendering) {
    if (::geteuid() == 0) GTEST_SKIP() << "root may write anywhere";
    fs::permissions(dir_, fs::perms::owner_write, fs::perm_options::remove);
    EXPECT_THROW(checkOutputPath(path("a.exr")), InputError);
}

TEST_F(ImageFiles, ReadErrorsNameTheFile) {
    try {
        readImageLinear(path("none.exr"));
        FAIL() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_EQ(e.where().file, path("none.exr"));
    }
    // A PNG holds display-encoded values, not linear ones.
    writeImage8(path("a.png"), {10, 20, 30}, 1, 1);
    EXPECT_THROW(readImageLinear(path("a.png")), InputError);
}

// --- Tone mapping ---

TEST(ToneMap, OperatorNamesRoundTripAndUnknownListsThem) {
    for (ToneOperator op : {ToneOperator::Aces, ToneOperator::Reinhard, ToneOperator::Clamp})
        EXPECT_EQ(parseToneOperator(toneOperatorName(op)), op);
    try {
        parseToneOperator("filmic");
        FAIL() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "unknown tone operator 'filmic' (use aces, reinhard or clamp)");
    }
}

TEST(ToneMap, SrgbOetfAtKnownPoints) {
    EXPECT_EQ(toSrgb8(0.0), 0);
    EXPECT_EQ(toSrgb8(1.0), 255);
    EXPECT_EQ(toSrgb8(0.5), 188);  // a 2.2 gamma would give 186
    EXPECT_EQ(toSrgb8(-1.0), 0);
    EXPECT_EQ(toSrgb8(7.0), 255);
    // Linear segment below the boundary, and the two pieces meet at it.
    EXPECT_DOUBLE_EQ(srgbOetf(0.002), 12.92 * 0.002);
    EXPECT_NEAR(srgbOetf(0.0031308), 0.04045, 1e-6);
    EXPECT_NEAR(srgbOetf(0.0031309), 0.04045, 1e-5);
    EXPECT_NEAR(srgbOetf(0.2), 1.055 * std::pow(0.2, 1.0 / 2.4) - 0.055, 1e-15);
}

TEST(ToneMap, AutoExposureMapsLogAverageToMiddleGrey) {
    for (double y : {1e-3, 0.18, 1.0, 250.0}) {
        // Grey and coloured pixels of luminance y (Rec.709 weights sum to 1).
        EXPECT_NEAR(autoExposureScale(ImageRgb(4, 3, Rgb(y))), 0.18 / y, 1e-6 * 0.18 / y);
        const Rgb green(0.0, y / 0.7152, 0.0);
        EXPECT_NEAR(autoExposureScale(ImageRgb(2, 2, green)), 0.18 / y, 1e-6 * 0.18 / y);
    }
    // Log average of 1 and 4 is 2; black pixels are ignored.
    ImageRgb img(4, 1);
    img.set(0, 0, Rgb(1.0));
    img.set(1, 0, Rgb(4.0));
    EXPECT_NEAR(autoExposureScale(img), 0.09, 1e-12);
    EXPECT_EQ(autoExposureScale(ImageRgb(3, 3)), 1.0);
}

// Near-black pixels are left out like black ones: a frame whose unlit half
// holds rounding (1e-12) is exposed for its lit half, not 10^5 times over.
TEST(ToneMap, AutoExposureIgnoresNearBlackPixels) {
    ImageRgb img(10, 10, Rgb(1e-12));
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 10; ++x) img.set(x, y, Rgb(0.5));
    EXPECT_NEAR(autoExposureScale(img), 0.18 / 0.5, 1e-9);
    // A pixel at 1e-3 of the lit level still counts.
    img.set(0, 9, Rgb(5e-4));
    EXPECT_LT(autoExposureScale(img), 0.18 / 0.5 * 1.2);
    EXPECT_GT(autoExposureScale(img), 0.18 / 0.5);
}

TEST(ToneMap, ExposureAndClampOperator) {
    ToneMapSettings s;
    s.op = ToneOperator::Clamp;
    s.autoExposure = false;
    s.exposureEV = 1.0;
    const std::vector<std::uint8_t> out = toneMap(ImageRgb(2, 1, Rgb(0.25)), s);
    EXPECT_EQ(out, std::vector<std::uint8_t>(6, 188));  // 0.25 * 2^1 = 0.5

    // Auto exposure takes a constant image to 0.18, then +1 EV to 0.36.
    s.autoExposure = true;
    EXPECT_EQ(toneMap(ImageRgb(1, 1, Rgb(40.0)), s)[0], toSrgb8(0.36));
}

TEST(ToneMap, AcesIsMonotoneFromBlackToWhite) {
    ToneMapSettings s;
    s.autoExposure = false;
    ImageRgb ramp(81, 1);
    ramp.set(0, 0, Rgb(0.0));
    for (int x = 1; x < ramp.width; ++x) ramp.set(x, 0, Rgb(std::pow(10.0, -4.0 + 0.1 * x)));
    const std::vector<std::uint8_t> out = toneMap(ramp, s);
    EXPECT_EQ(out[0], 0);
    for (std::size_t i = 3; i < out.size(); ++i) EXPECT_GE(out[i], out[i - 3]) << "at " << i / 3;
    EXPECT_GE(out.back(), 254);  // 10^4
    EXPECT_EQ(toneMap(ImageRgb(1, 1, Rgb(1e6)), s)[0], 255);
}

TEST(ToneMap, ReinhardPreservesChroma) {
    ToneMapSettings s;
    s.op = ToneOperator::Reinhard;
    s.autoExposure = false;
    EXPECT_EQ(toneMap(ImageRgb(1, 1, Rgb(1.0)), s)[0], 188);  // 1 / (1 + 1) = 0.5

    const std::vector<std::uint8_t> out = toneMap(ImageRgb(1, 1, Rgb(2.0, 1.0, 0.5)), s);
    const double r = srgbDecode(out[0]), g = srgbDecode(out[1]), b = srgbDecode(out[2]);
    EXPECT_NEAR(r / g, 2.0, 0.03);
    EXPECT_NEAR(b / g, 0.5, 0.02);
    EXPECT_NEAR(g, 1.0 / (1.0 + luminance(Rgb(2.0, 1.0, 0.5))), 0.005);
}

TEST(ToneMap, NonFiniteInputIsABug) {
    ImageRgb img(2, 2, Rgb(1.0));
    img.set(1, 1, Rgb(0.0, std::nan(""), 0.0));
    EXPECT_THROW(toneMap(img, ToneMapSettings{}), std::logic_error);
    img.set(1, 1, Rgb(kInf));
    EXPECT_THROW(autoExposureScale(img), std::logic_error);
}

// --- Photometry ---

TEST(Photometry, PureRedGivesEfficacyTimesTheRedWeightExactly) {
    const Rgb red(1, 0, 0);  // W/m²
    EXPECT_NEAR(photometryNamed("radiance").luminous(red), 179 * 0.265, 1e-9);
    EXPECT_NEAR(photometryNamed("radiance").luminous(red), 47.435, 1e-9);
    EXPECT_NEAR(photometryNamed("rec709").luminous(red), 38.0554, 1e-9);  // 179 × 0.2126
    EXPECT_NEAR(photometryNamed("radiance").luminous(Rgb(0, 1, 0)), 119.93, 1e-9);
    EXPECT_NEAR(photometryNamed("rec709").luminous(Rgb(0, 0, 2)), 2 * 179 * 0.0722, 1e-9);
    // The weights sum to 1: white of 1 W/m² is the efficacy in both.
    for (const char* name : {"radiance", "rec709"}) {
        const Photometry p = photometryNamed(name);
        EXPECT_NEAR(p.luminous(Rgb(1.0)), 179, 1e-9) << name;
        EXPECT_EQ(p.name, name);
        EXPECT_EQ(p.factors(), p.efficacy * p.weights);
    }
    // RADIANCE's is the default.
    EXPECT_EQ(Photometry().weights, photometryNamed("radiance").weights);
    EXPECT_EQ(Photometry().efficacy, kRadianceEfficacy);
}

TEST(Photometry, UnknownNamesAndBadEfficaciesAreInputErrors) {
    try {
        photometryNamed("cie1931");
        FAIL() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("radiance|rec709"), std::string::npos) << e.what();
    }
    Photometry p;
    p.efficacy = 0;
    EXPECT_THROW(p.validate(), InputError);
    p.efficacy = 683;
    EXPECT_NO_THROW(p.validate());
}
