#include "PropagationVolume.h"

#include "IrradianceVolume.h"
#include "RadianceProxy.h"
#include "RayGather.h"
#include "core/Error.h"
#include "core/MeshUtil.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace ml {

void PropagationVolumeSettings::validate() const {
    if (cells < 2 || cells > 128)
        throw InputError(concat("propagation volume: ", cells, " cells along the longest side is not within 2..128"));
    if (iterations < 0 || iterations > 4096)
        throw InputError(concat("propagation volume: ", iterations, " iterations is not within 0..4096 (0: the "
                                "grid's own count)"));
}

std::array<double, kShCoefficients> shCosineLobeProjection(const Vec3& n) {
    std::array<double, kShCoefficients> y = shBasis(n);
    for (int i = 0; i < kShCoefficients; ++i) y[size_t(i)] *= shCosineLobe(shBand(i));
    return y;
}

// --- The transfer between neighbours ----------------------------------------------------

namespace {

// ∫ Y_0 dω over the sphere: a field's flux is its band-0 coefficient times this.
const double kFluxOfBand0 = 2 * std::sqrt(kPi);

// Cube-map quadrature of the 30 parts: 96 texels a face puts the far face's
// edges (|u| = 1/3 of the face) on texel edges; the texels the diagonal
// |u| = |v| cuts in two are shared half and half, as the diagonal halves
// them. Which part a texel belongs to never changes the sum over all 30,
// ∫ Y_i over the sphere, so flux is conserved whatever the quadrature's
// error; that error (higher bands at the parts' edges) only shapes where
// each part's flux goes.
using TransferMatrices = decltype(PropagationTransfer::matrix);

TransferMatrices matricesOf(const PropagationTransfer& t, double window) {
    TransferMatrices m{};
    for (size_t d = 0; d < 6; ++d)
        for (size_t f = 0; f < 5; ++f) {
            const auto& part = t.integral[5 * d + f];
            const double solidAngle = part[0] * kFluxOfBand0;
            for (int i = 0; i < kShCoefficients; ++i) {
                const double received = (shBand(i) == 2 ? window : 1.0) * part[size_t(i)] / solidAngle;
                for (int j = 0; j < kShCoefficients; ++j) m[d][size_t(i)][size_t(j)] += received * part[size_t(j)];
            }
        }
    return m;
}

// The share of a beam's flux a step sends back where it came from, once
// the beam has settled into the shape the propagation gives it: a lobe
// along +y carried 8 steps forward, then the flux of its step to −y.
double backFlux(const TransferMatrices& m) {
    const std::array<double, kShCoefficients> lobe = shCosineLobeProjection(Vec3(0, 1, 0));
    std::array<double, kShCoefficients> f = lobe;
    auto apply = [&](size_t d, const std::array<double, kShCoefficients>& in) {
        std::array<double, kShCoefficients> out{};
        for (size_t i = 0; i < out.size(); ++i)
            for (size_t j = 0; j < in.size(); ++j) out[i] += m[d][i][j] * in[j];
        return out;
    };
    for (int k = 0; k < 8; ++k) f = apply(2, f);
    double total = 0;
    for (size_t d = 0; d < 6; ++d) total += apply(d, f)[0];
    return apply(3, f)[0] / total;
}

// Band 2 is even: whatever it adds to a beam's flux forward it adds
// backward too, and the order-2 projection of a cone (a part of the
// sphere) sends 8% of a settled beam back each step, which returns a
// lit floor's light to it. Scaling band 2 of what a neighbour receives by
// a window w < 1 (Sloan's windowing against ringing) trades that for a
// little more sideways spread; w is chosen so that a settled beam sends
// nothing back (bisection; about 0.69).
double bandTwoWindowOf(const PropagationTransfer& t) {
    double lo = 0, hi = 1;
    for (int k = 0; k < 50; ++k) {
        const double mid = 0.5 * (lo + hi);
        (backFlux(matricesOf(t, mid)) > 0 ? hi : lo) = mid;
    }
    return 0.5 * (lo + hi);
}

PropagationTransfer buildTransfer() {
    PropagationTransfer t;
    const CubeMapDirections dirs(96);
    for (size_t k = 0; k < dirs.direction.size(); ++k) {
        const Vec3& w = dirs.direction[k];
        int a = 0;
        for (int i = 1; i < 3; ++i)
            if (std::abs(w[i]) > std::abs(w[a])) a = i;
        const int d = 2 * a + (w[a] > 0 ? 0 : 1), b = (a + 1) % 3, c = (a + 2) % 3;
        const double u = w[b] / std::abs(w[a]), v = w[c] / std::abs(w[a]);
        const std::array<double, kShCoefficients> y = shBasis(w);
        auto add = [&](int face, double share) {
            for (int i = 0; i < kShCoefficients; ++i)
                t.integral[size_t(5 * d + face)][size_t(i)] += share * dirs.solidAngle[k] * y[size_t(i)];
        };
        const int sideB = u > 0 ? 1 : 2, sideC = v > 0 ? 3 : 4;
        if (std::abs(u) <= 1.0 / 3 && std::abs(v) <= 1.0 / 3) add(0, 1.0);
        else if (std::abs(std::abs(u) - std::abs(v)) < 1e-9) add(sideB, 0.5), add(sideC, 0.5);
        else if (std::abs(u) > std::abs(v)) add(sideB, 1.0);
        else add(sideC, 1.0);
    }
    // The neighbour gets each part's flux Φ = Σ_j integral_j I_j as the
    // part's own cone of directions, Φ × (projection of its indicator) /
    // its solid angle (the paper's eq. 3.2.3, L_j = T_j · average, scaled
    // so that band 0 carries Φ again), band 2 windowed (see bandTwoWindow).
    t.bandTwoWindow = bandTwoWindowOf(t);
    t.matrix = matricesOf(t, t.bandTwoWindow);
    return t;
}

// A transfer matrix's entries that are not zero by symmetry (about a third
// of the 81): the propagation's inner loop.
struct SparseEntry {
    int i, j;
    double value;
};
using SparseMatrix = std::vector<SparseEntry>;

std::array<SparseMatrix, 6> sparseTransfer() {
    const PropagationTransfer& t = PropagationTransfer::get();
    std::array<SparseMatrix, 6> s;
    for (size_t d = 0; d < 6; ++d) {
        double largest = 0;
        for (const auto& row : t.matrix[d])
            for (double m : row) largest = std::max(largest, std::abs(m));
        for (int i = 0; i < kShCoefficients; ++i)
            for (int j = 0; j < kShCoefficients; ++j) {
                const double m = t.matrix[d][size_t(i)][size_t(j)];
                if (std::abs(m) > 1e-12 * largest) s[d].push_back({i, j, m});
            }
    }
    return s;
}

const std::array<SparseMatrix, 6>& sparse() {
    static const std::array<SparseMatrix, 6> s = sparseTransfer();
    return s;
}

// The part of a convex polygon with p[axis] >= value (above) or < value.
std::vector<Vec3> clipped(const std::vector<Vec3>& polygon, int axis, double value, bool above) {
    std::vector<Vec3> out;
    auto inside = [&](const Vec3& p) { return above ? p[axis] >= value : p[axis] < value; };
    for (size_t i = 0; i < polygon.size(); ++i) {
        const Vec3& p = polygon[i];
        const Vec3& q = polygon[(i + 1) % polygon.size()];
        if (inside(p)) out.push_back(p);
        if (inside(p) != inside(q)) out.push_back(p + (value - p[axis]) / (q[axis] - p[axis]) * (q - p));
    }
    return out;
}

double polygonArea(const std::vector<Vec3>& polygon) {
    Vec3 sum(0.0);
    for (size_t i = 1; i + 1 < polygon.size(); ++i) sum += glm::cross(polygon[i] - polygon[0], polygon[i + 1] - polygon[0]);
    return 0.5 * glm::length(sum);
}

bool isZero(const ShRgb& f) {
    for (const Rgb& c : f.c)
        if (c.r != 0 || c.g != 0 || c.b != 0) return false;
    return true;
}

const PropagationVolumeSettings& validated(const PropagationVolumeSettings& s) {
    s.validate();
    return s;
}

double seconds(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

const PropagationTransfer& PropagationTransfer::get() {
    static const PropagationTransfer t = buildTransfer();
    return t;
}

// --- The grid ---------------------------------------------------------------------------

PropagationGrid::PropagationGrid(const Bounds3& bounds, int cellsAlongLongest) {
    const Vec3 extent = bounds.extent();
    const double longest = std::max({extent.x, extent.y, extent.z});
    lo = bounds.empty() ? Vec3(0.0) : bounds.lo;
    for (int a = 0; a < 3; ++a) {
        const double spacing = longest / cellsAlongLongest;
        dims[size_t(a)] = spacing > 0 ? std::max(1, int(std::lround(extent[a] / spacing))) : 1;
        cell[a] = extent[a] / dims[size_t(a)];
    }
}

std::array<int, 3> PropagationGrid::cellOf(const Vec3& p) const {
    std::array<int, 3> c{0, 0, 0};
    for (int a = 0; a < 3; ++a)
        if (cell[a] > 0) c[size_t(a)] = std::clamp(int(std::floor((p[a] - lo[a]) / cell[a])), 0, dims[size_t(a)] - 1);
    return c;
}

// --- The volume ---------------------------------------------------------------------------

PropagationVolume::PropagationVolume(const Scene& scene, const PropagationVolumeSettings& settings)
    : scene_(scene), settings_(validated(settings)), grid_(scene.bounds, settings.cells) {
    sparse();  // the transfer, built once per process: here rather than in the first update's time
    const std::vector<char> closed = closedMeshesOf(scene);
    const double spacing = 0.5 * std::min({grid_.cell.x, grid_.cell.y, grid_.cell.z});
    for (size_t a = 0; a < 3; ++a) blocking_[a].assign(grid_.count(), 0.0f);
    // Dense samples: each triangle cut into n² sub-triangles of equal area
    // (the regular subdivision), n making their edges at most half a cell,
    // one sample at each's centroid.
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const Mesh& mesh = scene.meshes[m];
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const Vec3 p0 = mesh.positions[mesh.triangles[t][0]], p1 = mesh.positions[mesh.triangles[t][1]],
                       p2 = mesh.positions[mesh.triangles[t][2]];
            const double area = mesh.area(t);
            if (!(area > 0)) continue;
            const Vec3 normal = glm::normalize(mesh.areaNormal(t));
            const double longest = std::max({glm::length(p1 - p0), glm::length(p2 - p1), glm::length(p0 - p2)});
            const int n = std::max(1, int(std::ceil(longest / std::max(spacing, 1e-30))));
            const double subArea = area / (double(n) * n);
            auto sample = [&](double u, double v) {
                SurfaceSample s;
                s.position = p0 + u * (p1 - p0) + v * (p2 - p0);
                s.normal = normal;
                s.area = subArea;
                s.kd = scene.albedo(m, t);
                s.twoSided = !closed[m];
                samples_.push_back(s);
            };
            for (int i = 0; i < n; ++i)
                for (int j = 0; i + j < n; ++j) {
                    sample((i + 1.0 / 3) / n, (j + 1.0 / 3) / n);
                    if (i + j < n - 1) sample((i + 2.0 / 3) / n, (j + 2.0 / 3) / n);
                }
        }
    }
    // The geometry volume, exactly: each triangle clipped to each face's
    // box, its area there projected on the face's axis. No box reaches
    // within half a cell of the grid's outer faces: walls there bound the
    // grid, and light reaching them leaves it.
    for (const Mesh& mesh : scene.meshes)
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const std::vector<Vec3> triangle{mesh.positions[mesh.triangles[t][0]], mesh.positions[mesh.triangles[t][1]],
                                             mesh.positions[mesh.triangles[t][2]]};
            if (!(mesh.area(t) > 0)) continue;
            const Vec3 normal = glm::normalize(mesh.areaNormal(t));
            for (int a = 0; a < 3; ++a)
                if (std::abs(normal[a]) > 0 && grid_.cell[a] > 0) addCoverage(triangle, std::abs(normal[a]), a);
        }
    for (auto& axis : blocking_)
        for (float& b : axis) b = std::min(b, 1.0f);
}

