// Image error metrics: how far an image is from a reference, as the logs,
// benches and tests of Meshlight report it.
#pragma once

#include "Image.h"

namespace ml {

// sqrt(mean over pixels and channels of (x − r)²). Sizes must match.
double rmse(const ImageRgb& x, const ImageRgb& reference);

// sqrt(mean over pixels and channels of (x − r)² / (r² + 0.01)): relative
// where the reference is bright, absolute (in units of 0.1) where it is
// dark, so black pixels neither vanish nor dominate. Sizes must match.
double relativeRmse(const ImageRgb& x, const ImageRgb& reference);

}  // namespace ml
