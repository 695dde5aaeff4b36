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

bool VertexSampler::sampleWithoutGpu(size_t, const Vec3&, const Vec3&, uint32_t, VertexSample&) { return false; }

void sampleEachWithoutGpu(VertexSampler& sampler, const std::vector<SampleRequest>& requests,
                          std::vector<VertexSample>& results, std::vector<char>& answered, size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
        const SampleRequest& r = requests[i];
        asBatchRequest(i, [&] { answered[i] = sampler.sampleWithoutGpu(r.mesh, r.x, r.n, r.seed, results[i]); });
    }
}

void VertexSampler::sampleBatchWithoutGpu(const std::vector<SampleRequest>& requests, std::vector<VertexSample>& results,
                                          std::vector<char>& answered) {
    results.resize(requests.size());
    answered.assign(requests.size(), 0);
    sampleEachWithoutGpu(*this, requests, results, answered, 0, requests.size());
}

}  // namespace ml
