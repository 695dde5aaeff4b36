// What the benches' walkthroughs share (CornellWalkthrough.h,
// OfficeWalkthrough.h): the curve their eyes follow, and the check that
// every view looks at the scene from inside it.
#pragma once

#include "core/Camera.h"

#include <vector>

namespace ml {

class EmbreeScene;

// The cubic Bézier curve with control points a, b, c, d at t ∈ [0, 1].
Vec3 bezier(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double t);

// Smoothstep of t ∈ [0, 1]: a path timed by it starts and ends at rest.
double smoothstep(double t);

// Every view must look at the scene from inside it: the eye is inside the
// scene's bounds and the ray through every pixel corner of a width × height
// image hits a surface, so nothing is seen out of an opening. Throws (an
// internal error naming the view and pixel) otherwise.
void checkViewsInside(const EmbreeScene& rays, const std::vector<Camera>& cameras, int width, int height);

}  // namespace ml
