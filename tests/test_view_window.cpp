// `meshlight view` end to end, through the binary: bad scripts and options
// are refused before any window opens (ViewCli, no display needed), and the
// scripted viewer in a real GLFW window (ViewWindow: under Xvfb in CI, see
// run_view_window_tests.sh) matches `render`, switches lights linearly and
// stops cleanly on Ctrl-C.
//
// Tolerances:
//  [exact]  With the same scene, seed, sample budget (--samples) and view
//           (camera and size: the refinement serves the camera), the worker
//           builds the same cache whatever the timing (a budget in samples
//           repeats on any machine), and the screenshot's EXR is composited
//           and box-filtered by the very code `render` uses: equal bit for bit.
//  [8-bit]  The window's PNG is tone-mapped on the GPU, render's on the CPU
//           (float against double before rounding, and auto exposure metered
//           on the GPU's box filter against the CPU's): one level.
//  [linear] Images of the same cache with other light weights: sums in float
//           (test_view.cpp): 1e-5 of the value plus 1e-6 of the largest.
#include "core/image/Image.h"
#include "core/image/ToneMap.h"

#include "RunCommand.h"
#include "TempDirTest.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace fs = std::filesystem;
using namespace ml;
using test::CommandResult;
using test::meshlightCommand;
using test::runCommand;
using test::runMeshlight;

namespace {

using ViewCli = test::TempDirTest;

class ViewWindow : public test::TempDirTest {
protected:
    void SetUp() override {
        if (!std::getenv("DISPLAY")) GTEST_SKIP() << "no DISPLAY (ctest runs these under xvfb-run)";
        TempDirTest::SetUp();
    }
};

std::vector<uint8_t> readPng(const std::string& file, int& width, int& height) {
    auto in = OIIO::ImageInput::open(file);
    if (!in) return {};
    const OIIO::ImageSpec& spec = in->spec();
    width = spec.width;
    height = spec.height;
    std::vector<uint8_t> pixels(size_t(width) * height * spec.nchannels);
    in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, pixels.data());
    std::vector<uint8_t> rgb;
    for (size_t i = 0; i < size_t(width) * height; ++i)
        for (int c = 0; c < 3; ++c) rgb.push_back(pixels[i * spec.nchannels + size_t(c)]);
    return rgb;
}

void expectLinear(const ImageRgb& x, const ImageRgb& expected, const char* what) {
    ASSERT_EQ(x.data.size(), expected.data.size()) << what;
    float largest = 0;
    for (float v : expected.data) largest = std::max(largest, std::abs(v));
    ASSERT_GT(largest, 0) << what;
    size_t bad = 0;
    for (size_t i = 0; i < x.data.size(); ++i)
        if (std::abs(x.data[i] - expected.data[i]) > 1e-5 * std::abs(expected.data[i]) + 1e-6 * largest && ++bad <= 3)
            ADD_FAILURE() << what << ": value " << i << " is " << x.data[i] << ", expected " << expected.data[i];
    EXPECT_EQ(bad, 0u) << what;
}

}  // namespace

// --- Refused before the window opens --------------------------------------------

TEST_F(ViewCli, MalformedScriptsNameFileAndLine) {
    const std::string bad = write("bad.txt", "wait 0.1\n# fine so far\njump 3\n");
    CommandResult r = runMeshlight("view cornell --script " + bad);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find(bad + ":3: unknown action 'jump'"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("OpenGL"), std::string::npos) << "no window may open: " << r.output;

    const std::string light = write("light.txt", "wait-done\nlight 3 off\n");
    r = runMeshlight("view cornell --script " + light);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find(light + ":2: no light '3' in the scene (lights: 0 'light')"), std::string::npos)
        << r.output;

    const std::string keys =
        write("keys.txt", "camera t=1 pos=0,0,1 target=0,0,0\ncamera t=0.5 pos=0,0,2 target=0,0,0\n");
    r = runMeshlight("view cornell --script " + keys);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find(keys + ":2: camera t=0.5 comes before the keyframe at line 1"), std::string::npos)
        << r.output;
}

