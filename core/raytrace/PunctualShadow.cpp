#include "PunctualShadow.h"

#include <cmath>

namespace ml {

PunctualSample punctualIrradiance(const EmbreeScene& rays, size_t light, const Vec3& x, const Vec3& n) {
    return punctualIrradiance(rays, light, x, n, n);
}

PunctualSample punctualIrradiance(const EmbreeScene& rays, size_t light, const Vec3& x, const Vec3& n,
                                  const Vec3& ng) {
    const Light& l = rays.scene().lights[light];
    const PunctualIncidence in = punctualIncidence(l, x, n);
    PunctualSample out;
    if (!(in.irradiance.r > 0 || in.irradiance.g > 0 || in.irradiance.b > 0)) return out;
    if (!(glm::dot(in.toLight, ng) > 0)) return out;  // below the true surface
    out.lit = true;
    out.toLight = in.toLight;
    const Vec3 origin = rays.spawnPoint(x, ng, in.toLight);
    double tFar = kInf;
    if (std::isfinite(in.distance)) {
        // Along the ray from the lifted origin to the light, less the offset
        // at the light's end (the surface a light lies on does not hide it).
        tFar = glm::dot(l.emission.position - origin, in.toLight) - rays.rayOffset(l.emission.position);
        if (!(tFar > 0)) tFar = 0;
    }
    // Hits nearer than the lift are the surfaces x touches (the next wall of
    // a corner, the floor under a block's edge): the ray starts on their
    // plane, and they do not hide the light, as the raster sampler's near
    // plane at half its eye lift does not draw them.
    const double tNear = rays.rayOffset(x);
    out.visible = tFar <= tNear || !rays.occluded(origin, in.toLight, tNear, tFar);
    if (out.visible) out.irradiance = in.irradiance;
    return out;
}

}  // namespace ml
