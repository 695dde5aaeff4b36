// The viewer script's moves (issue 17): `light N move|aim X,Y,Z` and
// `object NAME move|rotate ...` parse into SceneChanges, name lights as the
// other light commands do, refuse bad arguments naming the line, and wait
// while the viewer is still applying the change before.

#include "core/Error.h"
#include "viewer/window/ViewScript.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace ml {
namespace {

// A viewer that records the changes it is asked for, busy for the first
// `busyFrames` asks.
class MovesHost : public ScriptHost {
public:
    std::vector<SceneChange> changes;
    int busyFrames = 0;
    Camera camera() const override { return {}; }
    void setCamera(const Camera&) override {}
    DisplayState& display() override { return state_; }
    std::vector<LightControl>& lights() override { return lights_; }
    void lightsChanged() override {}
    void meterExposure() override {}
    void meterLuxRange() override {}
    void setPaused(bool) override {}
    uint64_t shownSamples() const override { return 0; }
    double shownError() const override { return 1; }
    bool refinementDone() const override { return true; }
    void screenshot(const std::string&) override {}
    void saveCache(const std::string&) override {}
    bool busySaving() const override { return false; }
    void quit() override {}
    bool changeScene(const SceneChange& change) override {
        if (busyFrames > 0) return --busyFrames, false;
        changes.push_back(change);
        return true;
    }

private:
    DisplayState state_;
    std::vector<LightControl> lights_;
};

TEST(ViewScriptMoves, ParseResolveAndPlay) {
    ViewScript s = parseViewScript("light lampB move 1,2,3\n"
                                   "light 0 aim 0,-1,0.5\n"
                                   "object \"Short Block\" move 10,0,-5\n"
                                   "object tall rotate 0,1,0 -30\n",
                                   "moves.txt");
    resolveViewScript(s, {"lampA", "lampB"});
    ASSERT_EQ(s.actions.size(), 4u);
    MovesHost host;
    host.busyFrames = 2;  // the first move waits two frames for the one before it
    ScriptPlayer player(s);
    for (int frame = 0; frame < 8 && !player.finished(); ++frame) player.advance(0.1 * frame, host);
    ASSERT_TRUE(player.finished());
    ASSERT_EQ(host.changes.size(), 4u);
    EXPECT_EQ(host.changes[0].kind, SceneChange::Kind::MoveLight);
    EXPECT_EQ(host.changes[0].light, 1u);  // lampB
    EXPECT_EQ(host.changes[0].point, Vec3(1, 2, 3));
    EXPECT_EQ(host.changes[0].where.str(), "moves.txt:1");
    EXPECT_EQ(host.changes[1].kind, SceneChange::Kind::AimLight);
    EXPECT_EQ(host.changes[1].light, 0u);
    EXPECT_EQ(host.changes[1].point, Vec3(0, -1, 0.5));
    EXPECT_EQ(host.changes[2].kind, SceneChange::Kind::MoveObject);
    EXPECT_EQ(host.changes[2].object, "Short Block");
    EXPECT_EQ(host.changes[2].offset, Vec3(10, 0, -5));
    EXPECT_EQ(host.changes[3].kind, SceneChange::Kind::RotateObject);
    EXPECT_EQ(host.changes[3].axis, Vec3(0, 1, 0));
    EXPECT_EQ(host.changes[3].degrees, -30);
}

TEST(ViewScriptMoves, BadMovesAreInputErrorsAtTheirLine) {
    const struct {
        const char* text;
        const char* says;
    } cases[] = {
        {"light 0 move 1,2\n", "light move"},
        {"light 0 move\n", "takes X,Y,Z"},
        {"object box\n", "move DX,DY,DZ or rotate"},
        {"object box move 1,2,3 4\n", "takes DX,DY,DZ"},
        {"object box rotate 0,1,0\n", "takes AX,AY,AZ and DEG"},
        {"object box rotate 0,0,0 10\n", "is zero"},
        {"object box rotate 0,1,0 ten\n", "not a finite number"},
    };
    for (const auto& c : cases) {
        try {
            parseViewScript(c.text, "bad.txt");
            ADD_FAILURE() << "accepted: " << c.text;
        } catch (const InputError& e) {
            const std::string m = e.what();
            EXPECT_NE(m.find("bad.txt:1"), std::string::npos) << m;
            EXPECT_NE(m.find(c.says), std::string::npos) << c.text << " -> " << m;
        }
    }
    ViewScript unknown = parseViewScript("light lampC move 0,0,0\n", "bad.txt");
    EXPECT_THROW(resolveViewScript(unknown, {"lampA"}), InputError);
}

}  // namespace
}  // namespace ml
