// The GL objects of ProxyClusters, for the gathers that rasterise the proxy
// (TriangleGather). Private to gpu_sampling/indirect: only its .cpp files
// include this, so its public headers need no GL.
#pragma once

#include "gpu_sampling/gl/GlObjects.h"
#include "gpu_sampling/indirect/ProxyClusters.h"

#include <vector>

namespace ml {

struct ProxyClusters::Gpu {
    // A vertex buffer of one radiance per proxy position (RGB float), for
    // binding point 1 of vao.
    GlBuffer uploadRadiance(const std::vector<Rgb>& radiance) const;

    const GlApi* gl = nullptr;
    size_t positionCount = 0;  // of the proxy: radiance values an upload takes
    GlBuffer vertices;
    // Attributes 0: position relative to the grid's origin (vec3), 1: the
    // reflecting side's normal and 1 if closed (vec4), both from binding 0
    // (`vertices`); 2: radiance (vec3) from binding 1 (an uploadRadiance
    // buffer). Indices come from the caller's buffer.
    GlVertexArray vao;
};

}  // namespace ml
