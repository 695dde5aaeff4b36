#include "ImageLayers.h"

#include "core/Error.h"

#include <algorithm>
#include <cctype>
#include <set>

namespace ml {

std::vector<std::string> lightLayerNames(const Scene& scene) {
    std::vector<std::string> names;
    std::set<std::string> taken;
    for (size_t l = 0; l < scene.lights.size(); ++l) {
        std::string name = scene.lights[l].name;
        for (char& c : name)
            if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
        if (name.empty()) name = concat("light", l);
        std::string unique = name;
        for (int k = 2; taken.count(unique); ++k) unique = concat(name, "_", k);
        taken.insert(unique);
        names.push_back("light." + unique);
    }
    return names;
}

namespace {

// Weights that keep no mesh and no emitting face: parts are added to it.
LightWeights none(size_t lights) {
    LightWeights w;
    w.light.assign(lights, Rgb(0.0));
    w.emission.assign(lights, Rgb(0.0));
    w.indirect = Rgb(0.0);
    w.shared = Rgb(0.0);
    return w;
}

}  // namespace

RenderLayers renderLayers(Compositor& compositor, const Scene& scene, const Camera& camera,
                          const std::vector<IrradianceMeshCopy>& direct,
                          const std::vector<IrradianceMeshCopy>& indirect, const CompositorSettings& settings,
                          const LayerSettings& layerSettings) {
    const size_t lights = scene.lights.size();
    ML_ASSERT(direct.size() == lights || direct.size() == lights + 1, direct.size(), " meshes for ", lights,
              " lights");
    const GpuCacheMeshes meshes = compositor.upload(direct, indirect);
    compositor.setSpecularCache(direct, indirect);
    CompositorSettings beauty = settings;
    beauty.quantity = CompositeQuantity::Radiance;
    // Every part but `specular` without the specular pass, so that they add up.
    CompositorSettings radiance = beauty;
    radiance.specular = SpecularPart::Off;
    auto composite = [&](const LightWeights& w, const CompositorSettings& s) {
        return compositor.composite(camera, meshes, w, s);
    };

    RenderLayers out;
    out.beauty = composite(LightWeights::unit(lights), beauty);
    if (compositor.hasSpecularPass()) {
        CompositorSettings alone = beauty;
        alone.specular = SpecularPart::Only;
        out.specular = composite(LightWeights::unit(lights), alone);
    }
    {
        // The meshes' standard errors composited as if they were irradiance.
        const auto errors = [](std::vector<IrradianceMeshCopy> meshes) {
            for (IrradianceMeshCopy& m : meshes)
                m.irradiance = m.standardError.size() == m.irradiance.size()
                                   ? m.standardError
                                   : std::vector<Rgb>(m.irradiance.size(), Rgb(0.0));
            return meshes;
        };
        const GpuCacheMeshes noiseMeshes = compositor.upload(errors(direct), errors(indirect));
        LightWeights w = LightWeights::unit(lights);
        w.emission.assign(lights, Rgb(0.0));
        // No emission: no outline to resolve (as the estimate's error
        // images, ImageErrorEstimate.cpp).
        CompositorSettings noOutlines = radiance;
        noOutlines.outlinePasses = 0;
        out.noise = compositor.composite(camera, noiseMeshes, w, noOutlines);
    }
    // The parts, composited together: the emitters' outline passes are
    // drawn once for all the parts without emission, and each light's
    // layer only where its mesh is (Compositor::composite).
    const std::vector<LightWeights> parts = layerParts(scene, direct.size(), layerSettings);
    std::vector<ImageRgb> images = compositor.composite(camera, meshes, parts, radiance);
    const std::vector<std::string> names = lightLayerNames(scene);
    const size_t own = std::min(lights, layerSettings.maxLightLayers);
    out.emission = std::move(images[0]);
    out.direct = std::move(images[1]);
    out.indirect = std::move(images[2]);
    for (size_t l = 0; l < own; ++l) out.lights.push_back({names[l], std::move(images[3 + l])});
    if (own < lights) out.directRest = std::move(images[3 + own]);
    if (direct.size() > lights) out.directShared = std::move(images.back());

    CompositorSettings reflectance = settings;
    reflectance.quantity = CompositeQuantity::Reflectance;
    out.reflectance = composite(LightWeights::unit(lights), reflectance);
    out.illuminance = compositor.renderIlluminance(camera, direct, indirect, settings);
    return out;
}

std::vector<LightWeights> layerParts(const Scene& scene, size_t directMeshes, const LayerSettings& layerSettings) {
    const size_t lights = scene.lights.size();
    std::vector<LightWeights> parts;
    LightWeights w = none(lights);
    w.emission.assign(lights, Rgb(1.0));
    parts.push_back(w);  // 0: emission
    w = none(lights);
    w.light.assign(lights, Rgb(1.0));
    w.shared = Rgb(1.0);
    parts.push_back(w);  // 1: direct
    w = none(lights);
    w.indirect = Rgb(1.0);
    parts.push_back(w);  // 2: indirect
    const size_t own = std::min(lights, layerSettings.maxLightLayers);
    for (size_t l = 0; l < own; ++l) {
        w = none(lights);
        w.light[l] = Rgb(1.0);
        parts.push_back(w);  // 3 + l: light l alone
    }
    if (own < lights) {
        w = none(lights);
        for (size_t l = own; l < lights; ++l) w.light[l] = Rgb(1.0);
        parts.push_back(w);  // the lights past the cap
    }
    if (directMeshes > lights) {
        w = none(lights);
        w.shared = Rgb(1.0);
        parts.push_back(w);  // last: the shared mesh
    }
    return parts;
}

size_t layerComposites(const Scene& scene, size_t directMeshes, bool specularPass, const LayerSettings& layers) {
    return 3 + (specularPass ? 1 : 0) + layerParts(scene, directMeshes, layers).size();
}

std::vector<ImageLayer> RenderLayers::exrLayers() const {
    std::vector<ImageLayer> layers = {ImageLayer::rgb("", beauty), ImageLayer::rgb("emission", emission),
                                      ImageLayer::rgb("direct", direct), ImageLayer::rgb("indirect", indirect)};
    if (specular) layers.push_back(ImageLayer::rgb("specular", *specular));
    for (const Light& l : lights) layers.push_back(ImageLayer::rgb(l.layer, l.image));
    if (directShared) layers.push_back(ImageLayer::rgb("direct_shared", *directShared));
    if (directRest) layers.push_back(ImageLayer::rgb("direct_rest", *directRest));
    layers.push_back(ImageLayer::rgb("noise", noise));
    layers.push_back(ImageLayer::rgb("reflectance", reflectance));
    layers.push_back(ImageLayer::single("illuminance", "Y", illuminance.lux));
    return layers;
}

}  // namespace ml
