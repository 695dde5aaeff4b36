#include "BenchOptions.h"

#include "gpu_sampling/gl/GlContext.h"

namespace ml {

BenchOptions::BenchOptions() : backend(GlBackend::OsMesa) {}

}  // namespace ml
