// The GL objects of VoxelSlices, for the gathers that draw from them
// (SliceGather, VoxelMarchGather). Private to gpu_sampling/indirect: only
// its .cpp files include this, so its public headers need no GL.
#pragma once

#include "gpu_sampling/gl/GlObjects.h"
#include "gpu_sampling/indirect/VoxelSlices.h"

namespace ml {

struct VoxelSlices::Gpu {
    // GL_TEXTURE_2D_ARRAY, arrayWidth() × arrayHeight() × facesKept() (none
    // if no face is kept).
    GlTexture faces;
    // The same layers (R32F): the mean coordinate, along the face's axis and
    // relative to the grid's origin, of the surfaces that cover each texel,
    // so a ray inside a slice can tell what lies ahead of it from what lies
    // behind.
    GlTexture depths;
    // Per layer: vec2(plane coordinate relative to the grid's origin, side ±1).
    GlBuffer planes;
    // For the face-loop gather: per axis a, slice i, [layerTableOffset(a) +
    // 2i] the layer of its upper face, [+1] of its lower face, −1 if empty.
    GlBuffer layerTable;
};

}  // namespace ml
