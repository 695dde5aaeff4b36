#include "CornellWalkthrough.h"

#include "core/Error.h"
#include "core/raytrace/EmbreeScene.h"

#include <cmath>

namespace ml {

namespace {

Vec3 bezier(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double t) {
    const double s = 1 - t;
    return s * s * s * a + 3 * s * s * t * b + 3 * s * t * t * c + t * t * t * d;
}

}  // namespace

std::vector<Camera> walkthroughCameras(const Scene& scene, int views) {
    ML_ASSERT(scene.camera, "the Cornell box has a camera");
    const Camera standard = *scene.camera;
    const Vec3 eye0(278, 273, 10), eye1(278, 273, 120), eye2(200, 330, 150), eye3(180, 330, 200);
    const Vec3 target0(278, 273, 559.2), target1(330, 100, 380);
    std::vector<Camera> cameras;
    for (int i = 0; i < views; ++i) {
        const double t = views > 1 ? double(i) / (views - 1) : 0.0;
        const double s = t * t * (3 - 2 * t);
        Camera c = standard;
        c.position = bezier(eye0, eye1, eye2, eye3, s);
        c.target = target0 + s * (target1 - target0);
        c.validate();
        cameras.push_back(c);
    }
    return cameras;
}

void checkViewsInside(const EmbreeScene& rays, const std::vector<Camera>& cameras, int size) {
    const Bounds3& b = rays.scene().bounds;
    for (size_t v = 0; v < cameras.size(); ++v) {
        const Camera& c = cameras[v];
        ML_ASSERT(glm::all(glm::greaterThan(c.position, b.lo)) && glm::all(glm::lessThan(c.position, b.hi)),
                  "walkthrough view ", v, " has its eye outside the box");
        Vec3 forward, right, up;
        c.basis(forward, right, up);
        const double tanY = std::tan(glm::radians(c.fovYDegrees) / 2);
        for (int y = 0; y <= size; ++y)
            for (int x = 0; x <= size; ++x) {
                const Vec3 dir = forward + (2.0 * x / size - 1) * tanY * right + (1 - 2.0 * y / size) * tanY * up;
                RayHit hit;
                ML_ASSERT(rays.intersect(c.position, dir, 0, kInf, hit), "walkthrough view ", v,
                          " sees out of the box at pixel corner (", x, ", ", y, ")");
            }
    }
}

}  // namespace ml
