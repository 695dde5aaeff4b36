// The viewer's parts that need no window: walking (WalkCamera), the script
// language and its player (ViewScript), light weights and display modes
// (DisplayState), illuminance and false colour (Illuminance), and the
// compositor's interactive passes on OSMesa (weights, modes, GPU display
// against the CPU tone mapper, snapshot upload in slices).
//
// Tolerances (each use says which):
//  [exact]   the same float operations in the same order: bit for bit.
//  [linear]  sums of per-light images against one image of all lights: the
//            compositor adds meshes in float (6e-8 relative per addition)
//            and interpolates each triangle as a plane whose rounding is
//            relative to the largest value it interpolates (test_stability's
//            [float]): 1e-5 of the pixel plus 1e-6 of the image's largest.
//  [8-bit]   the GPU display against toneMap() on the CPU: float against
//            double arithmetic before rounding to 8 bits: one level.
#include "cache/IrradianceCache.h"
#include "TestSamplers.h"
#include "core/Error.h"
#include "core/loaders/ObjLoader.h"
#include "core/scenes/CornellBox.h"
#include "core/scenes/ScalingScene.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/gl/GlObjects.h"
#include "viewer/compositor/Compositor.h"
#include "viewer/compositor/GpuCacheMeshes.h"
#include "core/image/FalseColour.h"
#include "core/image/Illuminance.h"
#include "core/image/Photometry.h"
#include "core/image/ToneMap.h"
#include "viewer/window/DisplayState.h"
#include "viewer/window/ViewLights.h"
#include "viewer/window/ViewScript.h"
#include "viewer/window/WalkCamera.h"

#include "GlTestContext.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>

using namespace ml;

namespace {

Camera cornellCamera() { return *makeCornellBox().camera; }

::testing::AssertionResult near(const Vec3& a, const Vec3& b, double tol) {
    if (glm::length(a - b) <= tol) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << "(" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x << ", " << b.y
                                         << ", " << b.z << "), tolerance " << tol;
}

Vec3 direction(const Camera& c) { return glm::normalize(c.target - c.position); }

}  // namespace

// --- WalkCamera ----------------------------------------------------------------

TEST(WalkCamera, StartsAndResetsToTheStartCameraBitForBit) {
    Camera start = cornellCamera();
    start.up = Vec3(0.1, 1, 0);  // not perpendicular to the view: kept as given
    WalkCamera walk(start, 100);
    auto same = [&](const Camera& c) {
        return std::memcmp(&c.position, &start.position, sizeof(Vec3)) == 0 &&
               std::memcmp(&c.target, &start.target, sizeof(Vec3)) == 0 &&
               std::memcmp(&c.up, &start.up, sizeof(Vec3)) == 0 && c.fovYDegrees == start.fovYDegrees;
    };
    EXPECT_TRUE(same(walk.camera()));
    WalkInput in;
    in.forward = 1;
    in.lookRight = 30;
    EXPECT_TRUE(walk.update(in, 0.5, 0.01));
    EXPECT_FALSE(same(walk.camera()));
    walk.reset();
    EXPECT_TRUE(same(walk.camera()));
    // No input changes nothing.
    EXPECT_FALSE(walk.update(WalkInput{}, 1.0, 0.01));
    EXPECT_TRUE(same(walk.camera()));
}

TEST(WalkCamera, WalksHorizontallyAtItsSpeedWhateverThePitch) {
    // Looking 30° down the -z axis; walking forward stays at the same height.
    Camera c;
    c.position = Vec3(0, 2, 0);
    c.target = Vec3(0, 2 - std::tan(glm::radians(30.0)), -1);
    c.up = Vec3(0, 1, 0);
    WalkCamera walk(c, 3.0);
    EXPECT_NEAR(walk.pitch(), -glm::radians(30.0), 1e-12);
    WalkInput in;
    in.forward = 1;
    walk.update(in, 2.0, 0.0);  // 2 s at 3 units/s
    EXPECT_TRUE(near(walk.camera().position, Vec3(0, 2, -6), 1e-12));
    // The view direction is unchanged by walking.
    EXPECT_TRUE(near(direction(walk.camera()), direction(c), 1e-12));
    // Right is +x when looking down -z with y up; up is the world's vertical.
    in = WalkInput{};
    in.right = 1;
    in.up = 1;  // diagonal: normalised, so no faster than straight
    walk.update(in, 1.0, 0.0);
    EXPECT_TRUE(near(walk.camera().position, Vec3(3 / std::sqrt(2.0), 2 + 3 / std::sqrt(2.0), -6), 1e-12));
    // Shift walks four times as fast.
    in = WalkInput{};
    in.forward = -1;
    in.speedFactor = 4;
    const Vec3 before = walk.camera().position;
    walk.update(in, 0.5, 0.0);
    EXPECT_TRUE(near(walk.camera().position, before + Vec3(0, 0, 6), 1e-12));
}

TEST(WalkCamera, MouseTurnsAboutTheVerticalAndNeverTurnsOver) {
    Camera c;
    c.position = Vec3(1, 1, 1);
    c.target = Vec3(1, 1, 0);  // looking down -z
    c.up = Vec3(0, 1, 0);
    WalkCamera walk(c, 1.0);
    WalkInput in;
    in.lookRight = 90;  // 90 px at 1°/px: a quarter turn to the right, towards +x
    walk.update(in, 0.016, glm::radians(1.0));
    EXPECT_TRUE(near(direction(walk.camera()), Vec3(1, 0, 0), 1e-12));
    EXPECT_TRUE(near(walk.camera().position, c.position, 0));
    // Looking up by 45° keeps the heading.
    in = WalkInput{};
    in.lookDown = -45;
    walk.update(in, 0.016, glm::radians(1.0));
    EXPECT_TRUE(near(direction(walk.camera()), glm::normalize(Vec3(1, 1, 0)), 1e-12));
    // Far past straight up: clamped just short of it, and still a valid camera.
    in.lookDown = -1000;
    walk.update(in, 0.016, glm::radians(1.0));
    EXPECT_NEAR(walk.pitch(), kPi / 2 - WalkCamera::kPitchMargin, 1e-12);
    EXPECT_NO_THROW(walk.camera().validate());
    in.lookDown = 5000;
    walk.update(in, 0.016, glm::radians(1.0));
    EXPECT_NEAR(walk.pitch(), -(kPi / 2 - WalkCamera::kPitchMargin), 1e-12);
    EXPECT_NO_THROW(walk.camera().validate());
    // The distance to the target (the focus) and the field of view are kept.
    EXPECT_NEAR(glm::length(walk.camera().target - walk.camera().position), 1.0, 1e-12);
    EXPECT_EQ(walk.camera().fovYDegrees, c.fovYDegrees);
}

TEST(WalkCamera, SetJumpsExactlyAndWalkingGoesOnFromThere) {
    WalkCamera walk(cornellCamera(), 50);
    Camera k;
    k.position = Vec3(100, 200, -300);
    k.target = Vec3(300, 100, 200);
    k.up = Vec3(0, 1, 0);
    k.fovYDegrees = 55;
    walk.set(k);
    EXPECT_EQ(walk.camera().position, k.position);
    EXPECT_EQ(walk.camera().target, k.target);
    WalkInput in;
    in.forward = 1;
    walk.update(in, 1.0, 0);
    const Vec3 heading = glm::normalize(Vec3(200, 0, 500));
    EXPECT_TRUE(near(walk.camera().position, k.position + 50.0 * heading, 1e-9));
    EXPECT_EQ(walk.camera().fovYDegrees, 55);
    walk.reset();  // back to the start camera, not to the keyframe
    EXPECT_EQ(walk.camera().position, cornellCamera().position);
}

// --- ViewScript ------------------------------------------------------------------

