// The mean of independent, identically distributed estimates and its
// standard error, and the unbiasedness check the sampler tests make of it.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace ml::test {

struct MeanAndError {
    double mean = 0;
    double standardError = 0;  // of the mean, from the samples' own spread (n − 1 in the variance)
};

// Of at least two values.
inline MeanAndError meanOf(const std::vector<double>& v) {
    MeanAndError m;
    for (double x : v) m.mean += x;
    m.mean /= double(v.size());
    double ss = 0;
    for (double x : v) ss += (x - m.mean) * (x - m.mean);
    m.standardError = std::sqrt(ss / double(v.size() - 1) / double(v.size()));
    return m;
}

// `passes`, estimates with fresh seeds, must differ (a sampler that ignores
// its seed has no spread to test with), and their mean must lie within 4
// standard errors of `exact` plus `allowance`, a known offset of the
// expectation (the eye's lift). For an unbiased estimator and a few dozen
// passes, 4 standard errors are exceeded with probability ~1e-4 (Student's
// t); the seeds are fixed, so the outcome is reproducible. `what` names the
// case in a failure.
inline void expectUnbiased(const std::vector<double>& passes, double exact, double allowance,
                           const std::string& what) {
    const MeanAndError m = meanOf(passes);
    EXPECT_GT(m.standardError, 0.0) << what << ": passes did not differ: the seed is ignored";
    EXPECT_LE(std::abs(m.mean - exact), 4 * m.standardError + allowance)
        << what << ": exact " << exact << ", mean " << m.mean << " ± " << m.standardError;
}

}  // namespace ml::test
