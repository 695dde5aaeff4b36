// Image error metrics: how far an image is from a reference, as the logs,
// benches and tests of Meshlight report it.
#pragma once

#include "Image.h"

namespace ml {

// sqrt(mean over pixels and channels of (x − r)²). Sizes must match.
double rmse(const ImageRgb& x, const ImageRgb& reference);

// sqrt(mean over pixels and channels of (x − r)² / (r² + f)): relative
// where the reference is bright, absolute (in units of √f) where it is
// dark, so black pixels neither vanish nor dominate. f is
// relativeRmseFloor(reference). Sizes must match.
double relativeRmse(const ImageRgb& x, const ImageRgb& reference);

// The floor f of relativeRmse's denominator: 0.1², or the square of the
// reference's mean (over pixels and channels) where that is lower. A fixed
// 0.1 was made for images of about the Cornell box's level (mean 0.14): in
// a dim one it is all floor, and the error absolute. The back rooms of
// ../shared/scenes (mean 6e-4) read 0.15% where the same images scaled by
// 1,000 read 18.6%. With the mean as the unit below 0.1, an image's error
// no longer depends on the scale of its lights; images of mean 0.1 or more
// (the Cornell box, the office at about 70) measure as they always did. A
// black reference keeps 0.1².
double relativeRmseFloor(const ImageRgb& reference);

// sqrt(mean over pixels and channels of σ² / (r² + f)), f =
// relativeRmseFloor(reference): the relative RMSE an image whose pixels err
// by σ (RMS) would measure against `reference`. A reference's own noise (σ
// its standard error), or an estimate's predicted error (the image taken
// for the reference). Sizes must match.
double relativeRmsError(const ImageRgb& sigma, const ImageRgb& reference);

}  // namespace ml
