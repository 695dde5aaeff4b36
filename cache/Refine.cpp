// Adaptive refinement of the cache meshes: scoring edges and vertices,
// conforming longest-edge bisection, resampling.
//
// What an edge's score means. Irradiance is displayed through exposure and
// a tone curve; people see relative steps (Weber), not absolute ones, and
// nothing in the dark. So every vertex's irradiance is mapped to a display
// level t = 2x/(1+x), x = luminance / white, where white is the irradiance
// the tone curve maps to about 1 (4× the scene's mean: auto exposure puts the
// log-average at 0.18 of white). Then for edge (a, b):
//  - on a smooth signal, linear interpolation misses the midpoint by about
//    h²f''/8, while a vertex's residual against the plane fitted to its
//    neighbours' values is about h²f''/2 (zero for any linear signal): the
//    predicted midpoint error is a quarter of the larger residual of its
//    ends, relative to the local level;
//  - where visibility is partial at an end (the sampler's bits saw a
//    penumbra) or jumps between the ends, the signal may be a step, and the
//    midpoint error is up to half the difference of the ends.
// An edge is split while that predicted error exceeds the split tolerance
// and it is longer than the minimum size; its priority is the error times
// its length (what a viewer sees scales with both), 10× lower outside the
// view when one is given. A vertex is resampled while the standard error of
// its mean (from its samples' spread) exceeds the noise tolerance; one
// sample is trusted unless it saw a penumbra (outside penumbrae the control-
// variate sampler is exact) or its sampler measured its own scatter (a
// gather's rays, the shared mesh's draws among lights). With a sampler
// whose every sample is noisy (CacheSettings::sampleNoise > 0: indirect
// gathers), and wherever samples measured their own scatter, twice a
// vertex's relative standard error is taken off its residual before it
// asks for a split, so noise is resampled away rather than refined into
// the mesh.
#include "IrradianceCache.h"

#include "core/Error.h"
#include "core/TangentPlaneFit.h"
#include "detail/CacheImpl.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ml {

