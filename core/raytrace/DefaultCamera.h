// The camera of a scene whose file has none. Framing the bounds from
// outside (Camera::framing) shows an object; for a closed interior lit
// inside (a building exported without a camera), it shows the outer walls,
// which no light reaches: a black image. So the outside view is tested
// with rays, and where it sees almost nothing lit, another side or a view
// from inside, under a light, is taken.
#pragma once

#include "core/Camera.h"
#include "core/Scene.h"

#include <string>
#include <vector>

namespace ml {

class EmbreeScene;

// What a view sees, from a 32 x 18 grid of rays through its image.
struct ViewHits {
    int front = 0;  // rays that meet a face's front (CCW) side
    int back = 0;   // rays that meet a face's back side
    int lit = 0;    // rays whose surface sees one of the lights' centroids (on their emitting side)
    // Σ t² over those rays (t the hit's distance): the lit area the view
    // shows, up to the rays' solid angle and the surfaces' slant. A view
    // down a corridor beats one of the wall a step away.
    double litArea = 0;
    int rays = 0;
};
ViewHits viewHits(const EmbreeScene& rays, const Camera& camera, double aspect, const std::vector<size_t>& lights);

struct CameraChoice {
    Camera camera;
    std::string reason;  // one line for the command's output
};

// Camera::framing(bounds) (from +z) if a quarter of the surfaces its view
// meets see one of the (up to 4) most powerful planar area lights; else the
// same framing from -z, +x or -x, the one whose view meets the most lit
// surfaces, if a quarter of what it meets is lit; else (a closed interior)
// the view that shows the most lit area (ViewHits::litArea) among views
// from under each of those lights, 0.55 of the way from the light to what
// lies below it, looking level each of 8 ways (60 degrees).
CameraChoice chooseDefaultCamera(const Scene& scene, double aspect);

}  // namespace ml