TEST_F(ViewCli, UnknownLightGroupListsTheScenesGroups) {
    const std::string scene = std::string(MESHLIGHT_TEST_DATA) + "/../../data/spot_room.gltf";
    const std::string s = write("group.txt", "wait-done\ngroup Panel off\n");
    const CommandResult r = runMeshlight("view " + scene + " --script " + s);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find(s + ":2: no light group 'Panel' in the scene (groups: 'Spot' (2 lights), 'Bulb')"),
              std::string::npos)
        << r.output;
    EXPECT_EQ(r.output.find("OpenGL"), std::string::npos) << "no window may open: " << r.output;
}

TEST_F(ViewCli, BadOptionsAndMissingFiles) {
    CommandResult r = runMeshlight("view cornell --frobnicate 3");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("unknown option '--frobnicate'"), std::string::npos) << r.output;
    r = runMeshlight("view cornell --script-step 0.1");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("--script-step needs --script"), std::string::npos) << r.output;
    r = runMeshlight("view cornell --units furlong");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("unknown length unit 'furlong'"), std::string::npos) << r.output;
    r = runMeshlight("view cornell --script " + path("missing.txt"));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find(path("missing.txt") + ": cannot read the script"), std::string::npos) << r.output;
    // Without a display: a clear message, not a crash.
    r = runCommand("env -u DISPLAY -u WAYLAND_DISPLAY " + meshlightCommand("view cornell"));
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.output.find("there is no display"), std::string::npos) << r.output;
}

// --- In a window --------------------------------------------------------------------

TEST_F(ViewWindow, ScreenshotsEqualRenderOfTheSameViewAndSamples) {
    // One sample per pixel (the window's forward pass) and 2×2 (the fused pass).
    for (int supersample : {1, 2}) {
        SCOPED_TRACE("supersample " + std::to_string(supersample));
        const std::string s = write("same.txt", concat("wait-done\n"
                                                       "screenshot ", path("v.exr"), "\n"
                                                       "ui off\n"
                                                       "exposure auto\n"
                                                       "screenshot ", path("v.png"), "\n"
                                                       "quit\n"));
        const std::string common = concat(" --width 96 --height 72 --samples 4000 --direct-only --supersample ",
                                          supersample, " --seed 3");
        CommandResult v = runMeshlight("view cornell --script " + s + common);
        ASSERT_EQ(v.status, 0) << v.output;
        // The window composites one pass and no outline passes; render's are its own.
        CommandResult r =
            runMeshlight("render cornell --subpixel-passes 1 --outline-passes 0 --out " + path("r.exr") + common);
        ASSERT_EQ(r.status, 0) << r.output;
        const ImageRgb viewed = readImageLinear(path("v.exr"));
        const ImageRgb rendered = readImageLinear(path("r.exr"));
        ASSERT_EQ(viewed.width, 96);
        ASSERT_EQ(viewed.height, 72);
        ASSERT_EQ(viewed.data.size(), rendered.data.size());
        size_t differ = 0;
        for (size_t i = 0; i < viewed.data.size(); ++i) differ += viewed.data[i] != rendered.data[i];
        EXPECT_EQ(differ, 0u) << "[exact] of " << viewed.data.size() << " values";

        // The window as shown, against render's tone mapping of its own image.
        int w = 0, h = 0;
        const std::vector<uint8_t> png = readPng(path("v.png"), w, h);
        ASSERT_EQ(w, 96);
        ASSERT_EQ(h, 72);
        const std::vector<uint8_t> cpu = toneMap(rendered, ToneMapSettings{});
        ASSERT_EQ(png.size(), cpu.size());
        int worst = 0;
        for (size_t i = 0; i < png.size(); ++i) worst = std::max(worst, std::abs(int(png[i]) - int(cpu[i])));
        EXPECT_LE(worst, 1) << "[8-bit]";
    }
}

