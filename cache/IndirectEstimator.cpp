#include "IndirectEstimator.h"

#include "core/Error.h"

namespace ml {

VertexSample IndirectEstimator::estimateSample(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) {
    VertexSample sample;
    sample.irradiance = estimate(slot, x, n, seed);
    return sample;  // visibility 1, never partial: indirect light has no light to see
}

VertexSample IndirectEstimator::estimateRequest(size_t slot, const SampleRequest& r) {
    return estimateSample(slot, r.x, r.n, r.seed);
}

void IndirectEstimator::estimateBatch(size_t slot, const std::vector<SampleRequest>& requests,
                                      std::vector<VertexSample>& results) {
    results.resize(requests.size());
    for (size_t i = 0; i < requests.size(); ++i) {
        const SampleRequest& r = requests[i];
        asBatchRequest(i, [&] { results[i] = estimateRequest(slot, r); });
    }
}

std::optional<std::vector<Rgb>> IndirectEstimator::seenAlbedo(const IrradianceMeshCopy&, size_t, size_t, int,
                                                              uint32_t) {
    return std::nullopt;
}

}  // namespace ml
