// Grid caches (§3.2 of the paper): "small grid caches built over highly
// tessellated objects to keep a reduced sampling density of irradiance over
// these objects". Such an object gets no per-light cache mesh: irradiance is
// sampled at a few points of its surface, one per occupied (grid cell, normal
// cluster), and the object's own vertices take a weighted mean of the samples
// around them.
//
// Units are the scene's own; nothing here depends on OpenMesh or on GL.
#pragma once

#include "core/Scene.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ml {

struct GridCacheSettings {
    // Edge of the grid's cubic cells, world units, > 0. Typical: the cache's
    // maximum edge length (CacheSettings::maxEdgeFraction × scene diagonal),
    // so that an object is sampled about as densely as a cache mesh would be.
    double cellSize = 0;
    // A sample is used at a vertex only when the cosine between their normals
    // is above this, in [0, 1); typical 0.5 (60°). Below 0 a cone would reach
    // the far side of a thin part, so it is refused.
    double normalConeCos = 0.5;
    // Throws InputError naming the bad value.
    void validate() const;
};

// Why (or why not) an object gets a grid cache.
//
// neededVertices estimates the cache vertices the object's surface needs at
// maxEdgeLength L: a triangulation whose edges are about L has one vertex per
// √3/2·L² of area (a regular triangular lattice), so needed = ⌈area / (√3/2·L²)⌉.
// The object gets a grid when
//     vertices > kGridVertexRatio × needed   and   vertices > kGridMinVertices.
// A grid with cells of size L holds about 1.5·area/L² samples (a surface
// crosses (|nx|+|ny|+|nz|)·area/L² cubic cells, 1.5·area/L² on average over
// orientations), i.e. about 1.3 × needed. A ratio of 4 therefore means at least
// ~3 object vertices per sample: below that the saving does not pay for what
// the grid loses (cache meshes follow the surface exactly and refine along
// shadows, a grid blurs over 2 cells). Objects of 2,000 vertices or fewer cost
// little to sample per vertex whatever their density, so they keep meshes.
constexpr double kGridVertexRatio = 4.0;
constexpr size_t kGridMinVertices = 2000;

struct GridCacheDecision {
    bool useGrid = false;
    std::string reason;         // one line with the object's name and both counts
    size_t vertices = 0;        // object.positions.size()
    size_t neededVertices = 0;  // see above
};

// maxEdgeLength: the cache's maximum edge length, world units, > 0 and
// finite (InputError otherwise).
GridCacheDecision decideGridCache(const Mesh& object, double maxEdgeLength);

class GridCache {
public:
    // Bins the object's vertices into cubic cells of settings.cellSize
    // (origin at the object's bounding-box corner, so only the object's size
    // relative to the cell matters, not its position or scale), then splits
    // each cell's vertices into normal clusters: a vertex joins the cluster
    // whose seed normal is closest, if within θ = acos(normalConeCos)/3,
    // else seeds a new one. One sample per cluster.
    //
    // Throws InputError naming the object and vertex for a non-finite
    // position, a zero or non-finite normal, normals not one per position;
    // and for an object without vertices or a cell so small that an axis
    // would need more than 2^21 cells.
    GridCache(const Mesh& object, const GridCacheSettings& settings);

    // Samples
    size_t sampleCount() const { return samples_.size(); }
    // The cluster's vertex nearest the cluster's centroid (lowest index among
    // ties within 1e-10 cell²): a point on the object's surface, where
    // irradiance is to be sampled.
    Vec3 samplePosition(size_t s) const { return samples_.at(s).position; }
    // The normalised mean of the cluster's normals: unit, and within θ of
    // every normal in the cluster.
    Vec3 sampleNormal(size_t s) const { return samples_.at(s).normal; }
    // The object vertex at samplePosition(s).
    uint32_t sampleVertex(size_t s) const { return samples_.at(s).vertex; }

    // Interpolation
    size_t vertexCount() const { return offsets_.size() - 1; }
    // vertexValues[v] = Σ weights · sampleValues over the samples of the 2×2×2
    // cells whose centres surround vertex v, each weighted by its cell's
    // trilinear weight × (cos − normalConeCos)/(1 − normalConeCos), cos being
    // the cosine between the sample's and the vertex's normal; samples with
    // cos <= normalConeCos are left out, so the two sides of a thin part are
    // never mixed. Weights are normalised to sum to 1 (constant fields are
    // reproduced). No fallback is needed: the vertex's own cluster sample lies
    // in one of the 8 cells with trilinear weight >= 1/8 and within 2θ <
    // acos(normalConeCos) of the vertex's normal, so every vertex has at least
    // one sample (the constructor asserts it).
    // sampleValues: one per sample, finite (std::invalid_argument otherwise);
    // vertexValues is resized to vertexCount() = object.positions.size().
    void interpolate(const std::vector<Rgb>& sampleValues, std::vector<Rgb>& vertexValues) const;

    // The same weights, compressed rows: vertex v uses
    // weightSamples()[k] with weights()[k] for k in [weightOffsets()[v], weightOffsets()[v+1]).
    const std::vector<uint32_t>& weightOffsets() const { return offsets_; }
    const std::vector<uint32_t>& weightSamples() const { return sampleIds_; }
    const std::vector<double>& weights() const { return weights_; }

    double cellSize() const { return cellSize_; }
    // Bytes held by the samples and the weights.
    size_t memoryBytes() const;

private:
    struct Sample {
        Vec3 position;
        Vec3 normal;
        uint32_t vertex;
    };
    double cellSize_ = 0;
    std::vector<Sample> samples_;
    std::vector<uint32_t> offsets_{0};
    std::vector<uint32_t> sampleIds_;
    std::vector<double> weights_;
};

}  // namespace ml
