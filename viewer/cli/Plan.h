// The plan: what a render will simulate and why, printed before any work
// (`meshlight plan SCENE` prints it alone).
#pragma once

#include "SamplerOptions.h"
#include "cache/IrradianceCache.h"
#include "core/Scene.h"

namespace ml {

// The cache options `render` and `plan` share, read in one place.
void declareCacheOptions(Options& options);
CacheSettings readCacheSettings(const Options& options);

// `indirect` must have decided its bounces (IndirectChoice::decide).
void printPlan(const Scene& scene, const DirectChoice& choice, const CacheSettings& cache,
               const IndirectChoice& indirect);

}  // namespace ml
