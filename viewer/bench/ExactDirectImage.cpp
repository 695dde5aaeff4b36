#include "ExactDirectImage.h"

#include "core/ParallelFor.h"

#include "core/Error.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/reference/ExactIrradiance.h"

#include <algorithm>
#include <cmath>
#include <thread>

namespace ml {

ImageRgb renderExactDirect(const Scene& scene, const Camera& camera, const ExactImageSettings& s) {
    ML_ASSERT(s.width > 0 && s.height > 0 && s.supersample > 0, "exact image size");
    camera.validate();
    const EmbreeScene rays(scene);
    const ExactDirect exact(scene);
    Vec3 forward, right, up;
    camera.basis(forward, right, up);
    const double tanY = std::tan(glm::radians(camera.fovYDegrees) * 0.5);
    const double tanX = tanY * double(s.width) / double(s.height);
    const int S = s.supersample;
    ImageRgb image(s.width, s.height);

    auto shadeRow = [&](int y) {
        for (int x = 0; x < s.width; ++x) {
            Rgb sum(0.0);
            for (int j = 0; j < S; ++j)
                for (int i = 0; i < S; ++i) {
                    // Sub-pixel centre in normalised device coordinates; row 0 at the top.
                    const double u = 2 * (x + (i + 0.5) / S) / s.width - 1;
                    const double v = 1 - 2 * (y + (j + 0.5) / S) / s.height;
                    const Vec3 dir = forward + u * tanX * right + v * tanY * up;
                    RayHit hit;
                    if (!rays.intersect(camera.position, dir, 0, kInf, hit)) continue;
                    const SurfacePoint p = rays.surface(hit);
                    const Material& m = scene.materials[p.material];
                    const bool front = glm::dot(p.geometricNormal, dir) < 0;
                    if (front) sum += m.ke;
                    // The side the camera sees.
                    const Vec3 n = front ? p.shadingNormal : -p.shadingNormal;
                    Rgb e(0.0);
                    for (size_t l = 0; l < scene.lights.size(); ++l) e += exact.irradiance(l, p.position, n);
                    sum += m.kd / kPi * e;
                }
            const Rgb mean = sum / double(S * S);
            const size_t o = image.offset(x, y);
            image.data[o] = float(mean.r), image.data[o + 1] = float(mean.g), image.data[o + 2] = float(mean.b);
        }
    };
    const int threads = s.threads > 0 ? s.threads : int(std::max(1u, std::thread::hardware_concurrency()));
    parallelFor(size_t(s.height), threads, [&](size_t y) { shadeRow(int(y)); });
    return image;
}

}  // namespace ml