TEST(ViewScript, ParsesEveryAction) {
    const ViewScript s = parseViewScript(
        "# a comment\n"
        "camera t=0 pos=1,2,3 target=4,5,6   # trailing comment\n"
        "camera t=2.5 pos=1,2,4 target=4,5,7 up=0,0,1 fov=50\n"
        "\n"
        "wait 0.5\nwait-samples 1000\nwait-error 0.02\nwait-done\n"
        "mode lux\nmode light lampB\nmode wireframe\n"
        "wireframe off\ncontours on\nui off\n"
        "light 0 off\nlight 1 intensity 0.25\nlight lampA color 1,0.5,0\n"
        "exposure -1.5\nexposure auto\ntonemap reinhard\nlux-range 10 500\nlux-range auto\n"
        "pause\nresume\nscreenshot out.exr\nsave-cache c.bin\nquit\n",
        "s.txt");
    using K = ScriptAction::Kind;
    const std::vector<K> kinds = {K::Camera, K::Camera, K::Wait, K::WaitSamples, K::WaitError, K::WaitDone,
                                  K::Mode, K::Mode, K::Mode, K::Wireframe, K::Contours, K::Ui, K::Light, K::Light,
                                  K::Light, K::Exposure, K::ExposureAuto, K::Tonemap, K::LuxRange, K::LuxRangeAuto,
                                  K::Pause, K::Resume, K::Screenshot, K::SaveCache, K::Quit};
    ASSERT_EQ(s.actions.size(), kinds.size());
    for (size_t i = 0; i < kinds.size(); ++i) EXPECT_EQ(int(s.actions[i].kind), int(kinds[i])) << "action " << i;
    EXPECT_EQ(s.actions[0].where.line, 2);
    EXPECT_EQ(s.actions[1].where.line, 3);
    EXPECT_EQ(s.actions[1].time, 2.5);
    EXPECT_EQ(s.actions[1].position, Vec3(1, 2, 4));
    EXPECT_EQ(*s.actions[1].up, Vec3(0, 0, 1));
    EXPECT_EQ(*s.actions[1].fov, 50);
    EXPECT_FALSE(s.actions[0].up.has_value());
    EXPECT_EQ(s.actions[3].samples, 1000u);
    EXPECT_EQ(s.actions[6].mode, DisplayMode::Illuminance);
    EXPECT_EQ(s.actions[7].mode, DisplayMode::Light);
    EXPECT_EQ(s.actions[7].lightName, "lampB");
    EXPECT_TRUE(s.actions[8].flag);  // mode wireframe: final with the overlay
    EXPECT_EQ(s.actions[13].change, ScriptAction::LightChange::Intensity);
    EXPECT_EQ(s.actions[13].number, 0.25);
    EXPECT_EQ(s.actions[14].colour, Rgb(1, 0.5, 0));
    EXPECT_EQ(s.actions[15].number, -1.5);
    EXPECT_EQ(s.actions[17].op, ToneOperator::Reinhard);
    EXPECT_EQ(s.actions[18].number2, 500);
    EXPECT_EQ(s.actions[22].path, "out.exr");
}

TEST(ViewScript, ErrorsNameTheFileAndLine) {
    struct Case {
        std::string text, message;
    };
    const std::vector<Case> cases = {
        {"wait 1\njump 3\n", "bad.txt:2: unknown action 'jump'"},
        {"wait soon\n", "bad.txt:1: wait 'soon' is not a finite number"},
        {"wait 1 2\n", "bad.txt:1: 'wait' takes SECONDS, got 2 arguments"},
        {"wait -1\n", "bad.txt:1: wait -1 is negative"},
        {"wait nan\n", "bad.txt:1: wait 'nan' is not a finite number"},
        {"\n\ncamera t=1 pos=1,2,3\n", "bad.txt:3: camera needs t=SECONDS (or in=SECONDS), pos=X,Y,Z and target=X,Y,Z"},
        {"camera t=1 in=2 pos=1,2,3 target=0,0,0\n", "bad.txt:1: camera needs t=SECONDS (or in=SECONDS)"},
        {"camera t=0 pos=1,2 target=0,0,0\n", "bad.txt:1: camera pos '1,2' is not three numbers X,Y,Z"},
        {"camera t=0 pos=1,2,3 target=0,0,0 zoom=2\n", "bad.txt:1: camera: unknown key 'zoom'"},
        {"camera t=0 pos=1,2,3 target=1,2,3\n", "bad.txt:1: camera position and target coincide"},
        {"camera t=0 pos=0,0,1 target=0,0,0 fov=180\n", "bad.txt:1: camera field of view 180"},
        {"camera t=2 pos=0,0,1 target=0,0,0\nwait 1\ncamera t=1 pos=0,0,2 target=0,0,0\n",
         "bad.txt:3: camera t=1 comes before the keyframe at line 1 (t=2)"},
        {"mode sepia\n", "bad.txt:1: unknown mode 'sepia'"},
        {"mode light\n", "bad.txt:1: 'mode light' needs the light"},
        {"wireframe maybe\n", "bad.txt:1: 'wireframe' takes on or off, not 'maybe'"},
        {"light 0 dim\n", "bad.txt:1: unknown light change 'dim'"},
        {"light 0 color 1,-1,0\n", "bad.txt:1: light color 1,-1,0 has a negative component"},
        {"light 0 intensity\n", "bad.txt:1: 'light 0 intensity' takes one number"},
        {"tonemap filmic\n", "bad.txt:1: unknown tone operator 'filmic'"},
        {"lux-range 100 10\n", "bad.txt:1: lux-range 100 10: needs 0 < MIN < MAX"},
        {"wait-samples 2.5\n", "bad.txt:1: wait-samples 2.5 is not a whole number"},
        {"wait-error 0\n", "bad.txt:1: wait-error 0 is not within (0, 1]"},
        {"screenshot shot.jpg\n", "bad.txt:1: screenshot: shot.jpg: unsupported output format '.jpg'"},
        {"quit now\n", "bad.txt:1: 'quit' takes no argument, got 1 argument"},
    };
    for (const Case& c : cases) {
        try {
            parseViewScript(c.text, "bad.txt");
            ADD_FAILURE() << "no error for: " << c.text;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos)
                << "got: " << e.what() << "\nexpected: " << c.message;
        }
    }
}

TEST(ViewScript, LightsResolveByIndexOrNameAgainstTheScene) {
    ViewScript s = parseViewScript("light lampB off\nmode light 0\n", "s.txt");
    resolveViewScript(s, {"lampA", "lampB"});
    EXPECT_EQ(s.actions[0].light, 1u);
    EXPECT_EQ(s.actions[1].light, 0u);
    for (const char* bad : {"light 2 off\n", "light lampC off\n", "mode light -1\n"}) {
        ViewScript b = parseViewScript(std::string("wait 0\n") + bad, "s.txt");
        try {
            resolveViewScript(b, {"lampA", "lampB"});
            ADD_FAILURE() << "no error for " << bad;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("s.txt:2: no light '"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("1 'lampB'"), std::string::npos) << e.what();
        }
    }
    ViewScript shot = parseViewScript("screenshot /nonexistent-folder/x.png\n", "s.txt");
    EXPECT_THROW(resolveViewScript(shot, {}), InputError);
}

namespace {

// A viewer stand-in recording what the player asks.
class FakeHost : public ScriptHost {
public:
    Camera cam = cornellCamera();
    DisplayState state;
    std::vector<LightControl> controls = std::vector<LightControl>(2);
    uint64_t samples = 0;
    double error = 1;
    bool done = false, quitAsked = false, saving = false;
    int lightChanges = 0, meters = 0;
    std::vector<std::string> shots, saves;