namespace {

using detail::CacheState;
using detail::CacheTriMesh;
using detail::LightMesh;
using detail::toVec3;
using VH = CacheTriMesh::VertexHandle;
using EH = CacheTriMesh::EdgeHandle;
using FH = CacheTriMesh::FaceHandle;
using HH = CacheTriMesh::HalfedgeHandle;

// Display levels below this fraction of white are too dark for steps to show.
constexpr double kDarkFloor = 0.02;
// Priority factor for what lies outside the view, when one is given.
constexpr double kOffViewWeight = 0.1;
// Deepest chain of longest-edge propagation (Rivara's LEPP): a chain
// follows strictly longer edges, so it is short on any sane mesh.
constexpr int kMaxLeppDepth = 48;

double displayLevel(double lum, double white) {
    const double x = std::max(lum, 0.0) / white;
    return 2 * x / (1 + x);
}

// What part of the image an edge or vertex falls in, and how small an edge
// can be seen there.
class ViewMetric {
public:
    ViewMetric(const std::optional<RefinementCamera>& view, double sceneMinLength, double minPixels)
        : sceneMin_(sceneMinLength), minPixels_(minPixels) {
        if (!view) return;
        has_ = true;
        position_ = view->camera.position;
        view->camera.basis(forward_, right_, up_);
        tanY_ = std::tan(glm::radians(view->camera.fovYDegrees) * 0.5);
        tanX_ = tanY_ * double(view->width) / double(view->height);
        height_ = view->height;
    }
    double weight(const Vec3& p) const {
        if (!has_) return 1;
        const Vec3 d = p - position_;
        const double z = glm::dot(d, forward_);
        // 10% margin: what is just outside will be seen when the camera turns.
        const bool inside = z > 0 && std::abs(glm::dot(d, right_)) <= 1.1 * z * tanX_ &&
                            std::abs(glm::dot(d, up_)) <= 1.1 * z * tanY_;
        return inside ? 1.0 : kOffViewWeight;
    }
    double minLength(const Vec3& p) const {
        if (!has_) return sceneMin_;
        const double pixel = 2 * glm::length(p - position_) * tanY_ / height_;
        return std::max(sceneMin_, minPixels_ * pixel);
    }

private:
    bool has_ = false;
    double sceneMin_, minPixels_;
    Vec3 position_{0.0}, forward_{0.0}, right_{0.0}, up_{0.0};
    double tanX_ = 1, tanY_ = 1;
    int height_ = 1;
};

struct Action {
    enum Kind : uint8_t { Split, Resample, ResampleGrid };
    double priority;
    uint32_t mesh;
    Kind kind;
    uint32_t a, b; // edge ends (a < b), or the vertex or grid sample in a
    bool operator<(const Action& o) const {
        if (priority != o.priority) return priority > o.priority;
        return std::tie(mesh, kind, a, b) < std::tie(o.mesh, o.kind, o.a, o.b);
    }
};

struct Scoring {
    double error = 0;
    std::vector<Action> actions;
};

// The area a grid sample stands for: its object's area over its samples.
double gridSampleArea(const CacheState& s, size_t g) {
    const detail::GridObject& o = detail::gridOf(s, g);
    return o.area / double(o.grid->sampleCount());
}

// Mesh l's luminance integrated over its surface (W) and that surface's
// area, from its vertices' means (and its grid samples').
std::pair<double, double> integrated(const CacheState& s, size_t l, const std::vector<double>& areas) {
    double sum = 0, area = 0;
    for (size_t v = 0; v < areas.size(); ++v) {
        sum += areas[v] * luminance(s.meshes[l].stats[v].mean());
        area += areas[v];
    }
    for (size_t g = 0; g < s.gridSamples; ++g) {
        const double a = gridSampleArea(s, g);
        sum += a * luminance(s.meshes[l].gridStats[g].mean());
        area += a;
    }
    return {sum, area};
}

double whiteLevel(const CacheState& s, const std::vector<std::vector<double>>& areas) {
    double total = 0;
    for (size_t l = 0; l < s.meshes.size(); ++l) {
        const auto [sum, area] = integrated(s, l, areas[l]);
        if (area > 0) total += sum / area;
    }
    return 4 * total;
}

// The relative standard error of a vertex's (or grid sample's) mean, as the
// scoring uses it; see the top of this file.
double relativeNoise(const detail::VertexStats& st, const detail::NoiseModel& noise, double white, double own) {
    return std::min(detail::meanNoise(st, noise, own) / (st.meanLuminance() + 0.5 * kDarkFloor * white), 1.0);
}

// The value at vertex v of the plane that fits its neighbours' values best
// (core/TangentPlaneFit.h); none with fewer than three neighbours off one
// line. `points` and `fit` are scratch.
std::optional<double> planeFitAt(const CacheTriMesh& mesh, size_t v, const std::vector<uint32_t>& ring,
                                 const std::vector<double>& value, std::vector<Vec3>& points, TangentPlaneFit& fit) {
    points.clear();
    for (uint32_t u : ring) points.push_back(toVec3(mesh.point(VH(int(u)))));
    if (!fitTangentPlane(toVec3(mesh.point(VH(int(v)))), toVec3(mesh.normal(VH(int(v)))), points, fit))
        return std::nullopt;
    glm::dvec3 b(0.0);
    for (size_t k = 0; k < ring.size(); ++k) b += fit.rows[k] * value[ring[k]];
    return (fit.inverse * b).x;
}

std::vector<double> vertexAreas(const CacheTriMesh& mesh) {
    std::vector<double> area(mesh.n_vertices(), 0.0);
    for (auto f : mesh.faces()) {
        const double a = mesh.calc_face_area(f) / 3;
        for (auto v : mesh.fv_range(f)) area[size_t(v.idx())] += a;
    }
    return area;
}

// Each vertex's residual |E − plane fit of its neighbours| (luminance,
// W·m⁻²); −1 where no plane fits (fewer than three neighbours off one line,
// even over the two-ring). Neighbours in index order, so the sums are the
// same however the mesh's halfedges happen to be numbered (a loaded cache).
void residuals(const CacheTriMesh& mesh, const std::vector<double>& lum, std::vector<double>& out) {
    out.assign(mesh.n_vertices(), -1.0);
    std::vector<uint32_t> ring;
    std::vector<Vec3> points;
    TangentPlaneFit fit;
    for (auto v : mesh.vertices()) {
        ring.clear();
        for (auto u : mesh.vv_range(v)) ring.push_back(uint32_t(u.idx()));
        if (ring.empty()) continue;
        std::sort(ring.begin(), ring.end());
        const size_t vi = size_t(v.idx());
        std::optional<double> value = planeFitAt(mesh, vi, ring, lum, points, fit);
        if (!value) {
            // Too few neighbours off one line (an object's corner): fit the
            // two-ring instead; if even that is a line, no estimate.
            const std::vector<uint32_t> one = ring;
            for (uint32_t u : one)
                for (auto w : mesh.vv_range(VH(int(u))))
                    if (size_t(w.idx()) != vi) ring.push_back(uint32_t(w.idx()));
            std::sort(ring.begin(), ring.end());
            ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
            value = planeFitAt(mesh, vi, ring, lum, points, fit);
            if (!value) continue;
        }
        out[vi] = std::abs(lum[vi] - *value);
    }
}

// Whether the light may step between two ends of an edge `length` long:
// the sampler saw a penumbra at either, or their visibilities differ by
// more than half, or the edge is longer than the reach of either end's
// rays (VertexSample::reach: a surface that near, a contact or a corner,
// can change the light by its own order along the edge; Ward's validity
// radius, which his irradiance cache spaces its records by).
bool mayStep(const detail::VertexStats& a, const detail::VertexStats& b, double length) {
    return a.partial > 0 || b.partial > 0 || std::abs(a.meanVisibility() - b.meanVisibility()) > 0.5 ||
           length > std::min(a.reach(), b.reach());
}

Scoring score(const CacheState& s, const std::optional<RefinementCamera>& view, bool collect) {
    const CacheSettings cs = effectiveSettings(s);
    const detail::NoiseModel noise = detail::noiseModel(s);
    std::vector<std::vector<double>> areas;
    for (const LightMesh& lm : s.meshes) areas.push_back(vertexAreas(lm.mesh));
    Scoring out;
    const double white = whiteLevel(s, areas);
    if (!(white > 0)) return out;  // no light reaches any vertex: nothing to refine
    const ViewMetric metric(view, cs.minEdgeFraction * s.diagonal, cs.minEdgePixels);

    const double uniformEdge = cs.uniformEdgeFraction > 0 ? cs.uniformEdgeFraction * s.diagonal
                                                          : std::numeric_limits<double>::infinity();
    double edgeErr = 0, edgeWeight = 0, noiseErr = 0, noiseWeight = 0;
    std::vector<double> t, lum, lap, res;
    for (size_t l = 0; l < s.meshes.size(); ++l) {
        const LightMesh& lm = s.meshes[l];
        const CacheTriMesh& mesh = lm.mesh;
        const size_t nv = mesh.n_vertices();
        t.resize(nv);
        lum.resize(nv);
        lap.assign(nv, 0.0);
        for (size_t v = 0; v < nv; ++v) {
            lum[v] = luminance(lm.stats[v].mean());
            t[v] = displayLevel(lum[v], white);
        }
        residuals(mesh, lum, res);
        const std::vector<double> own = ringOwnVariances(lm);
        for (size_t vi = 0; vi < nv; ++vi) {
            if (!(res[vi] >= 0)) continue;  // no fit there
            // The residual is an interpolation error in irradiance, where the
            // cache interpolates; it is seen through the tone curve's slope
            // there, dt/dx = 2/(1+x)², relative to the local level.
            const double residual = res[vi] / white;
            const double x = std::max(lum[vi], 0.0) / white;
            lap[vi] = residual * 2 / ((1 + x) * (1 + x)) / (t[vi] + kDarkFloor);
            // With a sampler whose every sample is noisy, a residual within
            // twice the mean's standard error may be noise, not curvature:
            // resampling, not splitting, is what helps there.
            if (cs.sampleNoise > 0 || own[vi] >= 0)
                lap[vi] = std::max(0.0, lap[vi] - 2 * relativeNoise(lm.stats[vi], noise, white, own[vi]));
        }

        for (auto e : mesh.edges()) {
            const HH h = mesh.halfedge_handle(e, 0);
            uint32_t a = uint32_t(mesh.from_vertex_handle(h).idx()), b = uint32_t(mesh.to_vertex_handle(h).idx());
            if (a > b) std::swap(a, b);
            const Vec3 pa = toVec3(mesh.point(VH(int(a)))), pb = toVec3(mesh.point(VH(int(b))));
            const double len = glm::length(pa - pb);
            const Vec3 mid = 0.5 * (pa + pb);
            double predicted = 0.25 * std::max(lap[a], lap[b]);
            if (mayStep(lm.stats[a], lm.stats[b], len)) {
                double step = 0.5 * std::abs(t[a] - t[b]) / (std::max(t[a], t[b]) + kDarkFloor);
                // As for the residual: a difference within twice the ends'
                // standard errors may be noise.
                if (cs.sampleNoise > 0 || (own[a] >= 0 && own[b] >= 0))
                    step = std::max(0.0, step - 2 * std::max(relativeNoise(lm.stats[a], noise, white, own[a]),
                                                             relativeNoise(lm.stats[b], noise, white, own[b])));
                predicted = std::max(predicted, step);
            }
            const bool splittable = len > metric.minLength(mid);
            const double seen = metric.weight(mid);
            edgeWeight += seen * len * len;
            // In the estimate, an edge errs by at most the level shown
            // (what showing nothing or twice the light errs by): beyond, the
            // plane fit is not modelling the light (a vertex beside an
            // emitter, hundreds of times white, makes its dark neighbours'
            // residuals huge). Splits keep the uncapped priority.
            const double counted = std::min(predicted, 1.0);
            if (splittable) edgeErr += seen * len * len * counted * counted;
            if (collect && splittable && predicted > cs.splitTolerance)
                out.actions.push_back({predicted * len / s.diagonal * seen, uint32_t(l), Action::Split, a, b});
            else if (collect && len > uniformEdge && t[a] + t[b] > 0)
                // Split as if its error were at the tolerance: after the
                // edges that measurably need it. However few pixels it
                // spans: the bias is in the light the mesh holds (and that
                // the next bounce reflects), not in detail on screen.
                out.actions.push_back({cs.splitTolerance * len / s.diagonal * seen, uint32_t(l), Action::Split, a, b});
        }

        for (size_t v = 0; v < nv; ++v) {
            const detail::VertexStats& st = lm.stats[v];
            const double rel = relativeNoise(st, noise, white, own[v]);
            const double seen = metric.weight(toVec3(mesh.point(VH(int(v)))));
            noiseErr += seen * areas[l][v] * rel * rel;
            noiseWeight += seen * areas[l][v];
            if (collect && rel > cs.noiseTolerance && st.count < cs.maxSamplesPerVertex)
                out.actions.push_back(
                    {rel * std::sqrt(areas[l][v]) / s.diagonal * seen, uint32_t(l), Action::Resample, uint32_t(v), 0});
        }
        for (size_t g = 0; g < s.gridSamples; ++g) {
            const detail::VertexStats& st = lm.gridStats[g];
            const double rel = relativeNoise(st, noise, white, st.ownUnitVariance()), area = gridSampleArea(s, g);
            const detail::GridObject& o = detail::gridOf(s, g);
            const double seen = metric.weight(o.grid->samplePosition(g - o.firstSample));
            noiseErr += seen * area * rel * rel;
            noiseWeight += seen * area;
            if (collect && rel > cs.noiseTolerance && st.count < cs.maxSamplesPerVertex)
                out.actions.push_back(
                    {rel * std::sqrt(area) / s.diagonal * seen, uint32_t(l), Action::ResampleGrid, uint32_t(g), 0});
        }
    }
    // Each mesh's errors are relative to its own light's level there: where
    // several lights add up, the relative error of their sum is at most the
    // RMS of theirs (equal at a place one light dominates, as the light
    // meshes' coverage arranges), so the estimate is the RMS over every
    // mesh's surface. (It was multiplied by the number of meshes, as if
    // each were relative to the total: the office's 13 direct meshes read
    // 10.7% at 16 s where the whole image measured 4.7%; 3.3% now.)
    const double edgeRms = edgeWeight > 0 ? std::sqrt(edgeErr / edgeWeight) : 0.0;
    const double noiseRms = noiseWeight > 0 ? std::sqrt(noiseErr / noiseWeight) : 0.0;
    out.error = std::hypot(edgeRms, noiseRms);
    return out;
}

// Conforming longest-edge bisection of one face (Rivara's LEPP): its longest
// edge is split, after the face across that edge has been refined until
// that edge is its longest too, so no split ever makes a T-vertex or halves
// a face across anything but its longest edge.
class Bisector {
public:
    Bisector(CacheTriMesh& mesh, std::vector<char>& touched) : mesh_(mesh), touched_(touched) {}

