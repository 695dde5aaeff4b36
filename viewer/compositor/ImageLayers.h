// The layers of `render`'s multi-layer EXR: one snapshot composited once in
// full and once per part, each part by masking the compositor's weights
// (LightWeights: the meshes of the part weigh 1, the rest 0), the way the
// viewer shows a light alone. No shader of its own. The parts are
// composited together (Compositor::composite of several parts), so the
// emitters' outline passes are drawn once for all the parts without
// emission: the 192-panel office's EXR (--samples 60000, 320×180) took
// 27.7 s in all, 21.4 s now, the same file bit for bit.
//
// Per sub-pixel the compositor adds Kd/π × E per mesh and Le per emitting
// face, so the parts add up to the beauty image up to float rounding
// (the sum's order on the GPU and the box filter's on the CPU):
//   beauty   = emission + direct + indirect [+ specular]
//   direct   = Σ light.<name> + direct_shared + direct_rest
//   indirect = Kd/π × Σ_b E_b (every bounce)
//   specular = mirrors, glass and Phong highlights (SpecularPaths), in
//              scenes with a glossy or specular material; the other layers
//              leave it out (CompositorSettings::specular)
// direct_shared: where lights share one mesh (many lights), their direct
// light cannot be told apart; direct_rest: the lights past the cap on
// per-light layers, together.
//   noise    = Kd/π × Σ_meshes (standard error of each mesh's interpolated
//              mean): the cache's own noise estimate per pixel, an upper
//              bound where meshes add (independent errors add in
//              quadrature); vertices sampled once count as noiseless (their
//              spread is not measured). Not part of the sum.
#pragma once

#include "Compositor.h"
#include "core/image/Illuminance.h"
#include "core/image/Image.h"

#include <optional>
#include <string>
#include <vector>

namespace ml {

struct LayerSettings {
    // Lights with a layer of their own, in the scene's order (the rest go
    // into direct_rest); each costs a composite and 3 floats per pixel.
    // Typical 64.
    size_t maxLightLayers = 64;
};

struct RenderLayers {
    ImageRgb beauty;       // what Compositor::render gives, bit for bit
    ImageRgb emission;     // the emitting faces' radiance
    ImageRgb direct;       // Kd/π × Σ direct irradiance
    ImageRgb indirect;     // Kd/π × Σ indirect irradiance
    std::optional<ImageRgb> specular;  // the specular pass (Compositor::hasSpecularPass)
    struct Light {
        std::string layer;  // "light.<sanitised name>" (lightLayerNames)
        ImageRgb image;     // Kd/π × E_l, without its emission
    };
    std::vector<Light> lights;
    std::optional<ImageRgb> directShared;  // the cache has a shared mesh
    std::optional<ImageRgb> directRest;    // more lights than LayerSettings::maxLightLayers
    ImageRgb noise;        // the standard error of the direct and indirect light (see above)
    ImageRgb reflectance;  // Kd, box-filtered (black off every surface)
    LuxImage illuminance;  // as Compositor::renderIlluminance (render --quantity lux)

    // Every layer for writeImageLayers: the beauty image as R, G, B, the
    // others as LAYER.R/G/B, illuminance as illuminance.Y.
    std::vector<ImageLayer> exrLayers() const;
};

// Composites every layer of one snapshot (`direct`, `indirect` as
// Compositor::render takes them) from `camera`.
RenderLayers renderLayers(Compositor& compositor, const Scene& scene, const Camera& camera,
                          const std::vector<IrradianceMeshCopy>& direct,
                          const std::vector<IrradianceMeshCopy>& indirect, const CompositorSettings& settings,
                          const LayerSettings& layers);

// The parts renderLayers composites together (Compositor::composite of
// several parts), for a cache of `directMeshes` direct meshes: emission,
// direct, indirect, each light with a layer of its own, the lights past the
// cap, the shared mesh.
std::vector<LightWeights> layerParts(const Scene& scene, size_t directMeshes, const LayerSettings& layers);

// How many composites renderLayers makes at the settings' sub-pixel passes
// (the illuminance is one pass): the beauty, the specular pass where there
// is one, the noise, the reflectance, and one per part (layerParts). A
// part without emission is composited only over its meshes' screen bounds
// (Compositor::composite of parts), so a light's layer costs a share of a
// whole composite: `render` times its last image's layers rather than
// count them. The back rooms' 16 lights and their shared mesh make 23.
size_t layerComposites(const Scene& scene, size_t directMeshes, bool specularPass, const LayerSettings& layers);

// "light.<name>" per light: the name with every character other than a
// letter, a digit or '_' made '_' (EXR tools split layers at '.'), "light<i>"
// when that leaves it empty, and "_2", "_3", ... on a name already taken.
std::vector<std::string> lightLayerNames(const Scene& scene);

}  // namespace ml
