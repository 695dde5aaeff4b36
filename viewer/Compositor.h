// The compositor of §3.2: a reflectance image rendered from the scene's
// geometry, a direct-irradiance image per light rendered from that light's
// cache mesh (Gouraud-interpolated), combined per sub-pixel as
// Kd/π × Σ E_l + Le, then box-filtered to pixels.
#pragma once

#include "cache/IrradianceCache.h"
#include "core/Camera.h"
#include "core/Scene.h"
#include "core/image/Image.h"

#include <memory>
#include <vector>

namespace ml {

class GlContext;

struct CompositorSettings {
    int width = 512;      // output pixels
    int height = 512;
    // Sub-pixels per pixel side, typical 4 (16 samples, box filter): an EXR
    // pixel is the average radiance over its area.
    int supersample = 4;
    void validate() const;
};

class Compositor {
public:
    // `scene` must outlive the compositor; `context` current on this thread.
    Compositor(GlContext& context, const Scene& scene);
    ~Compositor();

    // Linear radiance, W·sr⁻¹·m⁻², row 0 at the top. `direct` holds one
    // cache mesh per light (IrradianceCache::view), in the scene's light order.
    ImageRgb render(const Camera& camera, const std::vector<IrradianceMeshView>& direct,
                    const CompositorSettings& settings);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ml
