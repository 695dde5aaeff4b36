#include "ImageMetrics.h"

#include "core/Error.h"

#include <cmath>

namespace ml {

namespace {

template <class Term>
double rootMean(const ImageRgb& x, const ImageRgb& r, Term term) {
    if (x.width != r.width || x.height != r.height)
        throw InputError(concat("image sizes differ: ", x.width, "x", x.height, " against a ", r.width, "x",
                                r.height, " reference"));
    double sum = 0;
    for (size_t i = 0; i < x.data.size(); ++i) sum += term(double(x.data[i]), double(r.data[i]));
    return x.data.empty() ? 0.0 : std::sqrt(sum / double(x.data.size()));
}

}  // namespace

double rmse(const ImageRgb& x, const ImageRgb& r) {
    return rootMean(x, r, [](double a, double b) { return (a - b) * (a - b); });
}

double relativeRmse(const ImageRgb& x, const ImageRgb& r) {
    return rootMean(x, r, [](double a, double b) { return (a - b) * (a - b) / (b * b + 0.01); });
}

}  // namespace ml