TEST_F(ViewWindow, LightsSwitchDimAndShowAloneLinearly) {
    const std::string scene = std::string(MESHLIGHT_TEST_DATA) + "/view_two_lights.obj";
    // Each change and its screenshot fall in one frame: what the image shows
    // right after a change is already the changed light.
    const std::string s = write("lights.txt", concat("wait-done\n"
                                                     "screenshot ", path("all.exr"), "\n"
                                                     "light lampB off\n"
                                                     "screenshot ", path("offB.exr"), "\n"
                                                     "light lampB on\n"
                                                     "mode light 0\n"
                                                     "screenshot ", path("a.exr"), "\n"
                                                     "mode light lampB\n"
                                                     "screenshot ", path("b.exr"), "\n"
                                                     "mode final\n"
                                                     "light 0 intensity 2\n"
                                                     "light 1 color 0.5,1,0\n"
                                                     "screenshot ", path("mixed.exr"), "\n"
                                                     "mode reflectance\n"
                                                     "screenshot ", path("kd.exr"), "\n"
                                                     "mode lux\n"
                                                     "screenshot ", path("lux.exr"), "\n"
                                                     "screenshot ", path("lux.png"), "\n"
                                                     "quit\n"));
    CommandResult v = runMeshlight("view " + scene + " --script " + s +
                                   " --width 80 --height 60 --samples 3000 --direct-only --supersample 2"
                                   // A mesh per light everywhere: relighting is then exact; where
                                   // lights share a mesh it is their power-weighted mean there.
                                   " --light-share 0");
    ASSERT_EQ(v.status, 0) << v.output;
    const ImageRgb all = readImageLinear(path("all.exr")), offB = readImageLinear(path("offB.exr")),
                   a = readImageLinear(path("a.exr")), b = readImageLinear(path("b.exr")),
                   mixed = readImageLinear(path("mixed.exr")), kd = readImageLinear(path("kd.exr")),
                   lux = readImageLinear(path("lux.exr"));
    // Light B off is light A alone: the same weights, the same image.
    EXPECT_EQ(offB.data, a.data) << "[exact]";
    ImageRgb sum = a;
    for (size_t i = 0; i < sum.data.size(); ++i) sum.data[i] += b.data[i];
    expectLinear(all, sum, "A + B");
    ImageRgb expected = a;
    const float tint[3] = {0.5f, 1.0f, 0.0f};
    for (size_t i = 0; i < expected.data.size(); ++i) expected.data[i] = 2 * a.data[i] + tint[i % 3] * b.data[i];
    expectLinear(mixed, expected, "2 A + tinted B");
    // The modes show what they say: reflectance within [0, 1] and the floor's
    // 0.6 grey somewhere; lux exactly where a surface reflects light (its
    // radiance is positive and it is no emitter: Kd > 0), grey in all channels.
    bool floorSeen = false;
    size_t lit = 0;
    for (int y = 0; y < kd.height; ++y)
        for (int x = 0; x < kd.width; ++x) {
            const Rgb k = kd.at(x, y), l = all.at(x, y);
            EXPECT_LE(std::max({k.r, k.g, k.b}), 1.0);
            floorSeen = floorSeen || (std::abs(k.r - 0.6) < 1e-6 && std::abs(k.b - 0.6) < 1e-6);
            if (k.r > 0 && l.r > 0) {
                EXPECT_GT(lux.at(x, y).r, 0) << x << "," << y;
                ++lit;
            }
            EXPECT_EQ(lux.at(x, y).r, lux.at(x, y).g);
        }
    EXPECT_TRUE(floorSeen);
    EXPECT_GT(lit, size_t(kd.width * kd.height / 10));
    EXPECT_TRUE(fs::exists(path("lux.png")));
}