void PropagationVolume::addCoverage(const std::vector<Vec3>& triangle, double cosine, int a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    Vec3 lo = triangle[0], hi = triangle[0];
    for (const Vec3& p : triangle) lo = glm::min(lo, p), hi = glm::max(hi, p);
    // Along a, box i spans the centres of cells i and i + 1; across, the cells.
    auto range = [&](int axis, double shift, int last, int& first, int& end) {
        first = std::max(0, int(std::floor((lo[axis] - grid_.lo[axis]) / grid_.cell[axis] - shift)));
        end = std::min(last, int(std::floor((hi[axis] - grid_.lo[axis]) / grid_.cell[axis] - shift)));
    };
    int i0, i1, j0, j1, k0, k1;
    range(a, 0.5, grid_.dims[size_t(a)] - 2, i0, i1);
    range(b, 0.0, grid_.dims[size_t(b)] - 1, j0, j1);
    range(c, 0.0, grid_.dims[size_t(c)] - 1, k0, k1);
    const double faceArea = grid_.cell[b] * grid_.cell[c];
    for (int i = i0; i <= i1; ++i) {
        const double from = grid_.lo[a] + (i + 0.5) * grid_.cell[a];
        const std::vector<Vec3> slab = clipped(clipped(triangle, a, from, true), a, from + grid_.cell[a], false);
        if (slab.size() < 3) continue;
        for (int j = j0; j <= j1; ++j) {
            const double fromB = grid_.lo[b] + j * grid_.cell[b];
            // The grid's last cell takes what lies on its far face too.
            std::vector<Vec3> row = clipped(slab, b, fromB, true);
            if (j < grid_.dims[size_t(b)] - 1) row = clipped(row, b, fromB + grid_.cell[b], false);
            if (row.size() < 3) continue;
            for (int k = k0; k <= k1; ++k) {
                const double fromC = grid_.lo[c] + k * grid_.cell[c];
                std::vector<Vec3> part = clipped(row, c, fromC, true);
                if (k < grid_.dims[size_t(c)] - 1) part = clipped(part, c, fromC + grid_.cell[c], false);
                if (part.size() < 3) continue;
                std::array<int, 3> at{};
                at[size_t(a)] = i;
                at[size_t(b)] = j;
                at[size_t(c)] = k;
                blocking_[size_t(a)][grid_.index(at)] += float(polygonArea(part) * cosine / faceArea);
            }
        }
    }
}

