// What the cache needs from a method that estimates indirect irradiance.
//
// Indirect light is computed bounce by bounce (§5.1): bounce n is the
// irradiance arriving at a point from surfaces that reflect the irradiance
// of bounce n−1 (bounce 0 being direct light). An estimator is given that
// irradiance as cache meshes (setSource), turns it into exitant radiance
// Lo = Kd/π · ΣE over the scene's surfaces in whatever representation it
// gathers from (voxel slices, triangles, a 3D texture, later irradiance
// volumes, propagation volumes or virtual point lights), and then answers
// irradiance queries at points. Emission is not part of the source: light
// straight from the emitters is direct light and lives in the direct meshes.
#pragma once

#include "IrradianceCache.h"
#include "VertexSampler.h"

#include <optional>
#include <string>
#include <vector>

namespace ml {

// What building the source and gathering cost so far, for the plan, the
// log and the bench.
struct IndirectStats {
    size_t sourceBytes = 0;       // memory held by every source now built (textures, buffers)
    double buildSeconds = 0;      // time spent in setSource, all calls
    uint64_t estimates = 0;       // estimate() calls
    double estimateSeconds = 0;   // time spent in estimate(), all calls
    std::string source;           // one line on the last source built: "64x32x64 voxels, 212 of 384 slice faces, 9.1 MB"
};

class IndirectEstimator {
public:
    virtual ~IndirectEstimator() = default;

    // "slices", "perspective", ...
    virtual std::string name() const = 0;
    // Builds source `slot` (0, 1, ...; replacing what it held): surfaces
    // reflecting the sum of these meshes' irradiance (meshes laid over the
    // scene as IrradianceCache::view makes them: every light's direct mesh,
    // or one bounce's indirect mesh). Bounce n gathers from slot n−1.
    // `importance` (0, 1] is what an estimate from this source is worth
    // against one of bounce 1's pass 2: the share of light the source gives
    // relative to bounce 1's (about ā^(n−1) for bounce n), times the first
    // pass's share (IndirectSettings::firstPassGathers) while that is
    // gathered. An estimator may spend less per estimate on a weak bounce or
    // a first pass (a smaller image, fewer rays).
    virtual void setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance,
                           double importance = 1.0) = 0;
    // Frees a slot's memory; estimating from it again needs setSource.
    virtual void releaseSource(size_t slot) = 0;
    // Irradiance (W·m⁻²) at x, unit normal n, arriving from the surfaces of
    // source `slot`, drawing its randomness (jitter) from `seed`: one
    // estimate whose mean over seeds is the method's answer.
    virtual Rgb estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) = 0;
    // estimate() as a cache vertex's sample: its irradiance, and where the
    // method traces rays, their reach (VertexSample::reach: how near the
    // surfaces are, which tells the cache where indirect light may step).
    // The default knows no reach.
    virtual VertexSample estimateSample(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed);
    // estimateSample for a cache vertex's request, which also numbers the
    // vertex's samples (SampleRequest::stream, index): a method may draw a
    // vertex's successive estimates as blocks of one sequence, so that
    // their mean converges faster than independent estimates'. Each
    // estimate alone must keep the same mean. The default takes
    // estimateSample(slot, r.x, r.n, r.seed).
    virtual VertexSample estimateRequest(size_t slot, const SampleRequest& r);
    // Every request's estimateSample from source `slot` (requests[i].mesh is
    // not used), each exactly what it returns for that request; a failure
    // throws SampleBatchError naming the first failing request.
    virtual void estimateBatch(size_t slot, const std::vector<SampleRequest>& requests,
                               std::vector<VertexSample>& results);
    virtual IndirectStats stats() const = 0;
    // How far into its faces a bounce mesh's border vertex is gathered, in
    // its shortest edge (CacheLayout::borderInset). A thousandth by
    // default: a voxel gather sees the scene at the voxels' resolution, and
    // further in its slices' steps show (the furnace's worst pixel 3.7% off
    // at a twentieth, 3% allowed).
    virtual double borderInset() const { return CacheLayout::kDefaultInset; }
    // Whether a gather tells the two sides of a thin surface apart (rays
    // do; a voxel straddles it). Only then do the bounce meshes copy the
    // backs that reflected light alone reaches (CacheLayout::BackFaces::
    // ReachedByScene): gathered through voxels, such a copy of a partition's
    // back would hold the light leaking through it and pass it on to the
    // room behind (the two rooms of test_indirect: 3.7% of the lit floor's
    // light on the dark one, against 0.5%).
    virtual bool separatesSides() const { return false; }
    // The cosine-weighted albedo each vertex of `mesh` sees on its normal's
    // side: what a gather of a source holding 1 W·m⁻² on every surface
    // returns, 1/N Σ Kd over the surfaces N rays land on (0 where they leave
    // the scene or meet a closed object's inside), from `rays` rays per
    // vertex drawn from `seed`, for vertices [begin, end) (the same values
    // however the range is split). Light that has bounced a few times is near
    // uniform over a room, so the bounces after the first are about this
    // albedo times it: an office's ceiling, which sees the grey carpet, gets
    // less of them than the floor under the white ceiling
    // (IndirectSolver's guess of the bounces not yet gathered). nullopt
    // where the method has no cheap rays (the default): a voxel gather
    // costs as much for this as for light.
    virtual std::optional<std::vector<Rgb>> seenAlbedo(const IrradianceMeshCopy& mesh, size_t begin, size_t end,
                                                       int rays, uint32_t seed);
};

}  // namespace ml
