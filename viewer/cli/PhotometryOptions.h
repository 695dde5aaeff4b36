// --photometry, which `render`, `probe` and `view` share: how irradiance
// becomes lux (core/image/Photometry.h), declared and read in one place.
#pragma once

#include "Options.h"
#include "core/image/Photometry.h"

namespace ml {

// --photometry radiance|rec709, default radiance.
void declarePhotometryOption(Options& options);
// The photometry named by --photometry; InputError for another name.
Photometry readPhotometryOption(const Options& options);

}  // namespace ml
