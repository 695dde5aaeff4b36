#include "GridCache.h"

#include "core/Error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace ml {

void GridCacheSettings::validate() const {
    if (!(std::isfinite(cellSize) && cellSize > 0))
        throw InputError(concat("grid cache cell size ", cellSize, " is not a finite length > 0"));
    if (!(normalConeCos >= 0 && normalConeCos < 1))
        throw InputError(concat("grid cache normal cone cosine ", normalConeCos, " is not in [0, 1)"));
}

namespace {

// Area of a regular triangular lattice's vertex cell, for edge length 1.
const double kLatticeAreaPerVertex = std::sqrt(3.0) / 2.0;

std::string objectName(const Mesh& m) { return m.name.empty() ? std::string("(unnamed)") : m.name; }

// Cells are addressed by 21-bit unsigned coordinates packed in one key.
// Coordinate i+1 stores cell i, so the empty ring around the object (-1 and
// n) can be looked up without wrapping.
constexpr int kCellBits = 21;
constexpr int64_t kMaxCellCoord = (int64_t(1) << kCellBits) - 1;

uint64_t cellKey(int64_t x, int64_t y, int64_t z) {
    return (uint64_t(x + 1) << (2 * kCellBits)) | (uint64_t(y + 1) << kCellBits) | uint64_t(z + 1);
}

}  // namespace

GridCacheDecision decideGridCache(const Mesh& object, double maxEdgeLength) {
    if (!(std::isfinite(maxEdgeLength) && maxEdgeLength > 0))
        throw InputError(concat("object '", objectName(object), "': grid cache decision needs a finite maximum edge "
                                "length > 0, got ", maxEdgeLength));
    double area = 0;
    for (size_t t = 0; t < object.triangles.size(); ++t) {
        const glm::uvec3 i = object.triangles[t];
        if (i.x >= object.positions.size() || i.y >= object.positions.size() || i.z >= object.positions.size())
            throw InputError(concat("object '", objectName(object), "': triangle ", t, " indexes a vertex beyond its ",
                                    object.positions.size()));
        area += object.area(t);
    }
    if (!std::isfinite(area))
        throw InputError(concat("object '", objectName(object), "': its area is not finite (a non-finite position?)"));

    GridCacheDecision d;
    d.vertices = object.positions.size();
    const double needed = std::ceil(area / (kLatticeAreaPerVertex * maxEdgeLength * maxEdgeLength));
    // Capped where it no longer fits a size_t: such an object needs a mesh anyway.
    d.neededVertices = needed < 1e18 ? size_t(needed) : size_t(1e18);
    const bool dense = double(d.vertices) > kGridVertexRatio * double(d.neededVertices);
    const bool large = d.vertices > kGridMinVertices;
    d.useGrid = dense && large;
    const std::string counts = concat(d.vertices, " vertices, ", d.neededVertices, " needed at max edge ", maxEdgeLength,
                                      " (area ", area, ")");
    if (d.useGrid)
        d.reason = concat("object '", objectName(object), "': grid cache: ", counts, "; more than ", kGridVertexRatio,
                          " x needed and more than ", kGridMinVertices, " vertices");
    else
        d.reason = concat("object '", objectName(object), "': cache meshes: ", counts, ";",
                          dense ? "" : concat(" not more than ", kGridVertexRatio, " x needed"),
                          dense || large ? "" : " and",
                          large ? "" : concat(" not more than ", kGridMinVertices, " vertices"));
    return d;
}

