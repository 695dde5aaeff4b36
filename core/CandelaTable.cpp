#include "core/CandelaTable.h"

#include "core/Error.h"
#include "core/Math.h"

#include <algorithm>
#include <cmath>

namespace ml {

namespace {

constexpr double kDegree = kPi / 180;
// Two angles closer than this (degrees) are one after mirroring: mirrored
// angles differ from the stored ones by rounding only (the loaders refuse
// steps below 1e-6 degrees).
constexpr double kSameAngle = 1e-9;

// An angle in [0, 360).
double wrapDegrees(double c) {
    double w = std::fmod(c, 360.0);
    if (w < 0) w += 360;
    return w >= 360 - kSameAngle ? 0 : w;
}

// Index of the stored angle within kSameAngle of `c`, or -1.
long findAngle(const std::vector<double>& angles, double c) {
    const auto it = std::lower_bound(angles.begin(), angles.end(), c - kSameAngle);
    if (it != angles.end() && std::abs(*it - c) <= kSameAngle) return long(it - angles.begin());
    return -1;
}

// ∫ hat_i(γ) sin γ dγ over [a, b] (radians) for the hat that is 1 at b and 0
// at a (rising) or 1 at a and 0 at b (falling), in forms that keep their
// precision when b - a is tiny: with m the midpoint and h the half width,
//   rising  = (cos m (sin h - h cos h) + h sin m sin h) / h
//   falling = (-cos m (sin h - h cos h) + h sin m sin h) / h.
void hatIntegrals(double a, double b, double& rising, double& falling) {
    const double m = (a + b) / 2, h = (b - a) / 2;
    if (h <= 0) {
        rising = falling = 0;
        return;
    }
    const double h2 = h * h;
    // sin h - h cos h = h³/3 - h⁵/30 + h⁷/840 - ...: the series where the
    // difference would cancel.
    const double s = h < 1e-2 ? h * h2 * (1.0 / 3 - h2 * (1.0 / 30 - h2 / 840)) : std::sin(h) - h * std::cos(h);
    const double odd = std::cos(m) * s / h, even = std::sin(m) * std::sin(h);
    rising = std::max(0.0, odd + even);
    falling = std::max(0.0, even - odd);
}

}  // namespace

double CandelaTable::intensity(double gammaDeg, double cDeg) const {
    const size_t ng = gamma.size();
    if (ng == 0 || c.empty() || !(gammaDeg >= gamma.front() && gammaDeg <= gamma.back()) || !std::isfinite(cDeg))
        return 0;
    // Gamma: the interval [g0, g0 + 1] holding gammaDeg, weight tg of g0 + 1.
    size_t g0 = 0;
    double tg = 0;
    if (ng > 1) {
        g0 = size_t(std::upper_bound(gamma.begin(), gamma.end(), gammaDeg) - gamma.begin());
        g0 = std::min(g0 == 0 ? 0 : g0 - 1, ng - 2);
        tg = (gammaDeg - gamma[g0]) / (gamma[g0 + 1] - gamma[g0]);
    }
    const auto column = [&](size_t ci) {
        const double* v = &candela[ci * ng + g0];
        return ng > 1 ? v[0] + tg * (v[1] - v[0]) : v[0];
    };
    if (c.size() == 1) return column(0);
    // C: periodic; the last plane interpolates towards C0 at 360.
    const double w = wrapDegrees(cDeg);
    size_t c0 = size_t(std::upper_bound(c.begin(), c.end(), w) - c.begin());
    c0 = c0 == 0 ? 0 : c0 - 1;
    const size_t c1 = c0 + 1 == c.size() ? 0 : c0 + 1;
    const double upper = c1 == 0 ? 360 : c[c1];
    const double tc = std::clamp((w - c[c0]) / (upper - c[c0]), 0.0, 1.0);
    const double a = column(c0), b = column(c1);
    return a + tc * (b - a);
}

double CandelaTable::maxIntensity() const {
    return candela.empty() ? 0 : *std::max_element(candela.begin(), candela.end());
}

double CandelaTable::flux() const {
    const size_t ng = gamma.size(), nc = c.size();
    if (ng < 2 || nc == 0) return 0;
    // The interpolant is a sum of products hat_c(c) hat_g(γ) × value, so its
    // integral is Σ value × (∫ hat_c dc) × (∫ hat_g sin γ dγ): exact.
    std::vector<double> wg(ng, 0.0);
    for (size_t i = 0; i + 1 < ng; ++i) {
        double rising, falling;
        hatIntegrals(gamma[i] * kDegree, gamma[i + 1] * kDegree, rising, falling);
        wg[i] += falling;
        wg[i + 1] += rising;
    }
    double sum = 0;
    for (size_t j = 0; j < nc; ++j) {
        // ∫ hat_c dc: half of each neighbouring interval (periodic), radians.
        double wc = 2 * kPi;
        if (nc > 1) {
            const double next = j + 1 == nc ? 360 : c[j + 1];
            const double prev = j == 0 ? c[nc - 1] - 360 : c[j - 1];
            wc = (next - prev) / 2 * kDegree;
        }
        double column = 0;
        for (size_t i = 0; i < ng; ++i) column += wg[i] * candela[j * ng + i];
        sum += wc * column;
    }
    return sum;
}

void expandCSymmetry(CandelaTable& table, const std::vector<double>& storedC,
                     const std::vector<double>& storedCandela, CSymmetry symmetry) {
    const size_t ng = table.gamma.size();
    ML_ASSERT(!storedC.empty() && storedCandela.size() == storedC.size() * ng, storedC.size(), " planes, ",
              storedCandela.size(), " values");
    table.c.clear();
    table.candela.clear();
    if (symmetry == CSymmetry::Rotational) {
        table.c = {0.0};
        table.candela.assign(storedCandela.begin(), storedCandela.begin() + long(ng));
        return;
    }
    // The mirrors the symmetry adds; each is its own inverse, and together
    // with the identity they form a group, so a full-circle angle made from a
    // stored one by a mirror goes back to it by the same mirror.
    using Mirror = double (*)(double);
    const Mirror identity = [](double x) { return x; };
    const Mirror aboutC0 = [](double x) { return -x; };
    const Mirror aboutC90 = [](double x) { return 180 - x; };
    const Mirror both = [](double x) { return 180 + x; };
    std::vector<Mirror> mirrors = {identity};
    if (symmetry == CSymmetry::Quadrant) mirrors.insert(mirrors.end(), {aboutC0, aboutC90, both});
    if (symmetry == CSymmetry::BilateralC0C180) mirrors.push_back(aboutC0);
    if (symmetry == CSymmetry::BilateralC90C270) mirrors.push_back(aboutC90);

    std::vector<double> all;
    for (double s : storedC)
        for (auto mirror : mirrors) all.push_back(wrapDegrees(mirror(s)));
    std::sort(all.begin(), all.end());
    for (double a : all)
        if (table.c.empty() || a - table.c.back() > kSameAngle) table.c.push_back(a);
    if (table.c.size() > 1 && table.c.back() >= 360 - kSameAngle) table.c.pop_back();

    table.candela.reserve(table.c.size() * ng);
    for (double a : table.c) {
        long source = -1;
        for (auto mirror : mirrors) {
            const double m = wrapDegrees(mirror(a));
            source = findAngle(storedC, m);
            // 0 and 360 are one angle: a stored 360 (Full) stands for C0.
            if (source < 0 && m < kSameAngle) source = findAngle(storedC, 360.0);
            if (source >= 0) break;
        }
        ML_ASSERT(source >= 0, "no stored plane mirrors C", a);
        const auto first = storedCandela.begin() + source * long(ng);
        table.candela.insert(table.candela.end(), first, first + long(ng));
    }
    // Stored 90..270 without 180 mirrors to no C0: add it, interpolated
    // between its neighbours across 360, which leaves the interpolant as it was.
    if (table.c.front() > 0) {
        const double below = table.c.back() - 360, above = table.c.front();
        const double t = (0 - below) / (above - below);
        std::vector<double> plane(ng);
        for (size_t i = 0; i < ng; ++i) {
            const double a = table.candela[(table.c.size() - 1) * ng + i], b = table.candela[i];
            plane[i] = a + t * (b - a);
        }
        table.c.insert(table.c.begin(), 0.0);
        table.candela.insert(table.candela.begin(), plane.begin(), plane.end());
    }
}

}  // namespace ml