    Camera camera() const override { return cam; }
    void setCamera(const Camera& c) override { cam = c; }
    DisplayState& display() override { return state; }
    std::vector<LightControl>& lights() override { return controls; }
    void lightsChanged() override { ++lightChanges; }
    void meterExposure() override { ++meters; }
    void meterLuxRange() override { ++meters; }
    void setPaused(bool) override {}
    uint64_t shownSamples() const override { return samples; }
    double shownError() const override { return error; }
    bool refinementDone() const override { return done; }
    void screenshot(const std::string& p) override { shots.push_back(p); }
    void saveCache(const std::string& p) override {
        saves.push_back(p);
        saving = true;
    }
    bool busySaving() const override { return saving; }
    void quit() override { quitAsked = true; }
};

}  // namespace

TEST(ViewScript, PlayerInterpolatesKeyframesAndWaits) {
    ViewScript script = parseViewScript("camera t=0 pos=0,0,10 target=0,0,0 up=0,1,0 fov=40\n"
                                        "camera t=2 pos=4,0,10 target=4,0,0 fov=60\n"
                                        "wait-samples 500\n"
                                        "light 1 intensity 0.5\n"
                                        "screenshot a.png\n"
                                        "mode direct\n"
                                        "save-cache c\n"
                                        "wait 1\n"
                                        "quit\n",
                                        "p.txt");
    resolveViewScript(script, {"lampA", "lampB"});
    ScriptPlayer player(script);
    FakeHost host;
    player.advance(0.0, host);  // the first keyframe at once, then moving to the second
    EXPECT_EQ(host.cam.position, Vec3(0, 0, 10));
    player.advance(1.0, host);  // halfway
    EXPECT_TRUE(near(host.cam.position, Vec3(2, 0, 10), 1e-12));
    EXPECT_TRUE(near(host.cam.target, Vec3(2, 0, 0), 1e-12));
    EXPECT_NEAR(host.cam.fovYDegrees, 50, 1e-12);
    player.advance(2.5, host);  // arrived exactly; now waiting for samples
    EXPECT_EQ(host.cam.position, Vec3(4, 0, 10));
    EXPECT_EQ(host.cam.fovYDegrees, 60);
    EXPECT_EQ(player.where(), "p.txt:3");
    host.samples = 499;
    player.advance(3.0, host);
    EXPECT_EQ(host.lightChanges, 0);
    host.samples = 500;
    player.advance(3.1, host);  // light change, then the screenshot ends the frame
    EXPECT_EQ(host.lightChanges, 1);
    EXPECT_EQ(host.controls[1].intensity, 0.5);
    EXPECT_EQ(host.shots, std::vector<std::string>{"a.png"});
    EXPECT_EQ(host.state.mode, DisplayMode::Final);  // not yet: next frame
    player.advance(3.2, host);
    EXPECT_EQ(host.state.mode, DisplayMode::Direct);
    EXPECT_EQ(host.saves, std::vector<std::string>{"c"});
    player.advance(9.0, host);  // still saving
    EXPECT_EQ(player.where(), "p.txt:7");
    host.saving = false;
    player.advance(9.1, host);  // saved; `wait 1` starts at 9.1
    player.advance(10.0, host);
    EXPECT_FALSE(host.quitAsked);
    player.advance(10.2, host);
    EXPECT_TRUE(host.quitAsked);
    EXPECT_TRUE(player.finished());
}

TEST(ViewScript, RelativeKeyframesCountFromTheirLine) {
    ScriptPlayer player(parseViewScript("wait-done\ncamera in=2 pos=0,0,10 target=0,0,0 up=0,1,0\nquit\n", "r.txt"));
    FakeHost host;
    host.cam.position = Vec3(0, 0, 20);
    host.cam.target = Vec3(0, 0, 0);
    player.advance(0, host);
    player.advance(5, host);  // waited 5 s (longer than any t= could have known)
    host.done = true;
    player.advance(7, host);  // the keyframe starts at 7, arrives at 9
    player.advance(8, host);
    EXPECT_TRUE(near(host.cam.position, Vec3(0, 0, 15), 1e-12));
    player.advance(9, host);
    EXPECT_EQ(host.cam.position, Vec3(0, 0, 10));
    player.advance(9.1, host);
    EXPECT_TRUE(host.quitAsked);
}

TEST(ViewScript, WaitsEndWhenRefinementEnds) {
    ScriptPlayer player(parseViewScript("wait-samples 1000000\nwait-error 0.0001\nwait-done\nquit\n", "w.txt"));
    FakeHost host;
    player.advance(0, host);
    EXPECT_FALSE(player.finished());
    host.done = true;
    player.advance(1, host);
    EXPECT_TRUE(host.quitAsked);
}

// --- Light weights and modes -------------------------------------------------

TEST(DisplayState, IndirectWeightIsThePowerWeightedMeanOfTheLights) {
    std::vector<LightControl> lights(2);
    const std::vector<Rgb> powers = {Rgb(3, 1, 0), Rgb(1, 1, 2)};
    EXPECT_EQ(indirectWeight(lights, powers), Rgb(1.0));
    // All alike: exact.
    for (LightControl& l : lights) l.intensity = 0.5;
    EXPECT_EQ(indirectWeight(lights, powers), Rgb(0.5));
    lights[0].intensity = 1;
    lights[1].on = false;
    // Per channel: (3·1 + 1·0) / 4, (1 + 0) / 2, (0 + 0) / 2.
    EXPECT_EQ(indirectWeight(lights, powers), Rgb(0.75, 0.5, 0.0));
    // A channel with no power anywhere keeps weight 1.
    EXPECT_EQ(indirectWeight(lights, {Rgb(1, 0, 0), Rgb(1, 0, 0)}), Rgb(0.5, 1.0, 1.0));
}

TEST(DisplayState, ModesChooseWeightsAndQuantities) {
    std::vector<LightControl> lights(2);
    lights[0].intensity = 2;
    lights[1].colour = Rgb(1, 0, 0);
    const std::vector<Rgb> powers = {Rgb(1.0), Rgb(1.0)};
    DisplayState d;
    LightWeights w = compositeWeights(d, lights, powers);
    EXPECT_EQ(w.light[0], Rgb(2.0));
    EXPECT_EQ(w.light[1], Rgb(1, 0, 0));
    EXPECT_EQ(w.indirect, Rgb(1.5, 1.0, 1.0));
    d.mode = DisplayMode::Direct;
    EXPECT_EQ(compositeWeights(d, lights, powers).indirect, Rgb(0.0));
    d.mode = DisplayMode::Indirect;
    w = compositeWeights(d, lights, powers);
    EXPECT_EQ(w.light[0], Rgb(0.0));
    EXPECT_EQ(w.light[1], Rgb(0.0));
    EXPECT_EQ(w.indirect, Rgb(1.5, 1.0, 1.0));
    d.mode = DisplayMode::Light;
    d.light = 1;
    w = compositeWeights(d, lights, powers);
    EXPECT_EQ(w.light[0], Rgb(0.0));
    EXPECT_EQ(w.light[1], Rgb(1, 0, 0));
    EXPECT_EQ(w.indirect, Rgb(0.0));
    EXPECT_EQ(compositeQuantity(DisplayMode::Illuminance), CompositeQuantity::Illuminance);
    EXPECT_EQ(compositeQuantity(DisplayMode::Reflectance), CompositeQuantity::Reflectance);
    EXPECT_EQ(compositeQuantity(DisplayMode::Light), CompositeQuantity::Radiance);
}

// --- Light groups and punctual lights -------------------------------------------

