#include "PowerLawFit.h"

#include "core/Error.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ml {

double PowerLawFit::at(double x) const { return coefficient * std::pow(x, exponent); }

PowerLawFit fitPowerLaw(const std::vector<double>& x, const std::vector<double>& y) {
    if (x.size() != y.size())
        throw std::invalid_argument(concat("power-law fit: ", x.size(), " x values for ", y.size(), " y values"));
    std::vector<double> lx, ly;
    for (size_t i = 0; i < x.size(); ++i) {
        if (!(std::isfinite(x[i]) && std::isfinite(y[i]) && x[i] > 0 && y[i] > 0))
            throw std::invalid_argument(
                concat("power-law fit: point ", i, " is (", x[i], ", ", y[i], "); both must be finite and > 0"));
        lx.push_back(std::log(x[i]));
        ly.push_back(std::log(y[i]));
    }
    const double n = double(lx.size());
    double mx = 0, my = 0;
    for (size_t i = 0; i < lx.size(); ++i) {
        mx += lx[i] / n;
        my += ly[i] / n;
    }
    // Centred sums: no cancellation when the logarithms are large.
    double sxx = 0, sxy = 0, syy = 0;
    for (size_t i = 0; i < lx.size(); ++i) {
        sxx += (lx[i] - mx) * (lx[i] - mx);
        sxy += (lx[i] - mx) * (ly[i] - my);
        syy += (ly[i] - my) * (ly[i] - my);
    }
    if (lx.size() < 2 || !(sxx > 0))
        throw std::invalid_argument(concat("power-law fit: ", lx.size(), " points with ",
                                           sxx > 0 ? "" : "no ", "distinct x; need two distinct x"));
    PowerLawFit fit;
    fit.points = lx.size();
    fit.exponent = sxy / sxx;
    fit.coefficient = std::exp(my - fit.exponent * mx);
    double residual = 0;
    for (size_t i = 0; i < lx.size(); ++i) {
        const double r = ly[i] - (my + fit.exponent * (lx[i] - mx));
        residual += r * r;
    }
    fit.r2 = syy > 0 ? std::max(0.0, 1.0 - residual / syy) : 1.0;
    return fit;
}

}  // namespace ml
