// Walking through a scene: WASD moves, the mouse looks around, a key goes
// back to the start. Pure logic (no window, no GL), so it is unit-tested.
//
// The camera keeps the start camera's up vector as the world's vertical:
// looking is a yaw about it and a pitch towards it (clamped short of
// straight up or down, so the view never rolls or flips), and walking moves
// in the horizontal plane of the current heading, whatever the pitch, the
// way a person walks while looking up at a ceiling. Rising and sinking are
// separate keys.
#pragma once

#include "core/Camera.h"

#include <optional>

namespace ml {

// One frame's input, already mapped from keys and the mouse.
struct WalkInput {
    double forward = 0;  // +1 forward (W), −1 back (S)
    double right = 0;    // +1 right (D), −1 left (A)
    double up = 0;       // +1 up (E), −1 down (Q), along the world's vertical
    double speedFactor = 1;  // e.g. 4 with Shift held, 0.25 with Ctrl
    double lookRight = 0;    // mouse motion, pixels (+ turns right)
    double lookDown = 0;     // mouse motion, pixels (+ looks down)
};

class WalkCamera {
public:
    // `speed`: scene units per second at speedFactor 1, > 0; the viewer uses
    // the scene's diagonal / 8 (any scene is crossed in a few seconds).
    WalkCamera(const Camera& start, double speed);

    // Moves and turns for `seconds` of this input. `radiansPerPixel` turns
    // the mouse motion into angles (the viewer uses the vertical field of
    // view / the window's height: dragging across the window turns by the
    // field of view). Returns true when the camera changed.
    bool update(const WalkInput& input, double seconds, double radiansPerPixel);
    // Back to the start camera, exactly.
    void reset();
    // Jumps to `camera` (a script's keyframe), exactly; walking goes on from
    // there with this camera's up as the vertical.
    void set(const Camera& camera);

    // The current camera. Right after construction, reset() or set(), the
    // very camera given (bit for bit: a refinement view must repeat).
    Camera camera() const;
    const Camera& start() const { return start_; }
    double speed() const { return speed_; }
    void setSpeed(double unitsPerSecond);
    // Yaw about the vertical and pitch above the horizon, radians.
    double yaw() const { return yaw_; }
    double pitch() const { return pitch_; }

    // Pitch stays within ±(π/2 − this): the view never turns over.
    static constexpr double kPitchMargin = 0.01;

private:
    void setBasis(const Camera& c);
    Vec3 heading() const;  // unit, horizontal

    Camera start_;
    double speed_;
    std::optional<Camera> exact_;  // the camera given, until the first move
    Vec3 position_{0.0};
    Vec3 vertical_{0.0, 1.0, 0.0};  // unit world up
    Vec3 north_{0.0, 0.0, -1.0};    // horizontal heading at yaw 0
    Vec3 east_{1.0, 0.0, 0.0};      // horizontal heading at yaw π/2 (north × vertical)
    double yaw_ = 0, pitch_ = 0;
    double focus_ = 1;  // distance from the position to the target, kept
    double fovY_ = 40;
};

}  // namespace ml
