// How far an image of the cache is expected to be from the converged image,
// in the metric the logs, benches and tests measure against a reference
// (core/image/ImageMetrics.h: relative RMSE over pixels and channels, with
// its floor, relativeRmseFloor), so that `render --until-error E` stops where a
// measurement would say about E.
//
// The cache's part: every mesh's predicted error (IrradianceMeshCopy::
// predictedError: noise and interpolation per vertex, half of what a vertex
// not sampled yet or the missing bounces' tail show) composited like
// irradiance, Kd/π × E, through the same visibility, reflectance and pixels
// as the image, in two parts:
// - the noise (IrradianceMeshCopy::predictedNoise): every mesh's vertices
//   draw their own samples, so it adds in quadrature across meshes;
// - the rest (interpolation, guesses, the tail's model): it leans the same
//   way in every mesh over a place (a corner reads dark in every bounce),
//   so it adds linearly within direct light and within indirect light, and
//   the two in quadrature (different samplers).
// With every part added linearly (before), the office of the many-lights
// issue (48 panels, 320x180, 20 s) read 4.12% against 2.62% measured, its
// seven bounces' noise 3.5% where two runs of other seeds differ by 2.0%;
// now 2.95% against 2.43%, and 2.21% against 1.91% at 60 s (cache/README.md,
// "The image's estimate"). The surface-weighted estimate
// the refinement schedules by (IrradianceCache::estimatedError) counts
// surfaces the view hides, hidden penumbra steps and a tone-curve weighting;
// this one counts what the image shows, as a reference would.
//
// The sub-pixel sampling (an emitter's outline, silhouettes) is what the
// compositor's shifted passes average away, not what refinement does. It
// is reported beside (`sampling`: half the difference of two halves of the
// passes, each itself spread over the sub-pixel) but not added: measured
// against 64 passes of the same cache, it is 1.4x high at 128x128 with 4
// passes, 5.7x high at 256x256 and right at 16 passes (the halves of a
// rook pattern are not independent); the Cornell box at 256x256 and 4
// passes errs by 0.46% against 64 passes (test_image_error).
#pragma once

#include "Compositor.h"
#include "cache/CacheWorker.h"  // CacheSnapshot
#include "core/Scene.h"
#include "core/image/Image.h"
#include "core/image/ImageMetrics.h"  // relativeRmsError

namespace ml {

struct ImageErrorEstimate {
    ImageRgb image;       // the beauty image (the passes averaged), as render() makes it
    double cache = 0;     // relative RMSE the cache's predicted error gives: the estimate
    double sampling = 0;  // ... the passes' halves give (see above); 0 with one pass
};

// Composites `direct` and `indirect` from `camera` with `settings` (as
// Compositor::render does), and their predicted errors with one pass.
ImageErrorEstimate estimateImageError(Compositor& compositor, const Scene& scene, const Camera& camera,
                                      const std::vector<IrradianceMeshCopy>& direct,
                                      const std::vector<IrradianceMeshCopy>& indirect,
                                      const CompositorSettings& settings);

// ImageErrorEstimate::cache for `image`, the beauty a caller has already
// composited from the same meshes, camera and settings (the benches time
// theirs): only the predicted errors are composited.
double estimateCacheError(Compositor& compositor, const Scene& scene, const Camera& camera,
                          const std::vector<IrradianceMeshCopy>& direct,
                          const std::vector<IrradianceMeshCopy>& indirect, const CompositorSettings& settings,
                          const ImageRgb& image);

// Indirect light is asked for and `s` shows no bounce yet (the caustics'
// mesh alone, CacheSnapshot::shownBounces, is not indirect light): the
// image then lacks light by an amount nothing has measured, and its
// estimate reads 1 (unknown). The McGuire box with a mirror and a glass
// sphere, asked until 2%, stopped at 0.7 s on an image of direct light and
// caustics, its estimate 1.81%, before any bounce was gathered.
bool lacksBounces(const CacheSnapshot& s, bool indirectExpected);

}  // namespace ml