GridCache::GridCache(const Mesh& object, const GridCacheSettings& settings) : cellSize_(settings.cellSize) {
    settings.validate();
    const std::string name = objectName(object);
    const size_t nv = object.positions.size();
    if (nv == 0) throw InputError(concat("object '", name, "': a grid cache needs vertices, it has none"));
    if (object.normals.size() != nv)
        throw InputError(concat("object '", name, "': ", object.normals.size(), " normals for ", nv, " positions"));
    if (nv > std::numeric_limits<uint32_t>::max())
        throw InputError(concat("object '", name, "': ", nv, " vertices, more than 32-bit indices hold"));

    // Unit normals; the Mesh promises them, but a cancelled average upstream
    // gives a short or zero vector whose direction cannot be trusted.
    std::vector<Vec3> normals(nv);
    Bounds3 bounds;
    for (size_t v = 0; v < nv; ++v) {
        const Vec3& p = object.positions[v];
        const Vec3& n = object.normals[v];
        if (!isFinite(p))
            throw InputError(concat("object '", name, "': vertex ", v, " has a non-finite position (", p.x, ", ", p.y,
                                    ", ", p.z, ")"));
        const double len = glm::length(n);
        if (!(std::isfinite(len) && len > 1e-6))
            throw InputError(concat("object '", name, "': vertex ", v, " has a degenerate normal (", n.x, ", ", n.y,
                                    ", ", n.z, ")"));
        normals[v] = n / len;
        bounds.extend(p);
    }
    const double h = settings.cellSize;
    const Vec3 lo = bounds.lo;
    const Vec3 extent = bounds.extent();
    const double cellsAlongLongest = std::max({extent.x, extent.y, extent.z}) / h;
    // The empty ring (-1 and n) must fit the key as well as the n cells.
    if (!(cellsAlongLongest < double(kMaxCellCoord - 3)))
        throw InputError(concat("object '", name, "': grid cache cell size ", h, " needs ", cellsAlongLongest,
                                " cells along its longest side (", std::max({extent.x, extent.y, extent.z}),
                                "), more than 2^", kCellBits, "; use a larger cell or a cache mesh"));

    // Grid coordinates, relative to the object's corner: only size / cell matters.
    auto gridPoint = [&](size_t v) { return (object.positions[v] - lo) / h; };

    // Vertices sorted by cell, so cells and samples come in a fixed order.
    std::vector<std::pair<uint64_t, uint32_t>> byCell(nv);
    for (size_t v = 0; v < nv; ++v) {
        const Vec3 t = glm::floor(gridPoint(v));
        byCell[v] = {cellKey(int64_t(t.x), int64_t(t.y), int64_t(t.z)), uint32_t(v)};
    }
    std::sort(byCell.begin(), byCell.end());

    // Normal clusters of each cell. Every member is within θ of its seed, so
    // the members' normalised mean is within θ of the seed too (a cap of
    // half-angle < 90° is convex) and within 2θ of every member; 2θ <
    // acos(normalConeCos) keeps each vertex's own sample in its cone.
    const double theta = std::acos(settings.normalConeCos) / 3.0;
    const double cosTheta = std::cos(theta);
    std::vector<uint64_t> cellKeys;        // sorted
    std::vector<uint32_t> cellFirstSample; // one more than cellKeys
    std::vector<uint32_t> ownSample(nv);
    struct Cluster {
        Vec3 seed;
        Vec3 normalSum{0.0};
        Vec3 positionSum{0.0};
        std::vector<uint32_t> members;
    };
    std::vector<Cluster> clusters;
    for (size_t begin = 0; begin < nv;) {
        size_t end = begin;
        while (end < nv && byCell[end].first == byCell[begin].first) ++end;
        clusters.clear();
        for (size_t k = begin; k < end; ++k) {
            const uint32_t v = byCell[k].second;
            const Vec3& n = normals[v];
            size_t best = clusters.size();
            double bestCos = -2;
            for (size_t c = 0; c < clusters.size(); ++c) {
                const double cs = glm::dot(n, clusters[c].seed);
                if (cs > bestCos) bestCos = cs, best = c;
            }
            if (best == clusters.size() || bestCos < cosTheta) {
                clusters.push_back(Cluster{n, Vec3(0.0), Vec3(0.0), {}});
                best = clusters.size() - 1;
            }
            Cluster& c = clusters[best];
            c.normalSum += n;
            c.positionSum += object.positions[v] - lo;  // relative: keeps precision far from the origin
            c.members.push_back(v);
        }
        cellKeys.push_back(byCell[begin].first);
        cellFirstSample.push_back(uint32_t(samples_.size()));
        for (const Cluster& c : clusters) {
            const Vec3 centroid = c.positionSum / double(c.members.size());
            // Symmetric meshes have several vertices equally near the
            // centroid: the lowest index within 1e-10 cell² of the nearest
            // wins, so rounding (scale, position) does not pick another.
            double nearestD2 = kInf;
            auto dist2 = [&](uint32_t v) {
                const Vec3 d = (object.positions[v] - lo) - centroid;
                return glm::dot(d, d);
            };
            for (uint32_t v : c.members) nearestD2 = std::min(nearestD2, dist2(v));
            uint32_t nearest = c.members.front();
            for (uint32_t v : c.members)  // ascending indices
                if (dist2(v) <= nearestD2 + 1e-10 * h * h) {
                    nearest = v;
                    break;
                }
            const double len = glm::length(c.normalSum);
            ML_ASSERT(len >= cosTheta * double(c.members.size()) * (1 - 1e-12), "cluster normal sum ", len, " of ",
                      c.members.size(), " in object '", name, "'");
            const uint32_t s = uint32_t(samples_.size());
            samples_.push_back(Sample{object.positions[nearest], c.normalSum / len, nearest});
            for (uint32_t v : c.members) ownSample[v] = s;
        }
        begin = end;
    }
    cellFirstSample.push_back(uint32_t(samples_.size()));

    // Interpolation weights. The 2×2×2 cells whose centres surround a vertex
    // start at floor(t - 1/2); its own cell floor(t) is one of them with a
    // trilinear factor >= 1/2 per axis (t - 1/2 is exact for t < 2^52).
    const double c = settings.normalConeCos;
    offsets_.assign(1, 0);
    offsets_.reserve(nv + 1);
    sampleIds_.reserve(nv * 4);
    weights_.reserve(nv * 4);
    for (size_t v = 0; v < nv; ++v) {
        const Vec3 u = gridPoint(v) - 0.5;
        const Vec3 base = glm::floor(u);
        const Vec3 frac = u - base;
        const size_t rowBegin = sampleIds_.size();
        double total = 0;
        bool ownUsed = false;
        for (int corner = 0; corner < 8; ++corner) {
            const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
            const double wCell = (dx ? frac.x : 1 - frac.x) * (dy ? frac.y : 1 - frac.y) * (dz ? frac.z : 1 - frac.z);
            if (!(wCell > 0)) continue;
            const uint64_t key =
                cellKey(int64_t(base.x) + dx, int64_t(base.y) + dy, int64_t(base.z) + dz);
            const auto it = std::lower_bound(cellKeys.begin(), cellKeys.end(), key);
            if (it == cellKeys.end() || *it != key) continue;
            const size_t cell = size_t(it - cellKeys.begin());
            for (uint32_t s = cellFirstSample[cell]; s < cellFirstSample[cell + 1]; ++s) {
                const double cs = glm::dot(normals[v], samples_[s].normal);
                if (!(cs > c)) continue;
                const double w = wCell * (cs - c) / (1 - c);
                if (!(w > 0)) continue;
                sampleIds_.push_back(s);
                weights_.push_back(w);
                total += w;
                ownUsed |= s == ownSample[v];
            }
        }
        ML_ASSERT(ownUsed && total > 0 && std::isfinite(total), "vertex ", v, " of object '", name,
                  "' does not use its own sample ", ownSample[v], " (total weight ", total, ")");
        for (size_t k = rowBegin; k < weights_.size(); ++k) weights_[k] /= total;
        if (sampleIds_.size() > std::numeric_limits<uint32_t>::max())
            throw InputError(concat("object '", name, "': more than 2^32 grid cache weights"));
        offsets_.push_back(uint32_t(sampleIds_.size()));
    }
    samples_.shrink_to_fit();
    sampleIds_.shrink_to_fit();
    weights_.shrink_to_fit();
}

