// A consistent indirect gather: stratified cosine-weighted rays from the
// point (Embree, CPU) read the cached radiance where they land,
//   E(x) ≈ π/N Σ_i Lo(y_i),   Lo(y) = Kd(y)/π · Σ_m E_m(y),
// with E_m(y) the source meshes' irradiance interpolated at the hit y on the
// side the ray arrives from (MeshIrradianceLookup, exactly what the cache
// meshes hold there, read with the curvature their vertices show: linear
// interpolation of concave light runs dark, and each bounce would pass that
// on). Unlike the slice and triangle gathers it draws no
// proxy: no voxel stands a face off where it is, no slanted face is drawn in
// steps, and a corner sees its walls at their true distance. So its mean
// over seeds is the exact one-bounce irradiance of the cached radiance, and
// the cache's resampling of a vertex (its noise tolerance) drives the
// estimate to it: the bias floor of the slices goes, and what is left is
// noise, which falls as 1/√(rays) per estimate and with every resample.
//
// Beyond the paper (§5 gathers from voxel slices on the GPU): this is the
// refinement gather, chosen when the error estimate asks for accuracy the
// slices cannot give (IndirectChoice). On llvmpipe it is also faster per
// estimate than the slices (bench indirect), because the CPU's rays cost
// per ray, not per voxel face crossed.
#pragma once

#include "cache/IndirectEstimator.h"
#include "core/Scene.h"

#include <memory>
#include <vector>

namespace ml {

class EmbreeScene;
class MeshIrradianceLookup;

struct RayGatherSettings {
    // Rays per estimate at importance 1, in √rays × √rays cosine strata;
    // typical 64..1024. A weaker source (importance s) gets rays × s, at
    // least 16.
    int rays = 256;
    // Per scene light, 1 when the gather of source 0 (bounce 1) adds the
    // light's emitted radiance where its rays land on its emitting side
    // (GatheredLights.h: the direct meshes leave such a light out); empty:
    // none.
    std::vector<char> gatheredLights;
    void validate() const;  // InputError unless 4 <= rays <= 65536
};

// Per scene mesh, per triangle: 1 where a gather adds the face's emitted
// radiance (a gathered light's face); empty: no face.
using EmittingFaces = std::vector<std::vector<char>>;
EmittingFaces emittingFacesOf(const Scene& scene, const std::vector<char>& gatheredLights);

// Where a gather's ray directions come from: block `block` of the
// scrambled (0,2)-sequence `stream` (ScrambledSobol2D), N = strata² points
// of a block of 2^⌈log2 N⌉, so the gathers a vertex makes one after another
// (block 0, 1, 2, ...) stratify its hemisphere together ever finer. `seed`
// draws the rest (the choices along mirrors and glass). From a seed alone:
// stream = seed, block 0, one scrambled net per gather.
struct GatherDraw {
    GatherDraw(uint32_t seed) : seed(seed), stream(seed) {}  // NOLINT: a seed is a draw of its own
    GatherDraw(uint32_t seed, uint32_t stream, uint32_t block) : seed(seed), stream(stream), block(block) {}
    uint32_t seed = 0, stream = 0, block = 0;
};

// One gather: strata × strata cosine-weighted rays from x (unit
// normal n), their directions drawn as `draw` says, each taking Kd/π × Σ lookups' irradiance where it lands, on the
// side it arrives from (black inside a closed mesh: closedMeshes[mesh] != 0),
// plus the emitted radiance (its texture's, as the path tracer reads it)
// where it lands on the emitting side of a face `emitting` marks (null or
// empty: none); returns the irradiance, and in `reach` (when not null) the
// harmonic mean of the rays' distances to their first hit (VertexSample::
// reach), and in `variance` (when not null) the variance of the result's
// luminance with the rays taken as independent (VertexSample::ownVariance).
// RayGather::estimate's work, and bench indirect's "exact gather of the
// source".
Rgb gatherCachedRadiance(const Scene& scene, const EmbreeScene& rays, const std::vector<char>& closedMeshes,
                         const std::vector<const MeshIrradianceLookup*>& lookups, const Vec3& x, const Vec3& n,
                         int strata, const GatherDraw& draw, const EmittingFaces* emitting = nullptr,
                         double* reach = nullptr, double* variance = nullptr);
// closedMeshes for gatherCachedRadiance: isClosedMesh of every scene mesh.
std::vector<char> closedMeshesOf(const Scene& scene);

class RayGather final : public IndirectEstimator {
public:
    // `scene` must outlive the gather. Builds its own Embree scene.
    RayGather(const Scene& scene, const RayGatherSettings& settings);
    ~RayGather() override;

    std::string name() const override;
    void setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance = 1.0) override;
    void releaseSource(size_t slot) override;
    Rgb estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override;
    VertexSample estimateSample(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override;
    // A vertex's gathers as successive blocks of its stream (GatherDraw).
    VertexSample estimateRequest(size_t slot, const SampleRequest& r) override;
    IndirectStats stats() const override;
    // Where a block stands on a floor, the block's bottom vertices gathered
    // a thousandth of an edge up sent half their rays to the floor within a
    // few thousandths of the block, a sliver where the floor's direct mesh
    // interpolates towards its dark vertices under the block: the face's
    // foot read 15-30% dark in a band two pixels wide, half of the Cornell
    // box's error at 121 s. A twentieth of the edge in, the vertex takes the
    // light its edges interpolate from: `render cornell --width 256
    // --height 256 --time 30` 0.425% against 0.531% (0.420% at 0.15, its
    // bias growing), the 12-panel office at 16 s 2.11% against 2.17%.
    double borderInset() const override { return 0.05; }
    bool separatesSides() const override { return true; }
    // A gather of `mesh` itself holding 1 everywhere, √rays × √rays strata
    // per vertex (at least 2 × 2), on the calling thread.
    std::optional<std::vector<Rgb>> seenAlbedo(const IrradianceMeshCopy& mesh, size_t begin, size_t end, int rays,
                                               uint32_t seed) override;

private:
    VertexSample gather(size_t slot, const Vec3& x, const Vec3& n, const GatherDraw& draw);

    struct Source {
        std::vector<IrradianceMeshCopy> meshes;
        std::unique_ptr<MeshIrradianceLookup> lookup;        // every mesh's, in one grid
        std::vector<const MeshIrradianceLookup*> pointers;  // the same, as gatherCachedRadiance takes them
        int strata = 16;  // per side
        size_t bytes = 0;
    };

    const Scene& scene_;
    RayGatherSettings settings_;
    std::unique_ptr<EmbreeScene> rays_;
    std::vector<char> closed_;  // per scene mesh: its back is an inside (black)
    EmittingFaces emitting_;    // the gathered lights' faces, read by source 0's gathers
    std::vector<std::unique_ptr<Source>> sources_;
    IndirectStats stats_;
};

}  // namespace ml
