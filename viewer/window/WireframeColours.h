// The wireframe's colours, one per cache mesh shown (each light's own mesh,
// the lights' shared mesh, then each indirect bounce), and the legend that
// names them in the panel. Hues a golden angle apart, so meshes next to each
// other in the list never look alike however many there are.
#pragma once

#include "core/Math.h"

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace ml {

class GpuCacheMeshes;
struct Scene;

// The colour of mesh i (GpuCacheMeshes order: direct meshes, then indirect).
Rgb meshColour(size_t i);
// The colours of every mesh in `meshes`, for Compositor::drawWireframe.
std::vector<Rgb> meshColours(const GpuCacheMeshes& meshes);
// What each colour stands for ("light 0 'ceiling'", "the lights' shared
// mesh", "indirect, bounce 1"), for the panel's legend.
std::vector<std::pair<std::string, Rgb>> meshLegend(const Scene& scene, const GpuCacheMeshes& meshes);

}  // namespace ml