namespace {

// A white isotropic point light of `candela` at p, in `group`.
Light pointLight(const std::string& name, const std::string& group, const Vec3& p, double candela) {
    Light l;
    l.name = name;
    l.group = group;
    l.kind = LightKind::Point;
    l.emission.position = p;
    l.emission.intensity = Rgb(candela / kRadianceEfficacy);
    return l;
}

// A 10 × 10 floor of the given unit, the lights given (finalized).
Scene floorWith(std::vector<Light> lights, double metresPerUnit = 1) {
    Scene scene;
    scene.name = "floor";
    scene.materials = {Material::diffuse("grey", Rgb(0.5))};
    scene.meshes = {test::quadMesh("floor", 0, Vec3(-5, 0, -5), 10.0 * test::kZ, 10.0 * test::kX)};
    scene.metresPerUnit = metresPerUnit;
    scene.lights = std::move(lights);
    scene.finalize();
    return scene;
}

}  // namespace

TEST(ViewLights, PointLightOfICandelaGivesFourPiILumens) {
    // Φ = ∫ I dω = 4π I for an isotropic point, whatever the lengths are in:
    // the scene in metres or millimetres, and --units saying either.
    const double candela = 1000;
    for (double metresPerUnit : {1.0, 0.001}) {
        const Scene scene = floorWith({pointLight("bulb", "", Vec3(0, 2 / metresPerUnit, 0), candela)}, metresPerUnit);
        ASSERT_EQ(scene.lights.size(), 1u);
        for (double unit : {1.0, 0.001}) {
            const ViewLight v = viewLight(scene.lights[0], scene, unit, Photometry());
            EXPECT_NEAR(v.lumens, 4 * kPi * candela, 1e-9 * candela) << metresPerUnit << " m per unit, --units " << unit;
            EXPECT_EQ(v.kind, "point");
            EXPECT_NE(v.details.find("peak 1000 cd"), std::string::npos) << v.details;
        }
    }
    // An area light's flux is π Ke A, A in the viewer's unit.
    Scene lit = test::sceneOf("lit", {Material::diffuse("lamp", Rgb(0.0), Rgb(2.0)), Material::diffuse("grey", Rgb(0.5))},
                              {test::unitLight(), test::floorMesh()});
    const ViewLight area = viewLight(lit.lights[0], lit, 0.1, Photometry());
    EXPECT_EQ(area.kind, "area");
    EXPECT_NEAR(area.lumens, kRadianceEfficacy * kPi * 2.0 * 0.01, 1e-12);
}

TEST(ViewLights, GroupsFollowTheLightsGroupOrTheirName) {
    const Scene scene = floorWith({pointLight("Spot.001", "Spot", Vec3(1, 2, 0), 100),
                                   pointLight("Bulb", "", Vec3(0, 2, 0), 100),
                                   pointLight("Spot.002", "Spot", Vec3(-1, 2, 0), 100)});
    const std::vector<LightGroup> groups = lightGroups(scene.lights);
    ASSERT_EQ(groups.size(), 2u);
    EXPECT_EQ(groups[0].name, "Spot");
    EXPECT_EQ(groups[0].lights, (std::vector<size_t>{0, 2}));
    EXPECT_EQ(groups[1].name, "Bulb");
    EXPECT_EQ(groups[1].lights, (std::vector<size_t>{1}));
    EXPECT_EQ(describeGroups(groups), "'Spot' (2 lights), 'Bulb'");
}

TEST(ViewLights, DimmingAGroupIsDimmingEachOfItsLights) {
    const Scene scene = floorWith({pointLight("Spot.001", "Spot", Vec3(1, 2, 0), 100),
                                   pointLight("Spot.002", "Spot", Vec3(-1, 2, 0), 300),
                                   pointLight("Bulb", "", Vec3(0, 2, 0), 50)});
    const std::vector<LightGroup> groups = lightGroups(scene.lights);
    std::vector<Rgb> powers;
    for (const Light& l : scene.lights) powers.push_back(viewLight(l, scene, 1, Photometry()).powerW);
    // Punctual lights weigh in the indirect light's mean by their power.
    EXPECT_GT(powers[0].r, 0);
    for (DisplayMode mode : {DisplayMode::Final, DisplayMode::Direct, DisplayMode::Indirect}) {
        SCOPED_TRACE(displayModeName(mode));
        DisplayState d;
        d.mode = mode;
        std::vector<LightControl> byGroup(3), each(3);
        dimGroup(byGroup, groups[0], 0.5);
        each[0].intensity = 0.5;
        each[1].intensity = 0.5;
        LightWeights g = compositeWeights(d, byGroup, powers), e = compositeWeights(d, each, powers);
        EXPECT_EQ(g.light, e.light);
        EXPECT_EQ(g.indirect, e.indirect);
        EXPECT_EQ(g.shared, e.shared);
        // Off likewise; the bulb is untouched.
        switchGroup(byGroup, groups[0], false);
        EXPECT_FALSE(groupOn(byGroup, groups[0]));
        each[0].on = each[1].on = false;
        g = compositeWeights(d, byGroup, powers);
        e = compositeWeights(d, each, powers);
        EXPECT_EQ(g.light, e.light);
        EXPECT_EQ(g.indirect, e.indirect);
        if (mode != DisplayMode::Indirect) {
            EXPECT_EQ(g.light[2], Rgb(1.0));
        }
        // Off and on again keeps the dimmer.
        switchGroup(byGroup, groups[0], true);
        EXPECT_EQ(byGroup[1].weight(), Rgb(0.5));
    }
    // All off: no indirect light is left (the punctual lights' powers count).
    std::vector<LightControl> off(3);
    for (const LightGroup& group : groups) switchGroup(off, group, false);
    EXPECT_EQ(indirectWeight(off, powers), Rgb(0.0));
}

TEST(ViewScript, GroupsParseResolveAndSwitchTheirLights) {
    ViewScript s = parseViewScript("group Spot off\n"
                                   "group Spot dim 0.5   # comment\n"
                                   "group \"Ceiling Light\" on\n"
                                   "light Panel#2 off\n",
                                   "g.txt");
    ASSERT_EQ(s.actions.size(), 4u);
    EXPECT_EQ(s.actions[0].kind, ScriptAction::Kind::Group);
    EXPECT_EQ(s.actions[0].change, ScriptAction::LightChange::Off);
    EXPECT_EQ(s.actions[1].change, ScriptAction::LightChange::Intensity);
    EXPECT_EQ(s.actions[1].number, 0.5);
    EXPECT_EQ(s.actions[2].lightName, "Ceiling Light");
    EXPECT_EQ(s.actions[3].lightName, "Panel#2");  // '#' inside a word is no comment
    const std::vector<LightGroup> groups = {{"Spot", {0, 2}}, {"Ceiling Light", {1}}, {"Panel#2", {3}}};
    resolveViewScript(s, {"Spot.001", "Ceiling Light", "Spot.002", "Panel#2"}, groups);
    EXPECT_EQ(s.actions[0].group.lights, (std::vector<size_t>{0, 2}));
    EXPECT_EQ(s.actions[3].light, 3u);

    FakeHost host;
    host.controls.resize(4);
    ScriptPlayer player(s);
    player.advance(0, host);
    EXPECT_TRUE(player.finished());
    EXPECT_FALSE(host.controls[0].on);  // off, then dimmed: dimming leaves the switch off
    EXPECT_EQ(host.controls[0].weight(), Rgb(0.0));
    EXPECT_FALSE(host.controls[2].on);
    EXPECT_EQ(host.controls[2].intensity, 0.5);
    EXPECT_EQ(host.controls[1].intensity, 1.0);
    EXPECT_FALSE(host.controls[3].on);
    EXPECT_EQ(host.lightChanges, 4);

    // Errors name the line; an unknown group lists the scene's.
    const std::vector<std::pair<std::string, std::string>> bad = {
        {"wait 0\ngroup Spot\n", "g.txt:2: 'group' takes the group's name and on, off or dim F"},
        {"group Spot dim\n", "g.txt:1: 'group Spot dim' takes one number"},
        {"group Spot dim -1\n", "g.txt:1: group dim -1 is not within 0..1e6"},
        {"group Spot dim half\n", "g.txt:1: group dim 'half' is not a finite number"},
        {"group Spot toggle\n", "g.txt:1: unknown group change 'toggle' (use on, off or dim F)"},
        {"group Spot on now\n", "g.txt:1: 'group Spot on' takes no further argument"},
        {"group \"Ceiling Light on\n", "g.txt:1: a quoted name has no closing"},
    };
    for (const auto& [text, message] : bad) {
        try {
            parseViewScript(text, "g.txt");
            ADD_FAILURE() << "no error for: " << text;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what() << "\nexpected: " << message;
        }
    }
    ViewScript unknown = parseViewScript("wait 0\ngroup Panel off\n", "g.txt");
    try {
        resolveViewScript(unknown, {"Spot.001", "Bulb", "Spot.002"}, {{"Spot", {0, 2}}, {"Bulb", {1}}});
        ADD_FAILURE() << "no error for an unknown group";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("g.txt:2: no light group 'Panel' in the scene (groups: 'Spot' (2 "
                                             "lights), 'Bulb')"),
                  std::string::npos)
            << e.what();
    }
}

