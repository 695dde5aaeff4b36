// How a cost grows: the exponent b of y ≈ a·x^b, fitted by least squares on
// (ln x, ln y), i.e. the slope of the straight line through a log-log plot.
#pragma once

#include <cstddef>
#include <vector>

namespace ml {

struct PowerLawFit {
    double exponent = 0;     // b: 1 is linear growth, 0 constant, 0.5 square-root
    double coefficient = 0;  // a, in y's unit at x = 1
    // Coefficient of determination of the log-log line, in [0, 1]; 1 when
    // every point lies on it (also when all y are equal).
    double r2 = 0;
    size_t points = 0;       // (x, y) pairs fitted

    double at(double x) const;  // a·x^b
};

// Throws std::invalid_argument when x and y differ in length, when a value
// is not finite and positive, or when fewer than two distinct x are given
// (the slope is then undefined).
PowerLawFit fitPowerLaw(const std::vector<double>& x, const std::vector<double>& y);

}  // namespace ml
