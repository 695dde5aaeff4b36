// Sampling on every core: one thread per core, each with samplers of its
// own made by the factory on that thread (on llvmpipe a GL context renders
// on the thread that uses it: one context, one core; on a GPU each thread
// feeds the same device). A batch of samples is spread over the threads,
// each sample taken exactly as one sampler alone would take it (same seed,
// same answer), and the results come back in request order: the cache a
// batch makes does not depend on the number of threads.
#pragma once

#include "CacheWorker.h"

#include <memory>

namespace ml {

class SamplerPool {
public:
    // Makes `threads` sets of samplers: the first on the calling thread
    // (which must then use the pool), the others on helper threads of their
    // own. `threads` ≥ 1.
    SamplerPool(const SamplerFactory& factory, int threads);
    ~SamplerPool();  // joins the helpers; each set dies on its own thread
    SamplerPool(const SamplerPool&) = delete;
    SamplerPool& operator=(const SamplerPool&) = delete;

    int threads() const;
    // Spread batches (sampleBatch, estimateBatch) over the threads; single
    // samples run on the calling thread. Phase times and stats add up every
    // thread's.
    DirectSampler& direct();
    IndirectEstimator* indirect();  // null when the factory makes none

    struct Impl;  // the threads and their samplers (SamplerPool.cpp)

private:
    std::unique_ptr<Impl> impl_;
    std::unique_ptr<DirectSampler> direct_;
    std::unique_ptr<IndirectEstimator> indirect_;
};

}  // namespace ml