// --- Illuminance -------------------------------------------------------------

TEST(Illuminance, LuxLevelsAndFalseColour) {
    for (int i = -9; i <= 12; ++i) {
        EXPECT_NEAR(luxLevelIndex(luxAtLevel(i)), double(i), 1e-9) << i;
        EXPECT_LT(luxLevelIndex(luxAtLevel(i) * 0.999), double(i)) << i;
    }
    EXPECT_EQ(luxAtLevel(0), 1);
    EXPECT_EQ(luxAtLevel(4), 20);
    EXPECT_EQ(luxAtLevel(-1), 0.5);
    EXPECT_NEAR(luxLevelIndex(3.5), 1.5, 1e-12);  // halfway from 2 to 5
    EXPECT_EQ(luxLevelIndex(0), -kInf);
    EXPECT_EQ(luxLevels(1.5, 60), (std::vector<double>{2, 5, 10, 20, 50}));
    EXPECT_EQ(falseColour(0), falseColourPalette().front());
    EXPECT_EQ(falseColour(1), falseColourPalette().back());
    EXPECT_EQ(falseColour(-3), falseColourPalette().front());
    EXPECT_NEAR(falseColourPosition(10, 1, 100), 0.5, 1e-12);
    EXPECT_EQ(formatLux(20000), "20k");
    // The 2nd and 98th percentiles of what is lit (the 300 lx outlier is
    // left out), widened to 1-2-5 values and a decade: 20 .. 200.
    const auto [lo, hi] = autoLuxRange({0, 0, 30, 40, 50, 60, 70, 300});
    EXPECT_EQ(lo, 20);
    EXPECT_EQ(hi, 200);
    EXPECT_GE(luxLevelIndex(hi) - luxLevelIndex(lo), 3 - 1e-9);  // a decade at least
    EXPECT_NEAR(luxLevelIndex(lo), std::round(luxLevelIndex(lo)), 1e-9);
    EXPECT_EQ(autoLuxRange({}), std::make_pair(1.0, 1000.0));
    EXPECT_EQ(parseLengthUnit("mm"), LengthUnit::Millimetre);
    EXPECT_THROW(parseLengthUnit("inch"), InputError);
    EXPECT_EQ(metresPerUnit(LengthUnit::Centimetre), 0.01);
}

// --- The compositor's interactive passes --------------------------------------

namespace {

// The Cornell box with two ceiling lights, its cache filled with a smooth
// made-up irradiance per light (the compositor does not care where it came
// from; distinct per light and channel so mix-ups show).
struct TwoLights {
    Scene scene = makeCornellLightGrid(2);
    std::vector<IrradianceMeshCopy> direct;
    TwoLights() {
        CacheSettings cs;
        cs.maxEdgeFraction = 1.0 / 12;
        IrradianceCache cache(scene, cs);
        test::sampleEveryVertex(
            cache,
            [](size_t l, const Vec3& x, const Vec3&, uint32_t) {
                const double s = 1 + 0.5 * std::sin(0.01 * x.x + 0.02 * x.z + double(l));
                return l == 0 ? Rgb(2 * s, 1.5 * s, 0.5 * s) : Rgb(0.3 * s, 0.8 * s, 2.5 * s);
            },
            1, 1);
        direct = cache.copyMeshes();
    }
    Camera camera() const { return scene.cameraOrDefault(1.0); }
};

const TwoLights& twoLights() {
    static const TwoLights t;
    return t;
}

ImageRgb composeImage(Compositor& c, const GpuCacheMeshes& meshes, const LightWeights& w, CompositeQuantity q,
                      int supersample = 2, int size = 48) {
    CompositorSettings s;
    s.width = s.height = size;
    s.supersample = supersample;
    s.quantity = q;
    c.compose(twoLights().camera(), meshes, w, s);
    return c.readImage();
}

LightWeights weights(Rgb a, Rgb b, Rgb indirect = Rgb(1.0)) {
    LightWeights w;
    w.light = {a, b};
    w.indirect = indirect;
    return w;
}

// [linear]: |x − expected| ≤ 1e-5 |expected| + 1e-6 max |expected|.
void expectLinear(const ImageRgb& x, const ImageRgb& expected, const char* what) {
    ASSERT_EQ(x.data.size(), expected.data.size());
    float largest = 0;
    for (float v : expected.data) largest = std::max(largest, std::abs(v));
    ASSERT_GT(largest, 0) << what;
    size_t bad = 0;
    for (size_t i = 0; i < x.data.size(); ++i)
        if (std::abs(x.data[i] - expected.data[i]) > 1e-5 * std::abs(expected.data[i]) + 1e-6 * largest && ++bad <= 3)
            ADD_FAILURE() << what << ": value " << i << " is " << x.data[i] << ", expected " << expected.data[i];
    EXPECT_EQ(bad, 0u) << what;
}

bool identical(const ImageRgb& a, const ImageRgb& b) {
    return a.data.size() == b.data.size() && std::memcmp(a.data.data(), b.data.data(), a.data.size() * 4) == 0;
}

GpuCacheMeshes uploaded(const std::vector<IrradianceMeshCopy>& direct,
                        const std::vector<IrradianceMeshCopy>& indirect = {}) {
    GpuCacheMeshes m(test::glContext().gl(), twoLights().scene.bounds.center());
    m.upload(direct, indirect);
    return m;
}

}  // namespace

TEST(ViewCompositor, UnitWeightsGiveRendersImageBitForBit) {
    const TwoLights& t = twoLights();
    Compositor c(test::glContext(), t.scene);
    CompositorSettings s;
    s.width = s.height = 48;
    s.supersample = 2;
    const ImageRgb rendered = c.render(t.camera(), t.direct, s);
    const GpuCacheMeshes meshes = uploaded(t.direct);
    EXPECT_TRUE(identical(composeImage(c, meshes, LightWeights::unit(2), CompositeQuantity::Radiance), rendered));  // [exact]
}

