// The indirect-light options shared by `render`, `probe`, `plan` and the
// viewer, read in one place; the estimator they select; and the factories
// that give the cache worker its samplers, on its own thread and sharing
// one GL context.
#pragma once

#include "DirectSetup.h"
#include "Options.h"
#include "cache/CacheWorker.h"
#include "cache/IndirectEstimator.h"
#include "cache/IndirectSolver.h"
#include "core/raytrace/BouncePlan.h"
#include "gpu_sampling/indirect/SliceGather.h"

#include <memory>
#include <string>

namespace ml {

struct IndirectChoice {
    bool enabled = true;               // false with --direct-only
    std::string method = "slices";     // the gather: see indirectMethodNames()
    GatherSettings gather;
    BouncePlanSettings bounces;
    IndirectSettings solver;           // bounces and albedo come from plan()
    BouncePlan plan;                   // filled by plan()

    // Decides the bounce count from the scene (or --bounces) and fills
    // `solver` with it.
    void decide(const Scene& scene);
    std::string describe() const;      // "slices, 40x40 fish-eye, 64 voxels, near box ±1"
};

// "slices" (the paper's), and the comparisons of `bench indirect`.
std::vector<std::string> indirectMethodNames();

void declareIndirectOptions(Options& options);
IndirectChoice readIndirectOptions(const Options& options);

// The estimator `choice.method` names, on `context` (current on this thread).
std::unique_ptr<IndirectEstimator> makeIndirectEstimator(GlContext& context, const Scene& scene,
                                                         const IndirectChoice& choice);

struct WorkerFactories {
    CacheWorker::SamplerFactory direct;
    CacheWorker::IndirectFactory indirect;  // empty when indirect light is off
};
// The direct sampler (directSamplerFactory) and, if indirect light is on,
// the indirect estimator on the same GL context, both made on the worker
// thread. Direct phase times go to `totals` as with directSamplerFactory.
WorkerFactories workerFactories(const Scene& scene, const DirectChoice& direct, const IndirectChoice& indirect,
                                std::shared_ptr<DirectPhaseTimes> totals);

}  // namespace ml
