#include "VertexSampler.h"

#include "core/Error.h"

namespace ml {

void asBatchRequest(size_t i, const std::function<void()>& f) {
    try {
        f();
    } catch (const InputError&) {
        throw;
    } catch (const SampleBatchError&) {
        throw;
    } catch (const std::exception& e) {
        throw SampleBatchError(i, e.what());
    }
}

void sampleEach(VertexSampler& sampler, const std::vector<SampleRequest>& requests, std::vector<VertexSample>& results,
                size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
        const SampleRequest& r = requests[i];
        asBatchRequest(i, [&] { results[i] = sampler.sample(r.mesh, r.x, r.n, r.seed); });
    }
}

void VertexSampler::sampleBatch(const std::vector<SampleRequest>& requests, std::vector<VertexSample>& results) {
    results.resize(requests.size());
    sampleEach(*this, requests, results, 0, requests.size());
}

}  // namespace ml
