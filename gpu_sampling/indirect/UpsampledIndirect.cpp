#include "UpsampledIndirect.h"

#include "core/Error.h"
#include "core/raytrace/EmbreeScene.h"

#include <algorithm>
#include <cmath>

namespace ml {

void UpsamplingSettings::validate() const {
    if (factor < 2 || factor > 16) throw InputError(concat("upsampling: a factor of ", factor, " is not within 2..16"));
    if (!(normalCosine > 0 && normalCosine <= 1))
        throw InputError(concat("upsampling: a normal cosine of ", normalCosine, " is not within (0, 1]"));
    if (!(planeDistance > 0))
        throw InputError(concat("upsampling: a plane distance of ", planeDistance, " is not positive"));
}

ScreenSurfaces traceScreenSurfaces(const EmbreeScene& rays, const Camera& camera, int width, int height, int step) {
    if (width < 1 || height < 1 || step < 1)
        throw InputError(concat("screen surfaces: ", width, "x", height, " pixels every ", step, " is not an image"));
    camera.validate();
    Vec3 forward, right, up;
    camera.basis(forward, right, up);
    const double tanHalf = std::tan(glm::radians(camera.fovYDegrees) * 0.5);
    const double aspect = double(width) / double(height);
    ScreenSurfaces s;
    s.width = (width + step - 1) / step;
    s.height = (height + step - 1) / step;
    const size_t count = size_t(s.width) * size_t(s.height);
    s.hit.assign(count, 0);
    s.position.assign(count, Vec3(0.0));
    s.normal.assign(count, Vec3(0.0));
    s.depth.assign(count, 0.0);
    for (int j = 0; j < s.height; ++j)
        for (int i = 0; i < s.width; ++i) {
            // The centre of block (i, j) in pixels: ((i + ½)·step, (j + ½)·step).
            const double sx = 2.0 * (i + 0.5) * step / width - 1.0;
            const double sy = 1.0 - 2.0 * (j + 0.5) * step / height;
            const Vec3 dir = glm::normalize(forward + (sx * aspect * tanHalf) * right + (sy * tanHalf) * up);
            RayHit hit;
            if (!rays.intersect(camera.position, dir, 0.0, kInf, hit)) continue;
            const SurfacePoint y = rays.surface(hit);
            const size_t k = s.index(i, j);
            s.hit[k] = 1;
            s.position[k] = y.position;
            s.normal[k] = glm::dot(y.geometricNormal, dir) > 0 ? -y.geometricNormal : y.geometricNormal;
            s.depth[k] = hit.t;
        }
    return s;
}

std::vector<Rgb> fullResolutionIndirect(const ScreenSurfaces& full, const IrradianceAt& irradiance) {
    std::vector<Rgb> image(full.hit.size(), Rgb(0.0));
    for (size_t k = 0; k < full.hit.size(); ++k)
        if (full.hit[k]) image[k] = irradiance(full.position[k], full.normal[k]);
    return image;
}

UpsampledIndirect upsampleIndirect(const ScreenSurfaces& full, const ScreenSurfaces& low,
                                   const UpsamplingSettings& settings, const IrradianceAt& irradiance) {
    settings.validate();
    const int k = settings.factor;
    if (low.width != (full.width + k - 1) / k || low.height != (full.height + k - 1) / k)
        throw InputError(concat("upsampling: a ", low.width, "x", low.height, " low resolution is not ", full.width,
                                "x", full.height, " at 1/", k));
    UpsampledIndirect out;
    out.width = full.width;
    out.height = full.height;
    // The low-resolution pass.
    std::vector<Rgb> coarse(low.hit.size(), Rgb(0.0));
    for (size_t i = 0; i < low.hit.size(); ++i)
        if (low.hit[i]) coarse[i] = irradiance(low.position[i], low.normal[i]), ++out.lowEvaluations;
    out.irradiance.assign(full.hit.size(), Rgb(0.0));
    out.flagged.assign(full.hit.size(), 0);
    // Per pixel: its blend, or a flag and the full evaluation.
    auto axis = [k](int x, int n, int& i0, int& i1, double& t) {
        // Pixel x's centre in low-resolution sample coordinates.
        const double u = (x + 0.5) / k - 0.5;
        i0 = std::clamp(int(std::floor(u)), 0, n - 1);
        i1 = std::min(i0 + 1, n - 1);
        t = i1 > i0 ? std::clamp(u - i0, 0.0, 1.0) : 0.0;
    };
    for (int y = 0; y < full.height; ++y)
        for (int x = 0; x < full.width; ++x) {
            const size_t p = full.index(x, y);
            if (!full.hit[p]) continue;
            ++out.visiblePixels;
            int x0, x1, y0, y1;
            double tx, ty;
            axis(x, low.width, x0, x1, tx);
            axis(y, low.height, y0, y1, ty);
            const int xs[4] = {x0, x1, x0, x1}, ys[4] = {y0, y0, y1, y1};
            const double w[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
            bool continuous = true;
            Rgb blend(0.0);
            for (int c = 0; c < 4 && continuous; ++c) {
                if (!(w[c] > 0)) continue;
                const size_t q = low.index(xs[c], ys[c]);
                continuous = low.hit[q] && glm::dot(low.normal[q], full.normal[p]) >= settings.normalCosine &&
                             std::abs(glm::dot(low.normal[q], full.position[p] - low.position[q])) <=
                                 settings.planeDistance * full.depth[p];
                blend += w[c] * coarse[q];
            }
            if (continuous) {
                out.irradiance[p] = blend;
            } else {
                out.flagged[p] = 1;
                out.irradiance[p] = irradiance(full.position[p], full.normal[p]);
                ++out.fullEvaluations;
            }
        }
    return out;
}

}  // namespace ml
