#include "ImageErrorEstimate.h"

#include "core/Error.h"

#include <cmath>

namespace ml {

namespace {

// The meshes with their predicted errors in place of irradiance (a mesh
// without them, such as the caustics', shows its standard error).
std::vector<IrradianceMeshCopy> errorMeshes(std::vector<IrradianceMeshCopy> meshes) {
    for (IrradianceMeshCopy& m : meshes) {
        const size_t n = m.irradiance.size();
        m.irradiance = m.predictedError.size() == n ? m.predictedError
                       : m.standardError.size() == n ? m.standardError
                                                     : std::vector<Rgb>(n, Rgb(0.0));
    }
    return meshes;
}

}  // namespace

ImageErrorEstimate estimateImageError(Compositor& compositor, const Scene& scene, const Camera& camera,
                                      const std::vector<IrradianceMeshCopy>& direct,
                                      const std::vector<IrradianceMeshCopy>& indirect,
                                      const CompositorSettings& settings) {
    const size_t lights = scene.lights.size();
    ImageErrorEstimate out;
    ImageRgb spread;
    {
        const GpuCacheMeshes meshes = compositor.upload(direct, indirect);
        compositor.setSpecularCache(direct, indirect);
        out.image = compositor.composite(camera, meshes, LightWeights::unit(lights), settings, &spread);
    }
    // The cache's errors: no emission, no specular pass, one pass (the error
    // varies slowly over a surface, and the silhouettes are the passes').
    CompositorSettings errorSettings = settings;
    errorSettings.passes = 1;
    errorSettings.specular = SpecularPart::Off;
    errorSettings.quantity = CompositeQuantity::Radiance;
    const GpuCacheMeshes errors = compositor.upload(errorMeshes(direct), errorMeshes(indirect));
    LightWeights w = LightWeights::unit(lights);
    w.emission.assign(lights, Rgb(0.0));
    w.indirect = Rgb(0.0);
    const ImageRgb directError = compositor.composite(camera, errors, w, errorSettings);
    w.light.assign(lights, Rgb(0.0));
    w.shared = Rgb(0.0);
    w.indirect = Rgb(1.0);
    const ImageRgb indirectError = indirect.empty() ? ImageRgb(out.image.width, out.image.height)
                                                    : compositor.composite(camera, errors, w, errorSettings);

    ImageRgb cache(out.image.width, out.image.height);
    for (size_t i = 0; i < cache.data.size(); ++i) {
        const double d = directError.data[i], n = indirectError.data[i];
        cache.data[i] = float(std::sqrt(d * d + n * n));
    }
    out.cache = relativeRmsError(cache, out.image);
    out.sampling = relativeRmsError(spread, out.image);
    return out;
}

}  // namespace ml
