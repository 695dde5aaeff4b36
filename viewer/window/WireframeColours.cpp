#include "WireframeColours.h"

#include "core/Error.h"
#include "core/Scene.h"
#include "viewer/compositor/GpuCacheMeshes.h"

#include <cmath>

namespace ml {

Rgb meshColour(size_t i) {
    const double h = std::fmod(0.08 + 0.6180339887 * double(i), 1.0) * 6.0;
    const double s = 0.7, v = 1.0;
    const int sector = int(h);
    const double f = h - sector, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
    switch (sector % 6) {
        case 0: return {v, t, p};
        case 1: return {q, v, p};
        case 2: return {p, v, t};
        case 3: return {p, q, v};
        case 4: return {t, p, v};
        default: return {v, p, q};
    }
}

std::vector<Rgb> meshColours(const GpuCacheMeshes& meshes) {
    std::vector<Rgb> colours;
    for (size_t i = 0; i < meshes.directCount() + meshes.indirectCount(); ++i) colours.push_back(meshColour(i));
    return colours;
}

std::vector<std::pair<std::string, Rgb>> meshLegend(const Scene& scene, const GpuCacheMeshes& meshes) {
    std::vector<std::pair<std::string, Rgb>> legend;
    for (size_t i = 0; i < meshes.directCount() + meshes.indirectCount(); ++i)
        legend.emplace_back(i < scene.lights.size()     ? concat("light ", i, " '", scene.lights[i].name, "'")
                            : i < meshes.directCount() ? std::string("the lights' shared mesh")
                                                       : concat("indirect, bounce ", i - meshes.directCount() + 1),
                            meshColour(i));
    return legend;
}

}  // namespace ml
