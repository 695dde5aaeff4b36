#include "BenchStatistics.h"

#include <algorithm>
#include <cstddef>

namespace ml {

double median(std::vector<double> values) {
    if (values.empty()) return 0;
    const auto mid = values.begin() + std::ptrdiff_t(values.size() / 2);
    std::nth_element(values.begin(), mid, values.end());
    if (values.size() % 2) return *mid;
    return 0.5 * (*mid + *std::max_element(values.begin(), mid));
}

}  // namespace ml
