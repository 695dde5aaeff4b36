#include "ImageErrorEstimate.h"

#include "core/Error.h"

#include <cmath>

namespace ml {

namespace {

// A mesh's error per vertex (its predicted error; a mesh without one, such
// as a copy made by hand, shows its standard error) and the part of it that
// is the vertex's own noise.
struct VertexErrors {
    const std::vector<Rgb>* error = nullptr;
    const std::vector<Rgb>* noise = nullptr;
};

VertexErrors errorsOf(const IrradianceMeshCopy& m) {
    const size_t n = m.irradiance.size();
    VertexErrors e;
    if (m.predictedError.size() == n) {
        e.error = &m.predictedError;
        if (m.predictedNoise.size() == n) e.noise = &m.predictedNoise;
    } else if (m.standardError.size() == n) {
        e.error = e.noise = &m.standardError;
    }
    return e;
}

// What the compositor uploads of `m` (its geometry), with `values` in place
// of its irradiance.
IrradianceMeshCopy withValues(const IrradianceMeshCopy& m, std::vector<Rgb> values) {
    IrradianceMeshCopy out;
    out.positions = m.positions;
    out.normals = m.normals;
    out.triangles = m.triangles;
    out.irradiance = std::move(values);
    return out;
}

// The meshes' errors split for compositing (each mesh's geometry with one
// value per vertex in place of irradiance): the part that is not noise
// (interpolation, guesses, a model's), √(error² − noise²), and the noise's
// square (W²·m⁻⁴); `anyNoise`: whether any noise is above 0.
struct ErrorMeshes {
    std::vector<IrradianceMeshCopy> bias, noiseSquares;
    bool anyNoise = false;
};

ErrorMeshes splitErrors(const std::vector<IrradianceMeshCopy>& meshes) {
    ErrorMeshes out;
    for (const IrradianceMeshCopy& m : meshes) {
        const VertexErrors e = errorsOf(m);
        std::vector<Rgb> bias(m.irradiance.size(), Rgb(0.0)), square(m.irradiance.size(), Rgb(0.0));
        for (size_t i = 0; e.error && i < bias.size(); ++i) {
            const Rgb total = (*e.error)[i], noise = e.noise ? (*e.noise)[i] : Rgb(0.0);
            bias[i] = glm::sqrt(glm::max(total * total - noise * noise, Rgb(0.0)));
            square[i] = noise * noise;
            out.anyNoise |= luminance(square[i]) > 0;
        }
        out.bias.push_back(withValues(m, std::move(bias)));
        out.noiseSquares.push_back(withValues(m, std::move(square)));
    }
    return out;
}

}  // namespace

ImageErrorEstimate estimateImageError(Compositor& compositor, const Scene& scene, const Camera& camera,
                                      const std::vector<IrradianceMeshCopy>& direct,
                                      const std::vector<IrradianceMeshCopy>& indirect,
                                      const CompositorSettings& settings) {
    ImageErrorEstimate out;
    ImageRgb spread;
    {
        const GpuCacheMeshes meshes = compositor.upload(direct, indirect);
        compositor.setSpecularCache(direct, indirect);
        out.image = compositor.composite(camera, meshes, LightWeights::unit(scene.lights.size()), settings, &spread);
    }
    out.cache = estimateCacheError(compositor, scene, camera, direct, indirect, settings, out.image);
    out.sampling = relativeRmsError(spread, out.image);
    return out;
}

double estimateCacheError(Compositor& compositor, const Scene& scene, const Camera& camera,
                          const std::vector<IrradianceMeshCopy>& direct,
                          const std::vector<IrradianceMeshCopy>& indirect, const CompositorSettings& settings,
                          const ImageRgb& image) {
    const size_t lights = scene.lights.size();
    // The cache's errors: no emission, no specular pass, one pass (the error
    // varies slowly over a surface, and the silhouettes are the passes').
    CompositorSettings errorSettings = settings;
    errorSettings.passes = 1;
    // No outline passes: the errors have no emission to resolve (the three
    // error images drew 48 of the 64 surface passes the back rooms' image
    // took after 5 s of refinement: about 9 of 12 s).
    errorSettings.outlinePasses = 0;
    errorSettings.specular = SpecularPart::Off;
    errorSettings.quantity = CompositeQuantity::Radiance;
    LightWeights all = LightWeights::unit(lights);
    all.emission.assign(lights, Rgb(0.0));
    LightWeights directOnly = all, indirectOnly = all;
    directOnly.indirect = Rgb(0.0);
    indirectOnly.light.assign(lights, Rgb(0.0));
    indirectOnly.shared = Rgb(0.0);
    // What is not noise, direct and indirect light apart (their errors come
    // from different samplers), each mesh's added linearly within each (an
    // interpolation error or a guess leans the same way in every mesh over
    // a place: a corner reads dark in every bounce).
    const ErrorMeshes directErrors = splitErrors(direct), indirectErrors = splitErrors(indirect);
    const GpuCacheMeshes bias = compositor.upload(directErrors.bias, indirectErrors.bias);
    const ImageRgb directBias = compositor.composite(camera, bias, directOnly, errorSettings);
    const ImageRgb indirectBias = indirect.empty() ? ImageRgb(image.width, image.height)
                                                   : compositor.composite(camera, bias, indirectOnly, errorSettings);
    // The noise: every mesh's vertices draw their own samples, so their
    // noise adds in quadrature across meshes (Σ σ², composited as Kd/π ×
    // Σ σ², then times Kd/π and its root taken per pixel). Added linearly,
    // the office's seven bounces read 3.5% where their noise is 2.0%.
    ImageRgb noise(image.width, image.height);
    if (directErrors.anyNoise || indirectErrors.anyNoise) {
        const GpuCacheMeshes squares = compositor.upload(directErrors.noiseSquares, indirectErrors.noiseSquares);
        const ImageRgb sum = compositor.composite(camera, squares, all, errorSettings);
        CompositorSettings reflectance = errorSettings;
        reflectance.quantity = CompositeQuantity::Reflectance;
        const ImageRgb kd = compositor.composite(camera, squares, all, reflectance);
        for (size_t i = 0; i < noise.data.size(); ++i)
            noise.data[i] = float(std::sqrt(std::max(double(sum.data[i]) * double(kd.data[i]) / kPi, 0.0)));
    }

    ImageRgb cache(image.width, image.height);
    for (size_t i = 0; i < cache.data.size(); ++i) {
        const double d = directBias.data[i], b = indirectBias.data[i], n = noise.data[i];
        cache.data[i] = float(std::sqrt(d * d + b * b + n * n));
    }
    return relativeRmsError(cache, image);
}

bool lacksBounces(const CacheSnapshot& s, bool indirectExpected) { return indirectExpected && s.shownBounces() == 0; }

}  // namespace ml
