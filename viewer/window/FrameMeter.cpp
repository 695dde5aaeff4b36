#include "FrameMeter.h"

#include "core/image/Illuminance.h"
#include "core/image/ToneMap.h"

#include <algorithm>
#include <cmath>

namespace ml {

void FrameMeter::meter(Compositor& compositor, const GpuCacheMeshes& meshes, const Camera& camera,
                       DisplayState& state, const std::vector<LightControl>& lights, const std::vector<Rgb>& powers,
                       const LightWeights& weights, const CompositorSettings& shownSettings) {
    if (!pending()) return;
    const CompositeQuantity shownQuantity = shownSettings.quantity;
    auto pixelsOf = [&](CompositeQuantity q, const LightWeights& w) {
        CompositorSettings cs = shownSettings;
        cs.quantity = q;
        if (q != shownQuantity) compositor.compose(camera, meshes, w, cs);
        ImageRgb image = compositor.readPixels();
        if (q != shownQuantity) compositor.compose(camera, meshes, weights, shownSettings);
        return image;
    };
    if (exposurePending_ && !state.autoExposure) {
        exposurePending_ = false;  // the exposure is fixed: 2^exposureEV alone
    } else if (exposurePending_) {
        DisplayState final = state;
        if (shownQuantity != CompositeQuantity::Radiance) final.mode = DisplayMode::Final;
        scale_ = autoExposureScale(pixelsOf(CompositeQuantity::Radiance, compositeWeights(final, lights, powers)));
        exposurePending_ = false;
    }
    if (luxPending_) {
        const ImageRgb lux = pixelsOf(CompositeQuantity::Illuminance, weights);
        // A few tens of thousands of pixels give the percentiles to a pixel's worth.
        const int step = std::max(1, int(std::sqrt(double(lux.pixelCount()) / 65536.0)));
        std::vector<double> values;
        for (int y = 0; y < lux.height; y += step)
            for (int x = 0; x < lux.width; x += step) values.push_back(lux.at(x, y).r);
        const auto [lo, hi] = autoLuxRange(std::move(values));
        state.luxMin = lo;
        state.luxMax = hi;
        luxPending_ = false;
    }
}

}  // namespace ml
