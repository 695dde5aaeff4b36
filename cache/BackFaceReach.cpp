#include "BackFaceReach.h"

#include "core/raytrace/EmbreeScene.h"

namespace ml {

bool backLooksOutOfObject(const EmbreeScene& rays, const Scene& scene, const Triangle3& face,
                          const Bounds3& object) {
    const Vec3 area = glm::cross(face[1] - face[0], face[2] - face[0]);
    if (!(glm::length(area) > 0)) return false;
    const Vec3 back = -glm::normalize(area);
    Vec3 t, b;
    orthonormalBasis(back, t, b);
    const Vec3 centroid = (face[0] + face[1] + face[2]) / 3.0;
    const Vec3 origin = rays.spawnPoint(centroid, back, back);
    const double slack = kBackReachSlack * std::max(scene.bounds.diagonal(), 1e-30);
    const Vec3 lo = object.lo - Vec3(slack), hi = object.hi + Vec3(slack);
    constexpr int side = 4;
    static_assert(side * side == kBackReachRays, "a square of strata");
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
            const Vec3 w = cosineDirection(back, t, b, (i + 0.5) / side, (j + 0.5) / side);
            RayHit hit;
            if (!rays.intersect(origin, w, 0.0, kInf, hit)) continue;  // the back sees nothing there
            const Vec3 p = origin + hit.t * w;
            if (glm::any(glm::lessThan(p, lo)) || glm::any(glm::greaterThan(p, hi))) return true;
        }
    return false;
}

}  // namespace ml