TEST(ViewCompositor, LightsAddUpAndScaleLinearly) {
    const TwoLights& t = twoLights();
    Compositor c(test::glContext(), t.scene);
    const GpuCacheMeshes meshes = uploaded(t.direct);
    const Rgb one(1.0), off(0.0);
    const ImageRgb all = composeImage(c, meshes, weights(one, one), CompositeQuantity::Radiance);
    const ImageRgb a = composeImage(c, meshes, weights(one, off), CompositeQuantity::Radiance);
    const ImageRgb b = composeImage(c, meshes, weights(off, one), CompositeQuantity::Radiance);
    ImageRgb sum = a;
    for (size_t i = 0; i < sum.data.size(); ++i) sum.data[i] += b.data[i];
    expectLinear(all, sum, "light A alone + light B alone = both");
    // Dimmed and tinted: 2 A + (0.5, 1, 0) B, the emitters' radiance included.
    const Rgb tint(0.5, 1, 0);
    const ImageRgb mixed = composeImage(c, meshes, weights(Rgb(2.0), tint), CompositeQuantity::Radiance);
    ImageRgb expected = a;
    for (size_t i = 0; i < expected.data.size(); ++i)
        expected.data[i] = float(2.0 * a.data[i] + tint[int(i % 3)] * b.data[i]);
    expectLinear(mixed, expected, "2 A + tint B");
    // A light's emitting face shows its Ke (box-filtered: at most Ke, and
    // more than any lit wall), and nothing of it once the light is off.
    size_t brightest = 0;
    for (size_t i = 0; i < a.data.size(); ++i)
        if (a.data[i] > a.data[brightest]) brightest = i;
    EXPECT_LE(a.data[brightest], t.scene.lights[0].radiance[int(brightest % 3)] * (1 + 1e-6));
    EXPECT_GT(a.data[brightest], 8.0);
    EXPECT_LT(b.data[brightest], 0.01 * a.data[brightest]);  // B's light reflected by A's face
}

TEST(ViewCompositor, IndirectMeshesAddToDirectAndShowAlone) {
    const TwoLights& t = twoLights();
    Compositor c(test::glContext(), t.scene);
    // A made-up bounce: light A's mesh at a third of its irradiance.
    IrradianceMeshCopy bounce = t.direct[0];
    for (Rgb& e : bounce.irradiance) e /= 3.0;
    const GpuCacheMeshes directOnly = uploaded(t.direct);
    const GpuCacheMeshes withBounce = uploaded(t.direct, {bounce});
    const Rgb one(1.0), off(0.0), half(0.5);
    const ImageRgb direct = composeImage(c, directOnly, weights(one, one), CompositeQuantity::Radiance);
    const ImageRgb final = composeImage(c, withBounce, weights(one, one, half), CompositeQuantity::Radiance);
    const ImageRgb indirect = composeImage(c, withBounce, weights(off, off, half), CompositeQuantity::Radiance);
    ImageRgb sum = direct;
    for (size_t i = 0; i < sum.data.size(); ++i) sum.data[i] += indirect.data[i];
    expectLinear(final, sum, "direct + indirect");
    // Indirect alone is a sixth of light A's reflected light, without emission.
    const ImageRgb aReflected = composeImage(c, directOnly, weights(one, off), CompositeQuantity::Radiance);
    const ImageRgb kd = composeImage(c, directOnly, weights(one, one), CompositeQuantity::Reflectance);
    size_t checked = 0;
    for (int y = 0; y < kd.height; ++y)
        for (int x = 0; x < kd.width; ++x) {
            const Rgb k = kd.at(x, y), i = indirect.at(x, y), r = aReflected.at(x, y);
            if (k == Rgb(0.0) || r.r > 4) continue;  // background or an emitter
            EXPECT_NEAR(i.g, r.g / 6, 1e-5 * r.g + 1e-7) << x << "," << y;
            ++checked;
        }
    EXPECT_GT(checked, 500u);
}

TEST(ViewCompositor, IlluminanceIsThePhotometryOfTheIrradiance) {
    const TwoLights& t = twoLights();
    Compositor c(test::glContext(), t.scene);
    const GpuCacheMeshes meshes = uploaded(t.direct);
    const LightWeights w = weights(Rgb(1.0), Rgb(0.5));
    // One sample per pixel: each pixel is a single surface point, where
    // E = π L / Kd channel by channel (no emission off the lights).
    const ImageRgb radiance = composeImage(c, meshes, w, CompositeQuantity::Radiance, 1);
    const ImageRgb kd = composeImage(c, meshes, w, CompositeQuantity::Reflectance, 1);
    const ImageRgb lux = composeImage(c, meshes, w, CompositeQuantity::Illuminance, 1);
    size_t checked = 0;
    for (int y = 0; y < lux.height; ++y)
        for (int x = 0; x < lux.width; ++x) {
            const Rgb k = kd.at(x, y);
            if (k.r < 0.05 || k.g < 0.05 || k.b < 0.05) continue;  // background, lights, or a dark channel
            const Rgb e = kPi * radiance.at(x, y) / k;
            EXPECT_NEAR(lux.at(x, y).r, Photometry().luminous(e), 1e-4 * lux.at(x, y).r);
            EXPECT_EQ(lux.at(x, y).r, lux.at(x, y).g);
            ++checked;
        }
    EXPECT_GT(checked, 500u);
    // Reflectance shows the materials' Kd: every value seen is one of them.
    for (int y = 0; y < kd.height; ++y)
        for (int x = 0; x < kd.width; ++x) {
            const Rgb k = kd.at(x, y);
            if (k == Rgb(0.0)) continue;
            bool found = false;
            for (const Material& m : t.scene.materials) found = found || glm::length(Rgb(glm::vec3(m.kd)) - k) < 1e-7;
            EXPECT_TRUE(found) << "Kd (" << k.r << ", " << k.g << ", " << k.b << ") at " << x << "," << y;
        }
}

namespace {

// The display pass drawn into an 8-bit target and read back, row 0 at the top.
std::vector<uint8_t> displayed(Compositor& c, int size, const DisplaySettings& d) {
    const GlApi& gl = test::glContext().gl();
    GlTexture tex = makeTexture2D(gl, GL_RGBA8, size, size);
    GLuint f = 0;
    gl.CreateFramebuffers(1, &f);
    GlFramebuffer fb(gl, f);
    gl.NamedFramebufferTexture(f, GL_COLOR_ATTACHMENT0, tex.id(), 0);
    const GLenum buffer = GL_COLOR_ATTACHMENT0;
    gl.NamedFramebufferDrawBuffers(f, 1, &buffer);
    c.display(f, d);
    std::vector<uint8_t> rgba(size_t(size) * size * 4), rgb;
    gl.NamedFramebufferReadBuffer(f, GL_COLOR_ATTACHMENT0);
    gl.BindFramebuffer(GL_READ_FRAMEBUFFER, f);
    gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
    gl.ReadPixels(0, 0, size, size, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    gl.BindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    checkGl(gl, "reading the display back");
    for (int y = size - 1; y >= 0; --y)
        for (int x = 0; x < size; ++x)
            for (int k = 0; k < 3; ++k) rgb.push_back(rgba[(size_t(y) * size + x) * 4 + k]);
    return rgb;
}

}  // namespace

TEST(ViewCompositor, DisplayToneMapsOnTheGpuAsToneMapDoesOnTheCpu) {
    const TwoLights& t = twoLights();
    Compositor c(test::glContext(), t.scene);
    const GpuCacheMeshes meshes = uploaded(t.direct);
    const int size = 48;
    // One sample per pixel (the forward pass) and 2×2 (the fused pass).
    for (int supersample : {1, 2}) {
        for (ToneOperator op : {ToneOperator::Aces, ToneOperator::Reinhard, ToneOperator::Clamp}) {
            const ImageRgb image = composeImage(c, meshes, weights(Rgb(1.0), Rgb(1.0)), CompositeQuantity::Radiance,
                                                supersample, size);
            DisplaySettings d;
            d.op = op;
            d.exposure = autoExposureScale(image) * 2.0;
            const std::vector<uint8_t> gpu = displayed(c, size, d);
            ToneMapSettings tone;
            tone.autoExposure = false;
            tone.exposureEV = std::log2(d.exposure);
            tone.op = op;
            const std::vector<uint8_t> cpu = toneMap(image, tone);
            ASSERT_EQ(gpu.size(), cpu.size());
            int worst = 0;
            for (size_t i = 0; i < gpu.size(); ++i) worst = std::max(worst, std::abs(int(gpu[i]) - int(cpu[i])));
            EXPECT_LE(worst, 1) << "[8-bit] supersample " << supersample << ", " << toneOperatorName(op);
        }
    }
}

TEST(ViewCompositor, FalseColourFollowsTheLegend) {
    const TwoLights& t = twoLights();
    Compositor c(test::glContext(), t.scene);
    const GpuCacheMeshes meshes = uploaded(t.direct);
    const int size = 48;
    const ImageRgb lux = composeImage(c, meshes, weights(Rgb(1.0), Rgb(1.0)), CompositeQuantity::Illuminance, 1, size);
    DisplaySettings d;
    d.luxMin = 20;
    d.luxMax = 2000;
    d.contours = false;
    const std::vector<uint8_t> gpu = displayed(c, size, d);
    size_t checked = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double v = lux.at(x, y).r;
            if (!(v > 0)) continue;
            const Rgb expected = falseColour(falseColourPosition(v, d.luxMin, d.luxMax));
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(gpu[(size_t(y) * size + x) * 3 + k], expected[k] * 255, 1.5) << x << "," << y;
            ++checked;
        }
    EXPECT_GT(checked, 1000u);
    // With iso-lux lines, some pixels turn darker, and only some.
    d.contours = true;
    const std::vector<uint8_t> lined = displayed(c, size, d);
    size_t darker = 0;
    for (size_t i = 0; i < gpu.size(); ++i) darker += lined[i] + 8 < gpu[i];
    EXPECT_GT(darker, 10u);
    EXPECT_LT(darker, gpu.size() / 3);
}

