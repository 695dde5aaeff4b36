#include "CornellWalkthrough.h"

#include "WalkthroughViews.h"

#include "core/Error.h"

#include <cmath>

namespace ml {

std::vector<Camera> walkthroughCameras(const Scene& scene, int views) {
    ML_ASSERT(scene.camera, "the Cornell box has a camera");
    const Camera standard = *scene.camera;
    const Vec3 eye0(278, 273, 10), eye1(278, 273, 120), eye2(200, 330, 150), eye3(180, 330, 200);
    const Vec3 target0(278, 273, 559.2), target1(330, 100, 380);
    std::vector<Camera> cameras;
    for (int i = 0; i < views; ++i) {
        const double t = views > 1 ? double(i) / (views - 1) : 0.0;
        const double s = smoothstep(t);
        Camera c = standard;
        c.position = bezier(eye0, eye1, eye2, eye3, s);
        c.target = target0 + s * (target1 - target0);
        c.validate();
        cameras.push_back(c);
    }
    return cameras;
}

}  // namespace ml
