// The indirect estimator of Fournier & Péroche (§5.2–5.4): a fish-eye
// image of the hemisphere at the shading point, in which every pixel has
// the same projected solid angle, drawn from the voxel slices (one
// full-screen quad per slice face in front of the point, back-projected per
// pixel, eq. 7–10) plus the proxy's triangles near the point (its voxel and
// `nearVoxels` neighbours each way, intersected per pixel), summed to the
// irradiance.
#pragma once

#include "GatherSettings.h"
#include "NearField.h"
#include "RadianceProxy.h"
#include "VoxelSlices.h"
#include "cache/IndirectEstimator.h"

#include <map>
#include <memory>

namespace ml {

class GlContext;

// Seconds per phase over every gather so far (with `timePhases`, the GPU is
// waited for after each phase, so the parts add up to the whole).
struct GatherPhaseTimes {
    double nearField = 0;  // collecting and uploading the near triangles (CPU)
    double draw = 0;       // slice quads and near-field pass (GPU)
    double readback = 0;   // reading the image back and summing it
};

class SliceGather : public IndirectEstimator {
public:
    // `context` current on this thread for the estimator's lifetime.
    SliceGather(GlContext& context, const Scene& scene, const GatherSettings& settings);
    ~SliceGather() override;

    std::string name() const override { return settings_.quadPerFace ? "slice-quads" : "slices"; }
    // A source of importance q is gathered with an image of N·√q pixels a
    // side (at least 16): the noise of a gather grows as 1/side, and the
    // error it makes in the image shrinks as q.
    void setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance = 1.0) override;
    void releaseSource(size_t slot) override;
    Rgb estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override;
    IndirectStats stats() const override;

    const RadianceProxy& proxy() const { return proxy_; }
    const VoxelSlices& slices(size_t slot) const { return *slots_.at(slot).slices; }
    // The radiance of the proxy in a slot (one per proxy position).
    const std::vector<Rgb>& radiance(size_t slot) const { return slots_.at(slot).radiance; }
    void setTimePhases(bool on) { timePhases_ = on; }
    const GatherPhaseTimes& phases() const { return phases_; }
    // Near triangles drawn by the last gather.
    size_t lastNearCount() const { return lastNear_; }
    // The last gather's image: RGBA per pixel, row 0 at the bottom (alpha 1
    // where a surface was hit), lastImageSize() a side.
    const std::vector<float>& lastImage() const { return pixels_; }
    int lastImageSize() const { return lastImageSize_; }

private:
    struct Slot {
        int imageSize = 40;
        std::vector<Rgb> radiance;
        std::unique_ptr<VoxelSlices> slices;
    };
    // Its programs, targets and near-triangle buffer, defined in the .cpp so
    // that this header needs no GL.
    struct Gpu;

    GlContext& context_;
    GatherSettings settings_;
    RadianceProxy proxy_;
    std::map<size_t, Slot> slots_;
    std::unique_ptr<Gpu> gpu_;
    NearField nearField_;
    std::vector<NearTriangleGpu> near_;
    std::vector<float> pixels_;
    GatherPhaseTimes phases_;
    bool timePhases_ = false;
    size_t lastNear_ = 0;
    int lastImageSize_ = 0;
    IndirectStats stats_;
};

}  // namespace ml