TEST_F(ViewWindow, AGroupSwitchesAndDimsAsItsLights) {
    // Two spots in group 'Spot' and a bulb, all punctual: no emitting faces,
    // each light's image only its cache mesh.
    const std::string scene = std::string(MESHLIGHT_TEST_DATA) + "/../../data/spot_room.gltf";
    const std::string s = write("groups.txt", concat("wait-done\n"
                                                     "screenshot ", path("all.exr"), "\n"
                                                     "group Spot off\n"
                                                     "screenshot ", path("spotsOff.exr"), "\n"
                                                     "group Spot on\n"
                                                     "mode light Bulb\n"
                                                     "screenshot ", path("bulb.exr"), "\n"
                                                     "mode final\n"
                                                     "group Spot dim 0.5\n"
                                                     "screenshot ", path("groupHalf.exr"), "\n"
                                                     "group Spot dim 1\n"
                                                     "light Spot.001 intensity 0.5\n"
                                                     "light Spot.002 intensity 0.5\n"
                                                     "screenshot ", path("eachHalf.exr"), "\n"
                                                     "quit\n"));
    CommandResult v = runMeshlight("view " + scene + " --script " + s +
                                   " --width 80 --height 60 --samples 3000 --direct-only --supersample 2"
                                   " --light-share 0");  // a mesh per light everywhere: relighting is exact
    ASSERT_EQ(v.status, 0) << v.output;
    // The viewer lists each luminaire's flux (plan's: 462.8 lm a spot, 1659 lm the bulb).
    EXPECT_NE(v.output.find("'Spot.001' spot 462.8 lm"), std::string::npos) << v.output;
    EXPECT_NE(v.output.find("group 'Spot': 2 lights, 925.6 lm"), std::string::npos) << v.output;
    const ImageRgb all = readImageLinear(path("all.exr")), spotsOff = readImageLinear(path("spotsOff.exr")),
                   bulb = readImageLinear(path("bulb.exr")), groupHalf = readImageLinear(path("groupHalf.exr")),
                   eachHalf = readImageLinear(path("eachHalf.exr"));
    // The group off is the bulb alone, and the group dimmed is each light
    // dimmed: the same weights, the same image.
    EXPECT_EQ(spotsOff.data, bulb.data) << "[exact]";
    EXPECT_EQ(groupHalf.data, eachHalf.data) << "[exact]";
    EXPECT_NE(all.data, spotsOff.data) << "the spots light something in view";
    // Half the spots: (all + bulb alone) / 2.
    ImageRgb expected = all;
    for (size_t i = 0; i < expected.data.size(); ++i) expected.data[i] = 0.5f * (all.data[i] + bulb.data[i]);
    expectLinear(groupHalf, expected, "bulb + spots / 2");
}

TEST_F(ViewWindow, CtrlCStopsTheWorkerCleanly) {
    // SIGINT after 4 s (timeout -s INT); a hang would be killed after 30 more.
    const auto start = std::chrono::steady_clock::now();
    const CommandResult r = runCommand("timeout --preserve-status -s INT -k 30 4 " +
                                       meshlightCommand("view cornell --width 320 --height 240"));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(r.status, 130) << r.output;
    EXPECT_NE(r.output.find("interrupted; stopping the worker"), std::string::npos) << r.output;
    EXPECT_LT(seconds, 20.0) << r.output;
}

TEST_F(ViewWindow, ScriptLineThatFailsWhilePlayingIsNamed) {
    // Parses (the up vector is not given), but the up inherited from the box's
    // camera is parallel to this keyframe's view straight down.
    const std::string s = write("down.txt", "wait 0.1\ncamera t=0.2 pos=278,900,280 target=278,0,280\nquit\n");
    const CommandResult r = runMeshlight("view cornell --width 160 --height 120 --script " + s);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find(s + ":2: camera up vector is parallel to the view direction"), std::string::npos)
        << r.output;
}

TEST_F(ViewWindow, SavesTheCacheAndResumesFromIt) {
    const std::string cache = path("view.cache");
    const std::string s = write("save.txt", concat("wait-samples 1500\nsave-cache ", cache, "\nquit\n"));
    CommandResult v = runMeshlight("view cornell --width 160 --height 120 --direct-only --script " + s);
    ASSERT_EQ(v.status, 0) << v.output;
    ASSERT_TRUE(fs::exists(cache)) << v.output;
    // render resumes from it: the same scene and settings.
    CommandResult r = runMeshlight("render cornell --width 32 --height 32 --direct-only --samples 1 --cache " + cache +
                                   " --out " + path("r.png"));
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("cache: resumed from"), std::string::npos) << r.output;
}
