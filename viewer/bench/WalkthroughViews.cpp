#include "WalkthroughViews.h"

#include "core/Error.h"
#include "core/raytrace/EmbreeScene.h"

#include <cmath>

namespace ml {

Vec3 bezier(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double t) {
    const double s = 1 - t;
    return s * s * s * a + 3 * s * s * t * b + 3 * s * t * t * c + t * t * t * d;
}

double smoothstep(double t) { return t * t * (3 - 2 * t); }

void checkViewsInside(const EmbreeScene& rays, const std::vector<Camera>& cameras, int width, int height) {
    const Bounds3& b = rays.scene().bounds;
    for (size_t v = 0; v < cameras.size(); ++v) {
        const Camera& c = cameras[v];
        ML_ASSERT(glm::all(glm::greaterThan(c.position, b.lo)) && glm::all(glm::lessThan(c.position, b.hi)),
                  "walkthrough view ", v, " has its eye outside the scene");
        Vec3 forward, right, up;
        c.basis(forward, right, up);
        const double tanY = std::tan(glm::radians(c.fovYDegrees) / 2), tanX = tanY * width / height;
        for (int y = 0; y <= height; ++y)
            for (int x = 0; x <= width; ++x) {
                const Vec3 dir = forward + (2.0 * x / width - 1) * tanX * right + (1 - 2.0 * y / height) * tanY * up;
                RayHit hit;
                ML_ASSERT(rays.intersect(c.position, dir, 0, kInf, hit), "walkthrough view ", v,
                          " sees out of the scene at pixel corner (", x, ", ", y, ")");
            }
    }
}

}  // namespace ml
