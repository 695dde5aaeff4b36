// A pinhole camera: the view a render, a probe's reference or a walkthrough uses.
#pragma once

#include "Math.h"

namespace ml {

struct Bounds3;

struct Camera {
    Vec3 position{0.0, 0.0, 1.0};
    Vec3 target{0.0};
    Vec3 up{0.0, 1.0, 0.0};
    double fovYDegrees = 40.0;  // vertical field of view, typical 30..90

    // Right-handed view matrix (camera looks down -z).
    Mat4 view() const;
    // Camera basis: forward (unit, towards target), right, true up.
    void basis(Vec3& forward, Vec3& right, Vec3& trueUp) const;
    // Throws InputError if degenerate (zero direction, up parallel to it, fov out of (0,180)).
    void validate() const;

    // Looks at the centre of `bounds` from the +z side, far enough for the
    // whole box to fit in the vertical and horizontal fields of view.
    static Camera framing(const Bounds3& bounds, double aspect, double fovYDegrees = 40.0);
};

}  // namespace ml