PropagationVolume::~PropagationVolume() = default;

std::string PropagationVolume::name() const { return "lpv"; }

int PropagationVolume::iterations() const {
    if (settings_.iterations > 0) return settings_.iterations;
    return std::max(1, grid_.dims[0] + grid_.dims[1] + grid_.dims[2] - 3);
}

double PropagationVolume::blocking(int axis, int i, int j, int k) const {
    return blocking_.at(size_t(axis)).at(grid_.index(i, j, k));
}

double PropagationVolume::transmittance(int axis, int i, int j, int k) const {
    return settings_.occlusion ? 1.0 - double(blocking_[size_t(axis)][grid_.index(i, j, k)]) : 1.0;
}

const PropagationVolume::Report& PropagationVolume::report(size_t slot) const {
    ML_ASSERT(slot < sources_.size() && sources_[slot], "propagation volume: source ", slot, " is not built");
    return sources_[slot]->report;
}

Rgb PropagationVolume::absorbed(size_t slot, size_t cell, int side) const {
    ML_ASSERT(slot < sources_.size() && sources_[slot], "propagation volume: source ", slot, " is not built");
    return sources_[slot]->absorbed.at(size_t(side)).at(cell);
}

std::vector<ShRgb> PropagationVolume::inject(const std::vector<IrradianceMeshCopy>& irradiance) const {
    // The cache's irradiance at each sample, as the ray gather reads it.
    const double diagonal = scene_.bounds.diagonal() > 0 ? scene_.bounds.diagonal() : 1.0;
    std::vector<const IrradianceMeshCopy*> meshes;
    for (const IrradianceMeshCopy& m : irradiance) meshes.push_back(&m);
    const MeshIrradianceLookup lookup(meshes, diagonal / 64, 1e-5 * diagonal);
    std::vector<ShRgb> injected(grid_.count());
    auto inject = [&](const SurfaceSample& s, const Vec3& n) {
        const Rgb e = lookup.at(s.position, n);
        if (!(luminance(e) > 0)) return;
        // Half a cell in front of the surface, in the cell that holds it.
        const std::array<int, 3> c = grid_.cellOf(s.position + 0.5 * n * grid_.cell);
        const Rgb scaled = (s.area / kPi) * s.kd * e;  // Lo dA
        const std::array<double, kShCoefficients> lobe = shCosineLobeProjection(n);
        ShRgb& cell = injected[grid_.index(c)];
        for (int i = 0; i < kShCoefficients; ++i) cell.c[size_t(i)] += lobe[size_t(i)] * scaled;
    };
    for (const SurfaceSample& s : samples_) {
        inject(s, s.normal);
        if (s.twoSided) inject(s, -s.normal);
    }
    return injected;
}