    size_t refineFace(FH f, int depth = 0) {
        size_t added = 0;
        for (int guard = 0; guard < 4 * kMaxLeppDepth; ++guard) {
            const HH hl = longestHalfedge(f);
            const FH g = mesh_.opposite_face_handle(hl);
            if (g.is_valid() && depth < kMaxLeppDepth) {
                const HH hg = longestHalfedge(g);
                if (mesh_.edge_handle(hg) != mesh_.edge_handle(hl) && length(hg) > length(hl)) {
                    added += refineFace(g, depth + 1);
                    continue;  // f is untouched: the chain only climbs to longer edges
                }
            }
            const VH mid = detail::splitAtMidpoint(mesh_, mesh_.edge_handle(hl));
            touched_.resize(mesh_.n_faces(), 0);
            for (auto vf : mesh_.vf_range(mid)) touched_[size_t(vf.idx())] = 1;
            return added + 1;
        }
        ML_ASSERT(false, "longest-edge bisection did not terminate at face ", f.idx());
        return added;
    }

private:
    double length(HH h) const {
        return (mesh_.point(mesh_.to_vertex_handle(h)) - mesh_.point(mesh_.from_vertex_handle(h))).norm();
    }
    // The longest edge of f; ties go to the smaller (min, max) vertex pair,
    // so the choice does not depend on halfedge numbering.
    HH longestHalfedge(FH f) const {
        HH best;
        double bestLen = -1;
        std::pair<int, int> bestKey{0, 0};
        for (auto h : mesh_.fh_range(f)) {
            const int a = mesh_.from_vertex_handle(h).idx(), b = mesh_.to_vertex_handle(h).idx();
            const std::pair<int, int> key{std::min(a, b), std::max(a, b)};
            const double len = length(h);
            if (len > bestLen || (len == bestLen && key < bestKey)) best = h, bestLen = len, bestKey = key;
        }
        return best;
    }

