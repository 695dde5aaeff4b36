#include "IndirectSetup.h"

#include "core/Error.h"
#include "gpu_sampling/indirect/TriangleGather.h"
#include "gpu_sampling/indirect/VoxelMarchGather.h"

namespace ml {

std::vector<std::string> indirectMethodNames() {
    return {"slices", "slice-quads", "raymarch", "fisheye-triangles", "perspective", "hemicube"};
}

void IndirectChoice::decide(const Scene& scene) {
    plan = planBounces(scene, bounces);
    solver.bounces = enabled ? plan.bounces : 0;
    solver.albedo = plan.meanAlbedo;
    solver.validate();
}

std::string IndirectChoice::describe() const {
    if (method == "slices" || method == "slice-quads" || method == "raymarch")
        return concat(method, ": ", gather.imageSize, "x", gather.imageSize, " fish-eye gathers over ", gather.resolution,
                      " voxels along the longest side (slices ", gather.sliceSupersample,
                      "x supersampled), and the proxy's triangles near the point (",
                      gather.nearVoxels == 0 ? std::string("its own voxel")
                                             : concat("its voxel and ", gather.nearVoxels, " more each way"),
                      ")");
    return concat(method, ": the radiance proxy's triangles (", gather.resolution,
                  " voxels along the longest side set its size), gathered at image size ", gather.imageSize);
}

void declareIndirectOptions(Options& o) {
    const GatherSettings g;
    const BouncePlanSettings b;
    o.value("bounces", "N", "indirect bounces (default: from the albedo light meets, see --indirect-tolerance)");
    o.value("indirect-tolerance", "F", "enough bounces to leave less than F of the radiance missing",
            concat(b.missingFraction));
    o.value("max-bounces", "N", "at most N bounces whatever the albedo", concat(b.maxBounces));
    o.value("indirect-method", "NAME",
            "the hemispherical gather: slices (the paper's voxel slices), slice-quads (one quad per slice face), "
            "raymarch (the voxels as a 3D texture), fisheye-triangles, perspective (one 160-degree image) or "
            "hemicube (the proxy's triangles at --voxels, image --gather-size)",
            std::string("slices"));
    o.value("voxels", "N", "voxel slices: N voxels along the scene's longest side (32..128 typical)",
            concat(g.resolution));
    o.value("gather-size", "N", "fish-eye gather image N x N pixels", concat(g.imageSize));
    o.value("near-voxels", "K", "triangles, not slices, within K voxels of the gathering point", concat(g.nearVoxels));
    o.value("slice-supersample", "S", "S x S sub-texels per slice texel", concat(g.sliceSupersample));
}

IndirectChoice readIndirectOptions(const Options& o) {
    IndirectChoice c;
    c.enabled = !o.isSet("direct-only");
    c.method = o.str("indirect-method");
    const std::vector<std::string> names = indirectMethodNames();
    if (std::find(names.begin(), names.end(), c.method) == names.end()) {
        std::string list;
        for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
        throw InputError(concat("--indirect-method '", c.method, "': unknown (", list, ")"));
    }
    c.gather.resolution = o.integer("voxels", 4, 512);
    c.gather.imageSize = o.integer("gather-size", 4, 1024);
    c.gather.nearVoxels = o.integer("near-voxels", 0, 8);
    c.gather.sliceSupersample = o.integer("slice-supersample", 1, 8);
    c.gather.validate();
    c.bounces.missingFraction = o.number("indirect-tolerance", 1e-9, 0.999);
    c.bounces.maxBounces = o.integer("max-bounces", 1, 256);
    if (o.has("bounces")) c.bounces.forced = o.integer("bounces", 0, 256);
    c.bounces.validate();
    return c;
}

std::unique_ptr<IndirectEstimator> makeIndirectEstimator(GlContext& context, const Scene& scene,
                                                         const IndirectChoice& choice) {
    if (choice.method == "slices") return std::make_unique<SliceGather>(context, scene, choice.gather);
    // The comparisons of `bench indirect`: the same proxy, gathered otherwise.
    if (choice.method == "slice-quads") {
        GatherSettings g = choice.gather;
        g.quadPerFace = true;
        return std::make_unique<SliceGather>(context, scene, g);
    }
    if (choice.method == "raymarch") return std::make_unique<VoxelMarchGather>(context, scene, choice.gather);
    for (TriangleProjection p : {TriangleProjection::Fisheye, TriangleProjection::Perspective, TriangleProjection::Hemicube})
        if (choice.method == triangleProjectionName(p)) {
            TriangleGatherSettings t;
            t.projection = p;
            t.imageSize = choice.gather.imageSize;
            t.resolution = choice.gather.resolution;
            return std::make_unique<TriangleGather>(context, scene, t);
        }
    throw InputError(concat("indirect method '", choice.method, "' is unknown"));
}

WorkerFactories workerFactories(const Scene& scene, const DirectChoice& direct, const IndirectChoice& indirect,
                                std::shared_ptr<DirectPhaseTimes> totals) {
    // Made by the first factory on the worker thread, used by the second.
    auto shared = std::make_shared<std::shared_ptr<DirectEstimators>>();
    const bool gl = indirect.enabled && indirect.solver.bounces > 0;
    WorkerFactories f;
    f.direct = [&scene, direct, totals, shared, gl]() -> DirectSampleFn {
        auto estimators = std::make_shared<DirectEstimators>(scene, direct, gl);
        if (gl) *shared = estimators;  // for the indirect factory, which takes it at once
        return [estimators, totals](size_t light, const Vec3& x, const Vec3& n, uint32_t seed) {
            const VertexSample s = estimators->sampleOne(light, x, n, seed);
            *totals = estimators->totals();
            return s;
        };
    };
    if (gl)
        f.indirect = [&scene, indirect, shared]() -> std::unique_ptr<IndirectEstimator> {
            ML_ASSERT(*shared && (*shared)->context(), "the direct sampler's GL context comes first");
            // The estimator keeps the direct estimators (and their context)
            // alive as long as it lives.
            struct Owned : IndirectEstimator {
                std::shared_ptr<DirectEstimators> keep;
                std::unique_ptr<IndirectEstimator> inner;
                std::string name() const override { return inner->name(); }
                void setSource(size_t s, const std::vector<IrradianceMeshView>& m, double importance) override {
                    inner->setSource(s, m, importance);
                }
                void releaseSource(size_t s) override { inner->releaseSource(s); }
                Rgb estimate(size_t s, const Vec3& x, const Vec3& n, uint32_t seed) override {
                    return inner->estimate(s, x, n, seed);
                }
                IndirectStats stats() const override { return inner->stats(); }
            };
            auto owned = std::make_unique<Owned>();
            // Taken, not copied: the factories outlive the worker thread, and
            // the GL context must die on the thread it was made on (OSMesa
            // breaks the calling thread's current context otherwise).
            owned->keep = std::move(*shared);
            owned->inner = makeIndirectEstimator(*owned->keep->context(), scene, indirect);
            return owned;
        };
    return f;
}

}  // namespace ml