void PropagationVolume::setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double) {
    const auto start = std::chrono::steady_clock::now();
    const std::vector<ShRgb> injected = inject(irradiance);
    const double injectSeconds = seconds(start);
    propagateInjected(slot, injected);
    sources_[slot]->report.injectSeconds = injectSeconds;
    stats_.buildSeconds += injectSeconds;
}

void PropagationVolume::propagateInjected(size_t slot, const std::vector<ShRgb>& injected) {
    ML_ASSERT(injected.size() == grid_.count(), "propagation volume: ", injected.size(), " cells injected, the grid has ",
              grid_.count());
    const auto start = std::chrono::steady_clock::now();
    if (slot >= sources_.size()) sources_.resize(slot + 1);
    auto source = std::make_unique<Source>();
    for (const ShRgb& f : injected) source->report.injectedFlux += kFluxOfBand0 * luminance(f.c[0]);
    propagate(*source, injected);
    source->report.propagateSeconds = seconds(start);
    stats_.source = concat(grid_.dims[0], "x", grid_.dims[1], "x", grid_.dims[2], " cells, ", source->report.steps,
                           " steps, ", samples_.size(), " surface samples",
                           settings_.occlusion ? ", occlusion" : ", no occlusion");
    sources_[slot] = std::move(source);
    finishStats(seconds(start));
}

