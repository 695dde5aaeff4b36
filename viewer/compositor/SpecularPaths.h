// The compositor's specular pass (issue 16): per sub-pixel, the radiance no
// cache mesh holds, which the composite adds to Kd/π × E + Le:
//   - a mirror's or glass's reflection and transmission, followed through
//     further mirrors and glass to the surface where each path ends and
//     read from the cache there (CachedRadiance, deterministic splitting);
//   - the Phong highlight of a glossy material (Ks > 0), from each light's
//     cached direct irradiance and its direction.
//
// Traced on the CPU (Embree) beside the frame: the compositor's GL is
// llvmpipe on the machines Meshlight is built for, where a GPU ray tracer
// would run on the same cores as Embree, in shader code without its BVH
// (bench view measures what the pass costs a frame). The eye rays use the compositor's projection, sub-pixel grid
// and pass shift (CompositorSettings), so each value lands on the sub-pixel
// whose surface it belongs to. Only sub-pixels inside the screen rectangle
// of some glossy or specular triangle are traced; the rest stay black.
#pragma once

#include "Compositor.h"
#include "gpu_sampling/indirect/CachedRadiance.h"

#include <atomic>
#include <memory>
#include <vector>

namespace ml {

class SpecularPaths {
public:
    // `scene` must outlive this. Builds an Embree scene of it.
    SpecularPaths(const Scene& scene, const SpecularSplitSettings& settings = {});
    ~SpecularPaths();

    // Whether a scene needs the pass: some face's material is glossy or specular.
    static bool needed(const Scene& scene);

    // The cache the paths read, as Compositor::render takes it (copied).
    void setCache(const std::vector<IrradianceMeshCopy>& direct, const std::vector<IrradianceMeshCopy>& indirect);
    bool hasCache() const;

    // Specular radiance, W·sr⁻¹·m⁻², of the view that Compositor::compose
    // makes with `settings` (size, supersampling, shift): one value per
    // block of reduction × reduction sub-pixels, traced at the block's
    // centre, ⌈width·S / reduction⌉ × ⌈height·S / reduction⌉, row 0 at the
    // top. `weights` scale each mesh and emitter as they scale the
    // composite, so a light switched off leaves the reflections too.
    // Thread-safe, also against setCache (a trace reads the cache it
    // started with); `cancel`, once true, ends it early with rows left black.
    ImageRgb trace(const Camera& camera, const CompositorSettings& settings, const LightWeights& weights,
                   int reduction = 1, const std::atomic<bool>* cancel = nullptr) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ml