    CacheTriMesh& mesh_;
    std::vector<char>& touched_;
};

bool isTouched(const std::vector<char>& touched, FH f) {
    return f.is_valid() && size_t(f.idx()) < touched.size() && touched[size_t(f.idx())];
}

}  // namespace

double IrradianceCache::integratedLuminance() const {
    const CacheState& s = impl_->state;
    double total = 0;
    for (size_t l = 0; l < s.meshes.size(); ++l) total += integrated(s, l, vertexAreas(s.meshes[l].mesh)).first;
    return total;
}

double IrradianceCache::sharedLuminance() const {
    const CacheState& s = impl_->state;
    if (!s.sharedMesh || s.meshes.empty()) return 0;
    const size_t l = s.meshes.size() - 1;
    return integrated(s, l, vertexAreas(s.meshes[l].mesh)).first;
}

double IrradianceCache::estimatedError(const std::optional<RefinementCamera>& view) const {
    if (detail::unsampledCount(impl_->state) > 0) return 1;  // not every vertex sampled yet: unknown
    return score(impl_->state, view, false).error;
}

void IrradianceCache::setInterrupt(std::function<bool()> interrupted) { impl_->interrupt = std::move(interrupted); }

void IrradianceCache::setNoiseProbes(size_t every) { impl_->state.noiseProbeEvery = every; }

