#include "IndirectEstimator.h"

#include "core/Error.h"

namespace ml {

void IndirectEstimator::estimateBatch(size_t slot, const std::vector<SampleRequest>& requests,
                                      std::vector<Rgb>& results) {
    results.resize(requests.size());
    for (size_t i = 0; i < requests.size(); ++i) {
        const SampleRequest& r = requests[i];
        asBatchRequest(i, [&] { results[i] = estimate(slot, r.x, r.n, r.seed); });
    }
}

}  // namespace ml