// `render --quantity lux` to a PNG draws on the CPU what the viewer draws
// on the GPU: the same colours, the same iso-lux lines, the same photometry.
TEST(ViewCompositor, CpuFalseColourIsTheViewersDisplay) {
    const TwoLights& t = twoLights();
    Compositor c(test::glContext(), t.scene);
    const int size = 64;
    CompositorSettings s;
    s.width = s.height = size;
    s.supersample = 2;
    for (const char* name : {"radiance", "rec709"}) {
        s.photometry = photometryNamed(name);
        const LuxImage lux = c.renderIlluminance(t.camera(), t.direct, {}, s);
        // The irradiance of pixels wholly on a surface, against the composite's
        // own lux (a plain box filter of lux × seen).
        const GpuCacheMeshes meshes = uploaded(t.direct);
        const ImageRgb plain = composeImage(c, meshes, LightWeights::unit(2), CompositeQuantity::Illuminance, 2, size);
        c.renderIlluminance(t.camera(), t.direct, {}, s);  // display() shows this composite again
        size_t covered = 0;
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x)
                if (lux.coverage[lux.index(x, y)] == 1.0f) {
                    ++covered;
                    if (std::string(name) == "radiance") {  // composeImage's photometry
                        EXPECT_NEAR(lux.lux[lux.index(x, y)], plain.at(x, y).r, 1e-5 * plain.at(x, y).r);
                    }
                }
        EXPECT_GT(covered, size_t(size * size / 2)) << name;
        for (bool contours : {false, true}) {
            DisplaySettings d;
            d.luxMin = 20;
            d.luxMax = 2000;
            d.contours = contours;
            const std::vector<uint8_t> gpu = displayed(c, size, d);
            const std::vector<uint8_t> cpu = displayBytes(falseColourImage(lux, d.luxMin, d.luxMax, contours));
            ASSERT_EQ(gpu.size(), cpu.size());
            size_t off = 0;
            int worst = 0;
            for (size_t i = 0; i < gpu.size(); ++i) {
                const int diff = std::abs(int(gpu[i]) - int(cpu[i]));
                worst = std::max(worst, diff);
                off += diff > 2;
            }
            // Float on the GPU against double here: a line's edge may round
            // the other way, nothing more.
            if (!contours) {
                EXPECT_LE(worst, 2) << name;
            }
            EXPECT_LE(off, gpu.size() / 100) << name << (contours ? " with iso-lux lines" : "");
        }
    }
}

TEST(FalseColourLegend, TicksAreTheLevelsAndLabelTheDecadesWhenCrowded) {
    // 20 .. 2000 lx: 2, 5 per decade and the decades, seven levels.
    const std::vector<LegendTick> roomy = legendTicks(20, 2000, 300, 13);
    ASSERT_EQ(roomy.size(), 7u);
    EXPECT_EQ(roomy.front().lux, 20);
    EXPECT_NEAR(roomy.front().position, 1.0, 1e-12);  // the low end at the bottom
    EXPECT_NEAR(roomy.back().position, 0.0, 1e-12);
    for (const LegendTick& t : roomy) EXPECT_TRUE(t.labelled);
    const std::vector<LegendTick> crowded = legendTicks(20, 2000, 60, 13);
    std::vector<double> labelled;
    for (const LegendTick& t : crowded)
        if (t.labelled) labelled.push_back(t.lux);
    EXPECT_EQ(labelled, (std::vector<double>{100, 1000}));
    EXPECT_EQ(legendBarHeight(100), 120);
    EXPECT_EQ(legendBarHeight(1000), 360);
    // The legend is drawn in the top-right corner and leaves the rest.
    ImageRgb image(400, 300, Rgb(0.5));
    drawLuxLegend(image, 20, 2000, "20 .. 2k lx");
    EXPECT_EQ(image.at(10, 290), Rgb(0.5f));
    EXPECT_NE(image.at(400 - 10 - 20, 60), Rgb(0.5f));
    ImageRgb tiny(40, 30, Rgb(0.5));
    drawLuxLegend(tiny, 20, 2000, "20 .. 2k lx");
    EXPECT_EQ(tiny.at(20, 15), Rgb(0.5f));
}

TEST(ViewCompositor, WireframeDrawsEdgesOnlyWhereTheMeshIsSeen) {
    const TwoLights& t = twoLights();
    Compositor c(test::glContext(), t.scene);
    const GpuCacheMeshes meshes = uploaded(t.direct);
    const int size = 160;  // cache triangles some 10 pixels across
    composeImage(c, meshes, weights(Rgb(1.0), Rgb(1.0)), CompositeQuantity::Radiance, 1, size);
    const std::vector<uint8_t> plain = displayed(c, size, DisplaySettings{});
    // The overlay is drawn over what is in the target: draw both into one.
    const GlApi& gl = test::glContext().gl();
    GlTexture tex = makeTexture2D(gl, GL_RGBA8, size, size);
    GLuint f = 0;
    gl.CreateFramebuffers(1, &f);
    GlFramebuffer fb(gl, f);
    gl.NamedFramebufferTexture(f, GL_COLOR_ATTACHMENT0, tex.id(), 0);
    const GLenum buffer = GL_COLOR_ATTACHMENT0;
    gl.NamedFramebufferDrawBuffers(f, 1, &buffer);
    c.display(f, DisplaySettings{});
    c.drawWireframe(f, meshes, {Rgb(1, 0, 1)});
    std::vector<uint8_t> rgba(size_t(size) * size * 4);
    gl.NamedFramebufferReadBuffer(f, GL_COLOR_ATTACHMENT0);
    gl.BindFramebuffer(GL_READ_FRAMEBUFFER, f);
    gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
    gl.ReadPixels(0, 0, size, size, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    gl.BindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    size_t changed = 0, magenta = 0, background = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const uint8_t* w = &rgba[(size_t(size - 1 - y) * size + x) * 4];
            const uint8_t* p = &plain[(size_t(y) * size + x) * 3];
            if (w[0] == p[0] && w[1] == p[1] && w[2] == p[2]) continue;
            ++changed;
            magenta += (w[0] > p[0] && w[2] > p[2]) || w[1] < p[1];  // blended towards (1, 0, 1)
            background += p[0] == 0 && p[1] == 0 && p[2] == 0;
        }
    EXPECT_GT(changed, size_t(size));                 // edges drawn
    EXPECT_LT(changed, size_t(size) * size * 3 / 4);  // but not everywhere
    EXPECT_GT(magenta, changed * 9 / 10);
    EXPECT_EQ(background, 0u);  // never over the background: no mesh is seen there
}