void PropagationVolume::propagate(Source& source, std::vector<ShRgb> moving) const {
    const std::array<SparseMatrix, 6>& transfer = sparse();
    Report& r = source.report;
    for (auto& side : source.absorbed) side.assign(grid_.count(), Rgb(0.0));
    std::vector<ShRgb> next(grid_.count());
    const int steps = iterations();
    const std::array<int, 3>& dims = grid_.dims;
    for (int step = 0; step < steps; ++step) {
        std::fill(next.begin(), next.end(), ShRgb{});
        for (int k = 0; k < dims[2]; ++k)
            for (int j = 0; j < dims[1]; ++j)
                for (int i = 0; i < dims[0]; ++i) {
                    const size_t from = grid_.index(i, j, k);
                    if (isZero(moving[from])) continue;
                    for (int d = 0; d < 6; ++d) {
                        ShRgb out;
                        for (const SparseEntry& e : transfer[size_t(d)])
                            out.c[size_t(e.i)] += e.value * moving[from].c[size_t(e.j)];
                        const Rgb flux = kFluxOfBand0 * out.c[0];
                        std::array<int, 3> to{i, j, k};
                        const int axis = d / 2;
                        to[size_t(axis)] += d % 2 ? -1 : 1;
                        if (to[size_t(axis)] < 0 || to[size_t(axis)] >= dims[size_t(axis)]) {
                            source.absorbed[size_t(d)][from] += flux;
                            r.leftGrid += luminance(flux);
                            continue;
                        }
                        // The face between the two cells, indexed by the lower one.
                        std::array<int, 3> lower{i, j, k};
                        lower[size_t(axis)] = std::min(lower[size_t(axis)], to[size_t(axis)]);
                        const double t = transmittance(axis, lower[0], lower[1], lower[2]);
                        if (t < 1) {
                            source.absorbed[size_t(d)][from] += (1 - t) * flux;
                            r.blocked += (1 - t) * luminance(flux);
                        }
                        if (!(t > 0)) continue;
                        ShRgb& into = next[grid_.index(to)];
                        for (int c = 0; c < kShCoefficients; ++c) into.c[size_t(c)] += t * out.c[size_t(c)];
                    }
                }
        std::swap(moving, next);
        double inFlight = 0, magnitude = 0;
        for (const ShRgb& f : moving) {
            const double flux = kFluxOfBand0 * luminance(f.c[0]);
            inFlight += flux;
            magnitude += std::abs(flux);
        }
        r.inFlight = inFlight;
        r.steps = step + 1;
        if (!(magnitude > 1e-6 * std::abs(r.injectedFlux))) break;
    }
}

void PropagationVolume::finishStats(double seconds) {
    stats_.buildSeconds += seconds;
    size_t held = 0;
    for (const auto& s : sources_)
        if (s) held += 6 * grid_.count() * sizeof(Rgb);
    for (const auto& b : blocking_) held += b.size() * sizeof(float);
    stats_.sourceBytes = held + samples_.size() * sizeof(SurfaceSample);
}

