#include "ImageMetrics.h"

#include "core/Error.h"

#include <algorithm>
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

double relativeRmseFloor(const ImageRgb& reference) {
    double sum = 0;
    for (float v : reference.data) sum += double(v);
    const double mean = reference.data.empty() ? 0.0 : sum / double(reference.data.size());
    const double unit = mean > 0 ? std::min(0.1, mean) : 0.1;
    return unit * unit;
}

double relativeRmsError(const ImageRgb& sigma, const ImageRgb& r) {
    const double floor = relativeRmseFloor(r);
    return rootMean(sigma, r, [floor](double s, double b) { return s * s / (b * b + floor); });
}

double relativeRmse(const ImageRgb& x, const ImageRgb& r) {
    const double floor = relativeRmseFloor(r);
    return rootMean(x, r, [floor](double a, double b) { return (a - b) * (a - b) / (b * b + floor); });
}

}  // namespace ml