RefineReport IrradianceCache::refine(VertexSampler& sampler, size_t budget, uint32_t seed,
                                     const std::optional<RefinementCamera>& view) {
    ML_ASSERT(budget > 0, "refinement budget 0");
    CacheState& s = impl_->state;
    RefineReport report;
    // The score needs every vertex sampled: first, rounds of `budget` of
    // the vertices that have no sample yet (the base mesh, in (light,
    // vertex) order), so that a round stays short and snapshots keep coming.
    const size_t unsampled = detail::unsampledCount(s);
    if (unsampled > 0) {
        report.estimatedError = 1;
        const FirstSamples first(sampler);
        report.estimates = detail::sampleUnsampled(s, sampler, seed, budget, impl_->interrupt);
        // At least the scoring is still to come (estimates also count noise probes).
        report.candidates = detail::unsampledCount(s) + 1;
        ++s.rounds;
        return report;
    }

    Scoring scoring = score(s, view, true);
    report.estimatedError = scoring.error;
    report.candidates = scoring.actions.size();
    std::sort(scoring.actions.begin(), scoring.actions.end());

    const size_t perVertex = bytesPerVertex();
    size_t vertices = totalVertices(), cost = 0;
    std::vector<std::vector<char>> touched(s.meshes.size());
    std::vector<std::pair<uint32_t, uint32_t>> resample, resampleGrid;  // (mesh, vertex or grid sample)
    for (const Action& act : scoring.actions) {
        if (cost >= budget) break;
        LightMesh& lm = s.meshes[act.mesh];
        if (act.kind != Action::Split) {
            (act.kind == Action::Resample ? resample : resampleGrid).emplace_back(act.mesh, act.a);
            cost += 1;
            continue;
        }
        if (vertices + 2 > s.settings.maxVertices || (vertices + 2) * perVertex > s.settings.maxMemoryBytes)
            continue;  // out of budget for new vertices; resamples may go on
        const HH h = lm.mesh.find_halfedge(VH(int(act.a)), VH(int(act.b)));
        if (!h.is_valid()) continue;  // split already this round
        std::vector<char>& t = touched[act.mesh];
        FH faces[2] = {lm.mesh.face_handle(h), lm.mesh.opposite_face_handle(h)};
        if (isTouched(t, faces[0]) || isTouched(t, faces[1])) continue;  // refined already this round
        // The faces in the order of their third vertex, not of halfedge numbering.
        auto third = [&](HH hh) { return lm.mesh.to_vertex_handle(lm.mesh.next_halfedge_handle(hh)).idx(); };
        if (faces[0].is_valid() && faces[1].is_valid() && third(lm.mesh.opposite_halfedge_handle(h)) < third(h))
            std::swap(faces[0], faces[1]);
        Bisector bisector(lm.mesh, t);
        size_t added = 0;
        for (FH f : faces) {
            if (!f.is_valid() || isTouched(t, f)) continue;
            added += bisector.refineFace(f);
        }
        lm.stats.resize(lm.mesh.n_vertices());
        vertices += added;
        report.splits += added;
        cost += added;
    }

    // The vertices the splits made, whole even when interrupted: a cache
    // left with unsampled vertices has no estimate of its error.
    report.estimates += detail::sampleUnsampled(s, sampler, seed, ~size_t(0));
    // Resamples in one batch: (mesh, vertex) order, vertices before grid samples.
    std::sort(resample.begin(), resample.end());
    std::sort(resampleGrid.begin(), resampleGrid.end());
    std::vector<detail::PendingSample> pending;
    for (const auto& [l, v] : resample) pending.push_back({l, v, false});
    for (const auto& [l, g] : resampleGrid) pending.push_back({l, g, true});
    const size_t resampled = detail::takeSamples(s, sampler, seed, pending, impl_->interrupt);
    report.estimates += resampled;
    report.resamples += resampled;
    ++s.rounds;
    return report;
}


