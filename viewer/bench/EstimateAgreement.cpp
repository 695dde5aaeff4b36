#include "EstimateAgreement.h"

#include "core/Error.h"

#include <algorithm>

namespace ml {

EstimateAgreement estimateAgreement(const std::vector<EstimatePoint>& points, double high, double low) {
    EstimateAgreement a;
    for (const EstimatePoint& p : points) {
        if (!(p.estimate > 0 && p.estimate < 1) || !(p.measured > 0) || p.measured > high || p.measured < low)
            continue;
        const double factor = std::max(p.estimate / p.measured, p.measured / p.estimate);
        ++a.images;
        if (factor > a.worst) a.worst = factor, a.worstAt = p.seconds;
    }
    return a;
}

BenchTarget estimateTarget(const std::string& name, const EstimateAgreement& a, double factor) {
    if (a.images == 0) return {name, "no image in that range", "not measured"};
    return {name,
            concat("worst ", benchNumber(a.worst), "x (the image at ", benchNumber(a.worstAt), " s) over ", a.images,
                   a.images == 1 ? " image" : " images"),
            a.worst <= factor ? "met" : "not met"};
}

BenchTarget issueEstimateTarget(const std::string& prefix, const std::vector<EstimatePoint>& points) {
    return estimateTarget(concat(prefix, "the image's error estimate within ", kEstimateFactor, "x of the measured from ",
                                 benchPct(kEstimateRange[0]), "% down to ", benchPct(kEstimateRange[1]), "%"),
                          estimateAgreement(points, kEstimateRange[0], kEstimateRange[1]), kEstimateFactor);
}

}  // namespace ml
