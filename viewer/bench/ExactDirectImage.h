// The exact direct-light image: what `render --direct-only` converges to.
// Per sub-pixel (the compositor's S×S grid of sub-pixel centres, box-
// filtered to pixels), the visible surface point is found by ray casting
// (Embree) and shaded with Le + Kd/π × Σ over lights of the exact direct
// irradiance (CGAL visible polygon, Lambert's formula) at that point with
// its interpolated shading normal. It differs from a converged render only
// by the cache's interpolation, which is what the convergence bench and
// tests measure.
#pragma once

#include "core/Camera.h"
#include "core/Scene.h"
#include "core/image/Image.h"

namespace ml {

struct ExactImageSettings {
    int width = 256, height = 256;
    int supersample = 4;  // as CompositorSettings::supersample
    int threads = 0;      // 0: every core
};

// Deterministic whatever the thread count (each sub-pixel is independent).
// About 16,000 sub-pixels per second per core on the Cornell box.
ImageRgb renderExactDirect(const Scene& scene, const Camera& camera, const ExactImageSettings& settings);

}  // namespace ml
