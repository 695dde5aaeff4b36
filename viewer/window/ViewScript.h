// `meshlight view SCENE --script FILE`: camera keyframes and actions played
// in the window, for tests and for people who automate. One action a line;
// '#' starts a comment; blank lines are skipped.
//
//   camera t=SECONDS pos=X,Y,Z target=X,Y,Z [up=X,Y,Z] [fov=DEG]
//                      a keyframe: the camera moves from wherever it is to
//                      this pose, arriving at script time t (linear in
//                      position, target, up and fov), then the next line runs;
//                      a t already past jumps. t never decreases down the file.
//   camera in=SECONDS pos=... the same, arriving SECONDS after the line starts
//                      (after a wait of unknown length, say)
//   wait SECONDS       script time passes
//   wait-samples N     until the image shows a cache of N samples or more
//   wait-error E       until the image shows an estimated error of E or less
//   wait-done          until refinement has ended (the --samples budget, or
//                      converged for this view) and the image shows its last snapshot
//                      (the three waits also end when refinement ends)
//   mode final|direct|indirect|reflectance|lux|light N|wireframe
//                      (wireframe: final with the cache meshes' edges on)
//   wireframe on|off   contours on|off   ui on|off
//   light N on|off|intensity X|color R,G,B      (N: index from 0 or the light's name)
//   light N move X,Y,Z | aim X,Y,Z              the light to that point (an area
//                      light's centroid) or facing it (a directional light: its
//                      light travels along X,Y,Z); the cache follows (issue 17)
//   object NAME move DX,DY,DZ                   a Scene mesh by name, by an offset
//   object NAME rotate AX,AY,AZ DEG             about its bounds' centre (right-handed)
//                      (a move waits for the one before to be applied)
//   group NAME on|off|dim F   every light of the group (ViewLights.h) on, off,
//                      or at intensity F; NAME as the panel lists it
//   exposure EV|auto   tonemap aces|reinhard|clamp   lux-range MIN MAX|auto
//   pause | resume     refinement
//   screenshot FILE    .png: the window as shown; .exr/.hdr: the linear
//                      image of the mode (radiance, reflectance or lux)
//   save-cache FILE    quit
//
// A name with spaces is written in double quotes ("Ceiling Light"); '#'
// starts a comment at the start of a word only, so "Panel#2" is a name.
//
// Script time is wall-clock seconds since the script started, or
// frames × --script-step when that is given (deterministic frame timing).
// A screenshot ends the actions of its frame: what comes after it applies
// from the next frame on. Errors name the file and line.
#pragma once

#include "DisplayState.h"
#include "ViewLights.h"
#include "core/Camera.h"
#include "core/Error.h"
#include "core/SceneChange.h"

#include <optional>
#include <string>
#include <vector>

namespace ml {

struct ScriptAction {
    enum class Kind {
        Camera, Wait, WaitSamples, WaitError, WaitDone, Mode, Wireframe, Contours, Ui, Light, Group, Exposure,
        ExposureAuto, Tonemap, LuxRange, LuxRangeAuto, Pause, Resume, Screenshot, SaveCache, Quit, Change,
        Indirect,
    };
    enum class LightChange { On, Off, Intensity, Colour };