void GridCache::interpolate(const std::vector<Rgb>& sampleValues, std::vector<Rgb>& vertexValues) const {
    if (sampleValues.size() != samples_.size())
        throw std::invalid_argument(
            concat("grid cache: ", sampleValues.size(), " sample values for ", samples_.size(), " samples"));
    for (size_t s = 0; s < sampleValues.size(); ++s)
        if (!isFinite(sampleValues[s]))
            throw std::invalid_argument(concat("grid cache: sample ", s, " has a non-finite value (", sampleValues[s].r,
                                               ", ", sampleValues[s].g, ", ", sampleValues[s].b, ")"));
    const size_t nv = vertexCount();
    vertexValues.resize(nv);
    for (size_t v = 0; v < nv; ++v) {
        Rgb sum(0.0);
        for (uint32_t k = offsets_[v]; k < offsets_[v + 1]; ++k) sum += weights_[k] * sampleValues[sampleIds_[k]];
        ML_ASSERT(isFinite(sum), "vertex ", v);
        vertexValues[v] = sum;
    }
}

size_t GridCache::memoryBytes() const {
    return sizeof(*this) + samples_.capacity() * sizeof(Sample) + offsets_.capacity() * sizeof(uint32_t) +
           sampleIds_.capacity() * sizeof(uint32_t) + weights_.capacity() * sizeof(double);
}

}  // namespace ml
