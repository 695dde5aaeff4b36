// The sampling options shared by `render`, `probe`, `plan`, `view` and the
// benches, declared and read in one place: they fill the DirectChoice and
// IndirectChoice that gpu_sampling/SamplerFactory.h turns into samplers.
#pragma once

#include "Options.h"
#include "gpu_sampling/SamplerFactory.h"

namespace ml {

void declareDirectOptions(Options& options);
DirectChoice readDirectOptions(const Options& options);

void declareIndirectOptions(Options& options);
IndirectChoice readIndirectOptions(const Options& options);

}  // namespace ml
