// Auto exposure and the automatic lux range of the viewer, metered from a
// frame's own image when asked (the first light seen, a script's `exposure
// auto`, entering lux mode, a light change in lux mode), never on its own:
// a recording keeps one exposure unless its script asks again. With
// DisplayState::autoExposure off, exposure requests are ignored. The image is
// composited once more in the quantity the meter needs when the mode shows
// another, then the shown one is composited again.
#pragma once

#include "DisplayState.h"
#include "viewer/compositor/Compositor.h"

#include <vector>

namespace ml {

class FrameMeter {
public:
    void requestExposure() { exposurePending_ = true; }
    void requestLuxRange() { luxPending_ = true; }
    bool pending() const { return exposurePending_ || luxPending_; }
    // autoExposureScale of the last metered image (1 until one is).
    double exposureScale() const { return scale_; }

    // Meters what is pending from the frame just composited with `weights`
    // and `composite(quantity)`'s settings; sets state.luxMin/luxMax for a
    // lux range.
    void meter(Compositor& compositor, const GpuCacheMeshes& meshes, const Camera& camera, DisplayState& state,
               const std::vector<LightControl>& lights, const std::vector<Rgb>& powers, const LightWeights& weights,
               const CompositorSettings& shownSettings);

private:
    bool exposurePending_ = false, luxPending_ = false;
    double scale_ = 1;
};

}  // namespace ml