TEST(ViewCompositor, AFaceLitFromBehindShowsItsCopyEverywhere) {
    // The occluder faces the floor and the lights shine on its back: the
    // cache keeps a reversed copy for that side, coincident with it. Seen
    // from above, every pixel of it must show the copy's light: a depth tie
    // between the two may never drop it (each mesh is drawn once, and back
    // faces sit a hair behind their depth).
    const Scene scene = loadObj(std::string(MESHLIGHT_TEST_DATA) + "/view_lit_from_behind.obj");
    IrradianceCache cache(scene, CacheSettings{});
    ASSERT_GT(cache.backFaceCount(), 0u);
    test::sampleEveryVertex(cache, [](size_t, const Vec3&, const Vec3&, uint32_t) { return Rgb(1.0); }, 1, 1);
    std::vector<IrradianceMeshCopy> direct = cache.copyMeshes();
    Compositor c(test::glContext(), scene);
    GpuCacheMeshes meshes(test::glContext().gl(), scene.bounds.center());
    meshes.upload(direct, {});
    Camera above;
    above.position = Vec3(0.3, 1.7, 1.8);
    above.target = Vec3(0, 0.5, 0);
    above.up = Vec3(0, 1, 0);
    above.fovYDegrees = 60;
    for (int supersample : {1, 2}) {
        CompositorSettings s;
        s.width = 96;
        s.height = 72;
        s.supersample = supersample;
        s.quantity = CompositeQuantity::Reflectance;
        c.compose(above, meshes, LightWeights::unit(2), s);
        const ImageRgb kd = c.readImage();
        s.quantity = CompositeQuantity::Radiance;
        c.compose(above, meshes, LightWeights::unit(2), s);
        const ImageRgb radiance = c.readImage();
        // Pixels wholly on the occluder (Kd 0.3, 0.2, 0.1: no mix of the
        // other materials and the background makes it): both lights' 1 W/m².
        size_t seen = 0;
        for (int y = 0; y < kd.height; ++y)
            for (int x = 0; x < kd.width; ++x)
                if (glm::length(kd.at(x, y) - Rgb(0.3, 0.2, 0.1)) < 1e-6) {
                    EXPECT_NEAR(radiance.at(x, y).r, 0.3 / kPi * 2, 1e-5) << x << "," << y << ", supersample "
                                                                          << supersample;
                    ++seen;
                }
        EXPECT_GT(seen, 100u);
    }
}

TEST(ViewCompositor, LargeMeshesSortedIntoCellsAndCulledGiveTheSameImage) {
    // A cache of some 90,000 triangles: the uploader sorts it into cells
    // (kCellMinTriangles) and the compositor skips the cells out of view.
    // Neither may change a pixel: no triangle of a skipped cell is in view,
    // and the Cornell box has no coincident surfaces whose order could count.
    const Scene scene = makeCornellBox();
    CacheSettings cs;
    cs.maxEdgeFraction = 1.0 / 90;
    IrradianceCache cache(scene, cs);
    test::sampleEveryVertex(
        cache, [](size_t, const Vec3& x, const Vec3&, uint32_t) { return Rgb(1 + 0.002 * x.x, 1 + 0.001 * x.y, 2.0); },
        1, 1);
    const std::vector<IrradianceMeshCopy> direct = {cache.copyMesh(0)};
    ASSERT_GE(direct[0].triangles.size(), GpuCacheMeshes::kCellMinTriangles);
    CacheMeshUploader uploader(test::glContext().gl(), scene.bounds.center());
    uploader.start(direct, {});
    while (!uploader.step(0.001)) {
    }
    ASSERT_GT(uploader.front().direct(0).cells.size(), 100u);
    size_t inCells = 0;
    for (const GpuCacheMeshes::Cell& c : uploader.front().direct(0).cells) inCells += c.count;
    EXPECT_EQ(inCells, direct[0].triangles.size());
    GpuCacheMeshes whole(test::glContext().gl(), scene.bounds.center());
    whole.upload(direct, {});
    EXPECT_TRUE(whole.direct(0).cells.empty());
    Compositor c(test::glContext(), scene);
    Camera corner;  // inside the box, most of it out of view
    corner.position = Vec3(150, 320, 120);
    corner.target = Vec3(420, 120, 420);
    corner.up = Vec3(0, 1, 0);
    corner.fovYDegrees = 40;
    const Camera cameras[2] = {*scene.camera, corner};
    for (int view = 0; view < 2; ++view) {
        const Camera& camera = cameras[view];
        CompositorSettings s;
        s.width = 80;
        s.height = 60;
        s.supersample = 2;
        c.compose(camera, uploader.front(), LightWeights::unit(1), s);
        const size_t drawn = c.drawnTriangles();
        const ImageRgb sorted = c.readImage();
        if (view == 0)
            EXPECT_GT(drawn, direct[0].triangles.size() * 9 / 10);  // the box's camera sees nearly all of it
        else
            EXPECT_LT(drawn, direct[0].triangles.size() * 6 / 10);  // a corner's view: cells skipped
        c.compose(camera, whole, LightWeights::unit(1), s);
        EXPECT_TRUE(identical(sorted, c.readImage()));  // [exact]
    }
}

TEST(ViewCompositor, UploadsInSlicesShowOneWholeSnapshot) {
    const TwoLights& t = twoLights();
    Compositor c(test::glContext(), t.scene);
    CacheMeshUploader uploader(test::glContext().gl(), t.scene.bounds.center());
    std::vector<IrradianceMeshCopy> empty(2);
    uploader.start(empty, {});
    EXPECT_TRUE(uploader.step(0));  // empty meshes take no slice
    EXPECT_EQ(uploader.front().triangleCount(), 0u);
    // A budget of zero copies one slice per step: the front set stays the
    // previous (empty) one until the copy is complete.
    uploader.start(t.direct, {});
    int steps = 0;
    while (!uploader.step(0)) {
        EXPECT_EQ(uploader.front().triangleCount(), 0u);
        EXPECT_GT(uploader.progress(), 0.0);
        ASSERT_LT(++steps, 100000);
    }
    EXPECT_GE(steps, 1);
    const GpuCacheMeshes whole = uploaded(t.direct);
    EXPECT_EQ(uploader.front().triangleCount(), whole.triangleCount());
    const LightWeights w = LightWeights::unit(2);
    EXPECT_TRUE(identical(composeImage(c, uploader.front(), w, CompositeQuantity::Radiance),
                          composeImage(c, whole, w, CompositeQuantity::Radiance)));  // [exact]
    // Readback of the display pass's illuminance at a pixel: the mean over the
    // sub-pixels that see a surface.
    const ImageRgb lux = composeImage(c, whole, w, CompositeQuantity::Illuminance, 1);
    const std::optional<double> v = c.readIlluminance(24, 30);
    ASSERT_TRUE(v.has_value());
    EXPECT_NEAR(*v, lux.at(24, 30).r, 1e-6 * lux.at(24, 30).r);
}