namespace detail {

std::vector<double> ringOwnVariances(const LightMesh& lm) {
    const CacheTriMesh& mesh = lm.mesh;
    std::vector<double> out(mesh.n_vertices(), -1.0);
    for (auto v : mesh.vertices()) {
        const double own = lm.stats[size_t(v.idx())].ownUnitVariance();
        if (own < 0) continue;
        double sum = own, n = 1;
        for (auto u : mesh.vv_range(v)) {
            const double o = lm.stats[size_t(u.idx())].ownUnitVariance();
            if (o >= 0) sum += o, n += 1;
        }
        out[size_t(v.idx())] = std::max(own, sum / n);
    }
    return out;
}

double meanNoise(const VertexStats& st, const NoiseModel& m, double own) {
    // Samples that measured their own variance: it, scaled to what the
    // cache's resampled vertices measure, and the vertex's own spread
    // between its samples, each by its degrees of freedom.
    if (st.ownUnitVariance() >= 0 && own >= 0 && m.ownScale >= 0) {
        const double unit = (st.spread() + kOwnVarianceFreedom * m.ownScale * own) /
                            (double(st.count - 1) + kOwnVarianceFreedom);
        return std::sqrt(std::max(unit, 0.0) / st.work);
    }
    if (st.count >= 2) return std::sqrt(st.meanVariance());
    // A penumbra seen once: its spread is unknown, so assume the sampler's
    // per-sample error relative to the unoccluded irradiance (E / visibility).
    const double mean = st.meanLuminance();
    if (st.count == 1 && st.partial) return m.singleSampleNoise * mean / std::max(st.sumVisibility, 0.01);
    // A sampler whose every sample is noisy (a jittered gather); a cheaper
    // one (a first pass's gather of fewer rays) more so.
    if (st.count == 1 && m.sampleNoise > 0)
        return m.sampleNoise * mean * (m.fullWork > st.work ? std::sqrt(m.fullWork / st.work) : 1.0);
    return 0;
}

std::vector<double> predictedErrors(const CacheState& s, size_t l, const std::vector<double>& lum,
                                    const NoiseModel& noise, const std::vector<double>& own,
                                    std::vector<double>* vertexNoise) {
    const LightMesh& lm = s.meshes[l];
    const CacheTriMesh& mesh = lm.mesh;
    const size_t nv = mesh.n_vertices();
    ML_ASSERT(lum.size() == nv && own.size() == nv, lum.size(), " values and ", own.size(), " own variances for ",
              nv, " vertices");
    std::vector<double> res, sumSq(nv, 0.0), edges(nv, 0.0);
    residuals(mesh, lum, res);
    // A residual is the plane fit's miss at the vertex. Where the ring lies
    // to one side (a wall's corner, valence 2 or 3) the fit extrapolates
    // and its miss can be many times any difference the vertex has with
    // its neighbours: the Cornell box's bounce 1 on its 1/20 base had a
    // corner vertex with a residual of 8 times its light, which predicted
    // 1.31% of the 256×256 image's error in one corner where the image
    // measured 1.12% in all (1.05% predicted with this). No more than the
    // largest such difference, then: a smooth bump's miss is about that.
    for (auto vh : mesh.vertices()) {
        const size_t v = size_t(vh.idx());
        double range = 0;
        for (auto u : mesh.vv_range(vh)) range = std::max(range, std::abs(lum[v] - lum[size_t(u.idx())]));
        res[v] = std::min(res[v], range);
    }
    // Linear interpolation of a smooth signal errs most at an edge's
    // midpoint, by a quarter of the larger residual of its ends (see the
    // top of this file), and by e·4t(1−t) along it: an RMS of e·√(8/15) =
    // 0.73e. A step interpolated linearly across an edge errs by |t − H| of
    // the step's size Δ: an RMS of Δ/√12 = 0.29Δ.
    constexpr double kSmoothRms = 0.7303, kStepRms = 0.2887;
    for (auto e : mesh.edges()) {
        const HH h = mesh.halfedge_handle(e, 0);
        const size_t a = size_t(mesh.from_vertex_handle(h).idx()), b = size_t(mesh.to_vertex_handle(h).idx());
        double err = kSmoothRms * 0.25 * std::max({res[a], res[b], 0.0});
        // Steps the sampler saw (penumbrae, visibility jumps), not those
        // the reach only allows: an edge longer than its ends' reach is a
        // reason to split it while it can be split (score), not an error
        // seen; at a corner, where the reach tends to zero, it would stay
        // counted below the smallest edge refinement makes.
        if (mayStep(lm.stats[a], lm.stats[b], 0.0)) err = std::max(err, kStepRms * std::abs(lum[a] - lum[b]));
        for (size_t v : {a, b}) sumSq[v] += err * err, edges[v] += 1;
    }
    std::vector<double> out(nv, 0.0);
    if (vertexNoise) vertexNoise->assign(nv, 0.0);
    for (size_t v = 0; v < nv; ++v) {
        const double interpolation = edges[v] > 0 ? sumSq[v] / edges[v] : 0.0;
        // A vertex not sampled yet shows its neighbours' light (copyMesh):
        // a guess, assumed off by kGuessedLightError of itself.
        const bool sampled = lm.stats[v].count > 0;
        const double vertexError =
            sampled ? meanNoise(lm.stats[v], noise, own[v]) : kGuessedLightError * std::max(lum[v], 0.0);
        out[v] = std::sqrt(interpolation + vertexError * vertexError);
        if (vertexNoise && sampled) (*vertexNoise)[v] = vertexError;
    }
    return out;
}

}  // namespace detail

}  // namespace ml
