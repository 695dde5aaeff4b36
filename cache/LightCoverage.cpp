#include "LightCoverage.h"

#include "core/Error.h"

#include <algorithm>
#include <cmath>

namespace ml {

namespace {

// w_l rises from 0 at s_l = kRampStart·τ to 1 at τ (LightCoverage.h).
constexpr double kRampStart = 0.8;

// B_l(p) of LightCoverage.h, up to the common factor 1/π. A punctual light's
// is π times its unoccluded irradiance on a surface facing it: its intensity
// toward p over the squared distance (in metres), or a directional light's
// irradiance, the same everywhere.
double largest(const Rgb& c) { return std::max({c.r, c.g, c.b}); }

double bound(const Light& light, const Vec3& p) {
    if (light.kind == LightKind::Directional) return kPi * largest(light.emission.intensity);
    if (light.kind == LightKind::Point) {
        const PunctualEmission& e = light.emission;
        const Vec3 v = p - e.position;
        const double d = glm::length(v);
        const double i = largest(d > 0 ? e.intensityToward(v / d) : e.intensity);
        const double m = std::max(d, e.minDistance) * e.metresPerUnit;
        return kPi * i / (m * m);
    }
    const double power = std::max({light.power().r, light.power().g, light.power().b});
    if (!(power > 0)) return 0;
    const Vec3 v = p - light.centroid;
    const double d = glm::length(v), r = std::sqrt(light.area / kPi);
    const double facing = light.planar ? std::max(0.0, (glm::dot(light.normal, v) + r) / (d + r)) : 1.0;
    return power * facing / (d * d + r * r);
}

}  // namespace

LightCoverage::LightCoverage(const Scene& scene, double share, const std::vector<char>& gatheredLights, int resolution)
    : lights_(scene.lights.size()), share_(share), gathered_(gatheredLights) {
    if (!gathered_.empty() && gathered_.size() != lights_)
        throw InputError(concat("gathered lights: ", gathered_.size(), " flags for ", lights_, " lights"));
    if (!(share >= 0 && share <= 1)) throw InputError(concat("light share ", share, " is not in [0, 1]"));
    if (resolution < 1) throw InputError(concat("light coverage grid of ", resolution, " cells"));
    const Bounds3& b = scene.bounds;
    const Vec3 extent = glm::max(b.hi - b.lo, Vec3(0.0));
    const double longest = std::max({extent.x, extent.y, extent.z, 1e-30});
    cellSize_ = longest / resolution;
    // Half a cell of margin: points a hair outside the bounds still interpolate.
    origin_ = b.lo - Vec3(0.5 * cellSize_);
    for (int a = 0; a < 3; ++a) dims_[a] = std::max(1, int(std::ceil(extent[a] / cellSize_ + 1.0)));
    const size_t nodes = size_t(dims_[0] + 1) * size_t(dims_[1] + 1) * size_t(dims_[2] + 1);
    offsets_.assign(nodes + 1, 0);
    cellCovered_.assign(lights_, {});
    if (lights_ == 0) return;

    // Σ_k B_k at every node, and its mean over the nodes: the scene's
    // typical level. A light's share is taken of the local total, but of no
    // less than a quarter of that level: where little direct light arrives
    // at all (behind the lights, the ceiling around them) no light needs a
    // mesh of its own for the little it gives.
    std::vector<double> totals(nodes, 0.0);
    double level = 0;
    for (int k = 0; k <= dims_[2]; ++k)
        for (int j = 0; j <= dims_[1]; ++j)
            for (int i = 0; i <= dims_[0]; ++i) {
                const Vec3 p = origin_ + cellSize_ * Vec3(i, j, k);
                double& total = totals[node(i, j, k)];
                for (size_t l = 0; l < lights_; ++l)
                    if (!gathered(l)) total += bound(scene.lights[l], p);
                level += total;
            }
    const double floor = 0.25 * level / double(nodes);
    std::vector<std::vector<bool>> nodeCovered(lights_, std::vector<bool>(nodes, false));
    for (int k = 0; k <= dims_[2]; ++k)
        for (int j = 0; j <= dims_[1]; ++j)
            for (int i = 0; i <= dims_[0]; ++i) {
                const size_t n = node(i, j, k);
                const Vec3 p = origin_ + cellSize_ * Vec3(i, j, k);
                const double total = std::max(totals[n], floor);
                offsets_[n] = uint32_t(nodeLights_.size());
                for (size_t l = 0; l < lights_; ++l) {
                    if (gathered(l)) continue;  // w = 0, and not the shared mesh's either
                    // No light at all (no power anywhere): every light keeps
                    // its own, zero.
                    const double s = total > 0 ? bound(scene.lights[l], p) / total : 1.0;
                    const double w =
                        share_ > 0 ? std::clamp((s - kRampStart * share_) / ((1 - kRampStart) * share_), 0.0, 1.0) : 1.0;
                    if (w <= 0) {
                        sharing_ = true;
                        continue;
                    }
                    if (w < 1) sharing_ = true;
                    nodeLights_.push_back(uint32_t(l));
                    nodeWeights_.push_back(float(w));
                    nodeCovered[l][n] = true;
                }
            }
    offsets_[nodes] = uint32_t(nodeLights_.size());
    const size_t cells = size_t(dims_[0]) * size_t(dims_[1]) * size_t(dims_[2]);
    for (size_t l = 0; l < lights_; ++l) {
        std::vector<bool>& covered = cellCovered_[l];
        covered.assign(cells, false);
        for (int k = 0; k < dims_[2]; ++k)
            for (int j = 0; j < dims_[1]; ++j)
                for (int i = 0; i < dims_[0]; ++i) {
                    bool any = false;
                    for (int c = 0; c < 8 && !any; ++c)
                        any = nodeCovered[l][node(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))];
                    covered[(size_t(k) * size_t(dims_[1]) + size_t(j)) * size_t(dims_[0]) + size_t(i)] = any;
                }
    }
}