    Kind kind = Kind::Quit;
    SourceLocation where;
    // Camera
    double time = 0;
    bool relative = false;  // `in=`: time counts from when the line starts
    Vec3 position{0.0}, target{0.0};
    std::optional<Vec3> up;
    std::optional<double> fov;
    // Wait, WaitError, Exposure, LuxRange (number, number2)
    double number = 0, number2 = 0;
    uint64_t samples = 0;  // WaitSamples
    // Mode
    DisplayMode mode = DisplayMode::Final;
    bool flag = false;     // Wireframe, Contours, Ui: on; Mode: wireframe on
    // Light (and Mode light N): the light as written, resolved by
    // resolveViewScript(). Group: the group as written, and its lights once
    // resolved; `change` On, Off or Intensity (dim F).
    std::string lightName;
    size_t light = 0;
    LightGroup group;
    LightChange change = LightChange::On;
    Rgb colour{1.0};
    ToneOperator op = ToneOperator::Aces;
    std::string path;      // Screenshot, SaveCache; Indirect: cache, volume, vpl or lpv
    // Change: a light (its index set by resolveViewScript) or an object moves.
    SceneChange sceneChange;
};

struct ViewScript {
    std::string file;
    std::vector<ScriptAction> actions;
};

// Parses script text; `file` names it in errors ("view.txt:7: ...").
// Throws InputError for an unknown action, a missing or extra argument, a
// number that does not parse or is not finite, a keyframe earlier than the
// one before, an unsupported screenshot extension.
ViewScript parseViewScript(const std::string& text, const std::string& file);
// Reads and parses a file (InputError if it cannot be read).
ViewScript loadViewScript(const std::string& path);

// Checks the script against the scene before anything opens: light names
// and indices exist (sets ScriptAction::light), groups exist (sets
// ScriptAction::group; the error lists the scene's), keyframe cameras are
// valid, screenshot and cache folders exist. InputError naming the line
// otherwise.
void resolveViewScript(ViewScript& script, const std::vector<std::string>& lightNames,
                       const std::vector<LightGroup>& groups = {});

// What the player needs from the viewer. Queries answer for the image shown
// now; commands take effect in the frame being made.
class ScriptHost {
public:
    virtual ~ScriptHost() = default;
    virtual Camera camera() const = 0;
    virtual void setCamera(const Camera& camera) = 0;
    virtual DisplayState& display() = 0;
    virtual std::vector<LightControl>& lights() = 0;
    virtual void lightsChanged() = 0;  // after a change to lights()
    virtual void meterExposure() = 0;  // exposure auto: from the image shown
    virtual void meterLuxRange() = 0;  // lux-range auto
    virtual void setPaused(bool paused) = 0;
    virtual uint64_t shownSamples() const = 0;
    virtual double shownError() const = 0;
    // Refinement has nothing more to do and the image shows its last snapshot.
    virtual bool refinementDone() const = 0;
    virtual void screenshot(const std::string& path) = 0;  // of this frame, once drawn
    // Starts saving the cache; busySaving() until it is written.
    virtual void saveCache(const std::string& path) = 0;
    virtual bool busySaving() const = 0;
    virtual void quit() = 0;
    // A light or an object moves; false while the last change is still
    // being applied (the script tries again next frame). A viewer that
    // cannot move things refuses with an InputError.
    virtual bool changeScene(const SceneChange& change) {
        throw InputError(change.where, "this viewer cannot move lights or objects");
    }
    // What the image shows of indirect light: "cache" (a real-time method
    // standing in while it catches up), or a method's own light, live.
    virtual void setIndirectDisplay(const std::string& display) {
        throw InputError("this viewer cannot show another indirect light than its own (" + display + ")");
    }
};

class ScriptPlayer {
public:
    explicit ScriptPlayer(ViewScript script) : script_(std::move(script)) {}
    // Runs what is due at script time `now` (seconds, non-decreasing):
    // actions in order until one must wait, a screenshot is taken, or the
    // script ends.
    void advance(double now, ScriptHost& host);
    bool finished() const { return next_ >= script_.actions.size(); }
    // The line being played, for messages ("view.txt:4").
    std::string where() const;

private:
    // True when the action is done; false: call again next frame.
    bool run(const ScriptAction& a, double now, ScriptHost& host, bool& endFrame);

    ViewScript script_;
    size_t next_ = 0;
    bool started_ = false;     // the current action has begun
    double startedAt = 0;      // script time it began
    Camera from_;              // Camera: the pose it began from
};

// The camera a fraction `a` ∈ [0, 1] of the way from `from` to `to`
// (linear in position, target, up and fov; exactly `to` at 1).
Camera interpolateCamera(const Camera& from, const Camera& to, double a);

}  // namespace ml
