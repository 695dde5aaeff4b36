// The voxel-slice representation of the scene (§5.3): slices one voxel
// thick along each axis, each with two faces; a face's texture holds, per
// voxel, the radiance the surfaces inside the slice send towards that face,
// rendered on the GPU by a parallel projection of the radiance proxy from
// that side (RadianceProxy: Kd/π · E from the caches).
//
// Beyond the paper: each texel is rendered from ss×ss sub-texels and keeps
// the covered fraction in alpha (premultiplied colour), so a wall covering
// half a voxel blocks half the rays through it instead of all or none; the
// gather tests coverage stochastically. The insides of closed objects are
// black and opaque; open surfaces show each side's own radiance. Faces
// with nothing in them are freed after an occlusion query and never drawn.
// Storage: one 2D array texture (RGBA32F) of the non-empty faces, axis by
// axis, within an axis upper faces (seen from above) by slice, then lower
// faces; a face of axis a fills the layer's lower-left width × height
// texels (one texture, so a gather never branches on the axis to fetch).
#pragma once

#include "RadianceProxy.h"
#include "VoxelGrid.h"

#include <array>
#include <memory>
#include <vector>

namespace ml {

class GlContext;

class VoxelSlices {
public:
    // Renders every face from `radiance` (one value per proxy position) with
    // `supersample`² sub-texels per texel. `context` current on this thread.
    VoxelSlices(GlContext& context, const RadianceProxy& proxy, const std::vector<Rgb>& radiance, int supersample);
    ~VoxelSlices();

    struct Axis {
        int firstLayer = 0;              // this axis' faces start here in Gpu::faces
        int width = 0, height = 0;       // texels: VoxelGrid::texels of axes (a+1)%3 and (a+2)%3
        // upperBefore[i]: non-empty upper faces of slices < i (i in 0..dims);
        // lowerBefore likewise; lower faces' layers start at upperBefore[dims].
        std::vector<int> upperBefore, lowerBefore;
        int layers() const { return upperBefore.back() + lowerBefore.back(); }
    };
    const std::array<Axis, 3>& axes() const { return axes_; }
    // The faces' GL textures and buffers, defined in detail/VoxelSlicesGpu.h
    // for the gathers that draw them, so that this header needs no GL.
    struct Gpu;
    const Gpu& gpu() const { return *gpu_; }
    // Texels of a layer of Gpu::faces: the widest and highest face.
    int arrayWidth() const { return arrayWidth_; }
    int arrayHeight() const { return arrayHeight_; }
    // Where axis a's slices start in Gpu::layerTable.
    int layerTableOffset(int axis) const { return 2 * (axis > 0 ? grid_.dims[0] : 0) + 2 * (axis > 1 ? grid_.dims[1] : 0); }
    const VoxelGrid& grid() const { return grid_; }
    int facesTotal() const { return 2 * (grid_.dims[0] + grid_.dims[1] + grid_.dims[2]); }
    int facesKept() const;
    size_t memoryBytes() const;   // texture memory of the kept faces
    double buildSeconds() const { return buildSeconds_; }

private:
    VoxelGrid grid_;
    std::array<Axis, 3> axes_;
    int arrayWidth_ = 1, arrayHeight_ = 1;
    double buildSeconds_ = 0;
    std::unique_ptr<Gpu> gpu_;
};

}  // namespace ml