void LightCoverage::locate(const Vec3& x, int cell[3], double t[3]) const {
    for (int a = 0; a < 3; ++a) {
        const double u = std::clamp((x[a] - origin_[a]) / cellSize_, 0.0, double(dims_[a]));
        cell[a] = std::min(int(u), dims_[a] - 1);
        t[a] = u - cell[a];
    }
}

double LightCoverage::weight(size_t light, const Vec3& x) const {
    if (!sharing_) return gathered(light) ? 0.0 : 1.0;
    int c[3];
    double t[3];
    locate(x, c, t);
    double w = 0;
    for (int corner = 0; corner < 8; ++corner) {
        const int di = corner & 1, dj = (corner >> 1) & 1, dk = (corner >> 2) & 1;
        const double f = (di ? t[0] : 1 - t[0]) * (dj ? t[1] : 1 - t[1]) * (dk ? t[2] : 1 - t[2]);
        if (f == 0) continue;
        const size_t n = node(c[0] + di, c[1] + dj, c[2] + dk);
        const auto first = nodeLights_.begin() + offsets_[n], last = nodeLights_.begin() + offsets_[n + 1];
        const auto it = std::lower_bound(first, last, uint32_t(light));
        if (it != last && *it == light) w += f * double(nodeWeights_[size_t(it - nodeLights_.begin())]);
    }
    return std::min(w, 1.0);
}

void LightCoverage::weights(const Vec3& x, std::vector<std::pair<uint32_t, double>>& out) const {
    out.clear();
    if (!sharing_) {
        for (size_t l = 0; l < lights_; ++l)
            if (!gathered(l)) out.emplace_back(uint32_t(l), 1.0);
        return;
    }
    int c[3];
    double t[3];
    locate(x, c, t);
    for (int corner = 0; corner < 8; ++corner) {
        const int di = corner & 1, dj = (corner >> 1) & 1, dk = (corner >> 2) & 1;
        const double f = (di ? t[0] : 1 - t[0]) * (dj ? t[1] : 1 - t[1]) * (dk ? t[2] : 1 - t[2]);
        if (f == 0) continue;
        const size_t n = node(c[0] + di, c[1] + dj, c[2] + dk);
        for (uint32_t e = offsets_[n]; e < offsets_[n + 1]; ++e) out.emplace_back(nodeLights_[e], f * double(nodeWeights_[e]));
    }
    // Merge the corners' entries per light, in light order.
    std::sort(out.begin(), out.end());
    size_t kept = 0;
    for (size_t i = 0; i < out.size(); ++i) {
        if (kept > 0 && out[kept - 1].first == out[i].first) out[kept - 1].second += out[i].second;
        else out[kept++] = out[i];
    }
    out.resize(kept);
    for (auto& [l, w] : out) w = std::min(w, 1.0);
}

bool LightCoverage::covers(size_t light, const Triangle3& tri) const {
    if (!sharing_) return !gathered(light);
    Vec3 lo = glm::min(tri[0], glm::min(tri[1], tri[2])), hi = glm::max(tri[0], glm::max(tri[1], tri[2]));
    int clo[3], chi[3];
    double t[3];
    locate(lo, clo, t);
    locate(hi, chi, t);
    const std::vector<bool>& covered = cellCovered_[light];
    for (int k = clo[2]; k <= chi[2]; ++k)
        for (int j = clo[1]; j <= chi[1]; ++j)
            for (int i = clo[0]; i <= chi[0]; ++i)
                if (covered[(size_t(k) * size_t(dims_[1]) + size_t(j)) * size_t(dims_[0]) + size_t(i)]) return true;
    return false;
}

double LightCoverage::coveredFraction(size_t light) const {
    if (!sharing_) return gathered(light) ? 0.0 : 1.0;
    const std::vector<bool>& covered = cellCovered_.at(light);
    return covered.empty() ? 0.0 : double(std::count(covered.begin(), covered.end(), true)) / double(covered.size());
}

std::string LightCoverage::describe() const {
    if (lights_ == 0) return "no lights";
    const size_t sampled = lights_ - size_t(std::count(gathered_.begin(), gathered_.end(), 1));
    const std::string gatheredNote =
        sampled < lights_ ? concat(" (", lights_ - sampled, " gathered lights have none)") : std::string();
    if (!sharing_)
        return concat("every light's mesh covers the whole scene (each gives at least ", 100 * share_,
                      "% of the direct light everywhere by its power bound)", gatheredNote);
    double sum = 0, lo = 1, hi = 0;
    for (size_t l = 0; l < lights_; ++l) {
        if (gathered(l)) continue;
        const double f = coveredFraction(l);
        sum += f, lo = std::min(lo, f), hi = std::max(hi, f);
    }
    char line[256];
    std::snprintf(line, sizeof line,
                  "%zu lights: each keeps a mesh of its own where it gives at least %.3g%% of the direct light (by "
                  "a bound from power, distance and orientation), over %.0f%% of the scene's grid cells on average "
                  "(%.0f..%.0f%%); the rest of their light goes to one shared mesh",
                  sampled, 100 * share_, 100 * sum / double(std::max<size_t>(sampled, 1)), 100 * lo, 100 * hi);
    return line + gatheredNote;
}

}  // namespace ml