void PropagationVolume::releaseSource(size_t slot) {
    if (slot < sources_.size()) sources_[slot].reset();
}

double PropagationVolume::transmittanceBetween(std::array<int, 3> from, const std::array<int, 3>& to) const {
    double t = 1;
    for (int a = 0; a < 3 && t > 0; ++a)
        while (from[size_t(a)] != to[size_t(a)]) {
            const int next = from[size_t(a)] + (to[size_t(a)] > from[size_t(a)] ? 1 : -1);
            std::array<int, 3> lower = from;
            lower[size_t(a)] = std::min(from[size_t(a)], next);
            t *= transmittance(a, lower[0], lower[1], lower[2]);
            from[size_t(a)] = next;
        }
    return t;
}

double PropagationVolume::coverage(const std::array<int, 3>& c, int side) const {
    const int axis = side / 2;
    std::array<int, 3> lower = c;
    if (side % 2) {
        if (c[size_t(axis)] == 0) return 1.0;
        --lower[size_t(axis)];
    } else if (c[size_t(axis)] == grid_.dims[size_t(axis)] - 1) {
        return 1.0;
    }
    return settings_.occlusion ? double(blocking_[size_t(axis)][grid_.index(lower)]) : 0.0;
}

Rgb PropagationVolume::faceIrradiance(const Source& source, const std::array<int, 3>& c, int side) const {
    const int axis = side / 2;
    const double covered = coverage(c, side) * grid_.cell[(axis + 1) % 3] * grid_.cell[(axis + 2) % 3];
    return covered > 0 ? source.absorbed[size_t(side)][grid_.index(c)] / covered : Rgb(0.0);
}

Rgb PropagationVolume::estimate(size_t slot, const Vec3& x, const Vec3& nIn, uint32_t) {
    ML_ASSERT(slot < sources_.size() && sources_[slot], "propagation volume: source ", slot, " is not built");
    const auto start = std::chrono::steady_clock::now();
    const Source& source = *sources_[slot];
    const Vec3 n = glm::normalize(nIn);
    Rgb result(0.0);
    for (int a = 0; a < 3; ++a) {
        const double share = n[a] * n[a];
        if (!(share > 1e-12) || !(grid_.cell[a] > 0)) continue;
        // Light arriving against n along this axis crosses the face of the
        // cell half a cell in front of x on x's side.
        const int side = 2 * a + (n[a] > 0 ? 1 : 0);
        Vec3 q = x;
        q[a] += (n[a] > 0 ? 0.5 : -0.5) * grid_.cell[a];
        const std::array<int, 3> home = grid_.cellOf(q);
        // Bilinear over the faces beside it in the face's plane (their
        // centres are the cells' centres there), faces no surface covers
        // left out.
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        std::array<int, 2> base{}, span{};
        std::array<double, 2> t{};
        for (int m = 0; m < 2; ++m) {
            const int axis = m ? c : b;
            const int dims = grid_.dims[size_t(axis)];
            const double g = grid_.cell[axis] > 0 ? (q[axis] - grid_.lo[axis]) / grid_.cell[axis] - 0.5 : 0.0;
            base[size_t(m)] = dims > 1 ? std::clamp(int(std::floor(g)), 0, dims - 2) : 0;
            span[size_t(m)] = dims > 1 ? 1 : 0;
            t[size_t(m)] = dims > 1 ? std::clamp(g - base[size_t(m)], 0.0, 1.0) : 0.0;
        }
        Rgb sum(0.0);
        double weights = 0;
        for (int u = 0; u <= span[0]; ++u)
            for (int v = 0; v <= span[1]; ++v) {
                std::array<int, 3> at = home;
                at[size_t(b)] = base[0] + u;
                at[size_t(c)] = base[1] + v;
                const double w = (u ? t[0] : 1 - t[0]) * (v ? t[1] : 1 - t[1]) * transmittanceBetween(home, at);
                if (!(w > 0) || !(coverage(at, side) > 0)) continue;
                sum += w * faceIrradiance(source, at, side);
                weights += w;
            }
        if (weights > 0) result += (share / weights) * sum;
    }
    result = glm::max(result, Rgb(0.0));
    stats_.estimates++;
    stats_.estimateSeconds += seconds(start);
    return result;
}

IndirectStats PropagationVolume::stats() const { return stats_; }

}  // namespace ml
