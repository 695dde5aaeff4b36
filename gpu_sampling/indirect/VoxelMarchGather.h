// A third way to gather from the voxels, for `bench indirect`: the voxel
// slices' faces copied into one 3D texture, in world order (six blocks, one
// per face direction; volume_fill.comp), and a fragment program that walks
// each fish-eye pixel's ray through it plane crossing by plane crossing (a
// 3D DDA over every voxel, empty or not), compositing partly covered faces
// front to back (gather_volume_march.frag). The fish-eye image, its jitter,
// the eye and the near field (the proxy's triangles around the point,
// NearField) are SliceGather's; what differs is the walk (a 3D texture
// instead of quads or the walk over non-empty slice faces) and alpha
// compositing instead of a stochastic coverage test: the same mean, less
// noise. Memory: 6 × voxels × 16 bytes per source (25 MB at 64 voxels, 200
// MB at 128); the slices it is filled from are freed once it is.
#pragma once

#include "NearField.h"
#include "RadianceProxy.h"
#include "SliceGather.h"
#include "cache/IndirectEstimator.h"

#include <map>
#include <memory>

namespace ml {

class GlContext;

class VoxelMarchGather : public IndirectEstimator {
public:
    // imageSize, resolution, nearVoxels and sliceSupersample as for
    // SliceGather (quadPerFace does not apply). `context` current on this
    // thread for the estimator's lifetime.
    VoxelMarchGather(GlContext& context, const Scene& scene, const GatherSettings& settings);
    ~VoxelMarchGather() override;

    std::string name() const override { return "raymarch"; }
    // `importance` is not used: every source is gathered at the same image size.
    void setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance = 1.0) override;
    void releaseSource(size_t slot) override;
    Rgb estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override;
    IndirectStats stats() const override;

    const RadianceProxy& proxy() const { return proxy_; }
    // Per phase over every gather, as SliceGather's (nearField: collecting
    // and uploading the near triangles).
    void setTimePhases(bool on) { timePhases_ = on; }
    const GatherPhaseTimes& phases() const { return phases_; }
    size_t lastNearCount() const { return lastNear_; }

private:
    // Its programs, target, near-triangle buffer and each slot's 3D texture,
    // defined in the .cpp so that this header needs no GL.
    struct Gpu;

    GlContext& context_;
    GatherSettings settings_;
    RadianceProxy proxy_;
    NearField near_;
    std::map<size_t, std::vector<Rgb>> radiance_;  // per slot: one per proxy position
    std::unique_ptr<Gpu> gpu_;
    std::vector<NearTriangleGpu> nearTriangles_;
    std::vector<float> pixels_;
    GatherPhaseTimes phases_;
    bool timePhases_ = false;
    size_t lastNear_ = 0;
    IndirectStats stats_;
};

}  // namespace ml
