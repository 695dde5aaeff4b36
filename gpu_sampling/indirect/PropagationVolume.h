// Voxel light propagation with occlusion (Mavridis, Gaitatzes & Papaioannou):
// the scene's surfaces injected into a uniform grid as virtual point lights,
// their light spread from cell to neighbouring cell through the empty
// space, stopped where the grid's geometry volume says a surface lies
// between two cells, and a surface point's irradiance read from the light
// that passed through the cells around it.
//
// One bounce per source. The paper reflects light arriving at occupied
// voxels inside its propagation loop; here the cache's bounce structure
// does it (as for the other estimators): source n−1 is injected, propagated
// once, and the irradiance estimated at the cache's vertices becomes the
// next bounce's source. A surface a flux runs into absorbs it.
//
// The grid. `cells` along the scene's longest side, the others near
// cubes, the scene's bounds tiled exactly, so the box walls of a room lie
// on the grid's outer faces. Each cell holds order-2 spherical harmonics
// per channel (9 coefficients, core/SphericalHarmonics.h) of radiant
// intensity I(ω), W·sr⁻¹, ω the direction light travels (the paper's
// propagation buffer). The paper keeps order 1 (4 coefficients, one RGBA
// texture per channel); on the CPU order 2 costs nothing special and
// keeps a beam's direction better (see the window below).
//
// Injection. Every scene triangle is cut into n² equal sub-triangles no
// longer than half a cell (the "dense sampling" of the paper's voxel-wise
// average): each is a virtual point light of flux π Lo dA, Lo = Kd/π · E
// (E read from the source meshes there, MeshIrradianceLookup; both sides of
// an open surface), whose intensity is the cosine lobe Lo dA max(0, n·ω),
// added to the cell half a cell in front of it (so a light on a cell's
// far side does not start behind a neighbour it faces: Kaplanyan &
// Dachsbacher's shift).
//
// Propagation (their eq. 3.2.3, made exact for flux). From a cell's
// centre the sphere of directions is cut into 30 parts: a direction leaves
// through one of the 6 faces (its dominant axis) into that neighbour, and
// then through the neighbour's far face or one of its 4 side faces
// (Kaplanyan & Dachsbacher's faces). The flux through each part is
// ∫ I(ω) dω over it, an exact dot product with the basis' integrals over
// the part (precomputed by a 96-texel cube-map quadrature), and the
// neighbour receives it as the part's own cone of directions: the paper's
// L_j = T_j · average, scaled so that band 0 carries the flux again.
// Because the 30 parts tile the sphere, a step moves exactly the cell's
// flux onward, less what leaves the grid and what the geometry stops.
// Band 2 is even, so what a cone's order-2 projection adds forward it adds
// backward too: a settled beam would send 8% of its flux back each step,
// and a lit floor would get its own light back. Band 2 of what a neighbour
// receives is windowed (× 0.69, found so that a settled beam sends nothing
// back; Sloan's windowing against ringing): the beam then goes on with
// 70% a step and spreads 7.4% to each side. Negative values from ringing
// propagate as they are: clamping would break the linearity that conserves
// flux.
//
// Occlusion: the geometry volume. Per face between two cells, the share
// of the face that surfaces block along the face's axis: Σ area |n·a| /
// (face area) over the parts of the triangles inside the box spanning the
// two cells' centres (a cell's width across), each triangle clipped to the
// box exactly, clamped to 1; the flux crossing the face is multiplied by 1
// minus it. The paper (and Kaplanyan & Dachsbacher's later version) keeps
// the coverage as low-order SH of blocking and evaluates it in the flux's
// direction; order 2 of |n·ω| is 1.125 along a surface's normal and 0.1875
// along the surface itself, so a floor would block 19% of the light
// running along it. The projected area along the one axis a face is
// crossed along is exact for axis-aligned surfaces and costs one number.
//
// Iterations: the lattice distance between the grid's opposite corner
// cells, (nx − 1) + (ny − 1) + (nz − 1): a step moves light one cell along
// one axis, so after that many steps light from any cell can have reached
// every other cell (the paper's rule, its longest side, lets light cross
// the scene along an axis only). Propagation stops sooner when the flux
// still moving is below 1e-6 of the injected flux.
//
// Reading irradiance. The paper accumulates the radiance that arrives at
// occupied voxels and reads it there (§3.2-3.3). Here that is exact for
// flux: every step, what a face's surfaces stop (or the grid's outer face
// takes) is added to that face's tally, per side, so all the light
// injected ends on some surface. A surface at x facing n reads, along each
// axis a with weight n_a², the tally of the face of the cell half a cell in
// front of it, on its side, over the area the surfaces cover there
// (irradiance = absorbed flux / area), blended bilinearly with the faces
// beside it in the face's plane; a neighbouring face counts times the
// transmittance between the two cells (beyond the paper: a point beside a
// thin wall does not blend in the faces on its other side).
//
// Error: the lattice spreads a beam sideways (7.4% a step to each side), so
// light is smeared over the walls it meets and gathers at edges and
// corners, and more with more steps: finer grids do not converge to the
// exact answer (tests/test_propagation_volume.cpp and bench indirect
// measure it). Within a cell of a lit surface, a point takes that
// surface's first step directly.
//
// On the CPU (plain loops, one thread): bench indirect times the same
// steps as a GL compute shader (PropagationCompute.h), slower on this
// machine's llvmpipe; see gpu_sampling/README.md.
#pragma once

#include "cache/IndirectEstimator.h"
#include "core/Scene.h"
#include "core/SphericalHarmonics.h"

#include <array>
#include <memory>
#include <vector>

namespace ml {

// The grid: cells tiling the scene's bounds exactly, `cellsAlongLongest`
// along the longest side and as many along the others as keep them near
// cubes (at least 1).
struct PropagationGrid {
    std::array<int, 3> dims{1, 1, 1};
    Vec3 lo{0.0}, cell{0.0};

    PropagationGrid() = default;
    PropagationGrid(const Bounds3& bounds, int cellsAlongLongest);
    size_t count() const { return size_t(dims[0]) * size_t(dims[1]) * size_t(dims[2]); }
    size_t index(int i, int j, int k) const { return (size_t(k) * size_t(dims[1]) + size_t(j)) * size_t(dims[0]) + size_t(i); }
    size_t index(const std::array<int, 3>& c) const { return index(c[0], c[1], c[2]); }
    // The cell holding p (clamped to the grid).
    std::array<int, 3> cellOf(const Vec3& p) const;
};

struct PropagationVolumeSettings {
    // Cells along the scene's longest side; the others get as many as keep
    // the cells near cubes. The paper's is 32; typical 16..32 (Cornell box
    // at 16: 4,096 cells 35 mm wide, 45 steps).
    int cells = 16;
    // The geometry volume: occlusion between cells during propagation and
    // between the cells a point blends. Off: Kaplanyan's plain propagation
    // volume (light goes through walls).
    bool occlusion = true;
    // Propagation steps; 0: the scene's rule (the grid's corner-to-corner
    // lattice distance, see above).
    int iterations = 0;
    void validate() const;  // InputError unless 2 <= cells <= 128 and 0 <= iterations <= 4096
};

// The flux transfer of one propagation step between neighbours, from the
// cell's SH intensity: for each of the 6 neighbour directions d (+x, −x,
// +y, −y, +z, −z), the 9×9 matrix taking the source cell's coefficients to
// what the neighbour receives (the sum over its 5 faces of the cone of the
// flux through each), before occlusion. Built once per process.
struct PropagationTransfer {
    // matrix[d][i][j]: coefficient i received from source coefficient j.
    std::array<std::array<std::array<double, kShCoefficients>, kShCoefficients>, 6> matrix{};
    // The basis' integrals over each of the 30 parts of the sphere
    // (d·5 + f; f = 0 the far face, 1..4 the side faces +b, −b, +c, −c with
    // b, c the axes after d's): what the matrices are made of, for tests.
    std::array<std::array<double, kShCoefficients>, 30> integral{};
    // The factor on band 2 of what a neighbour receives (PropagationVolume.cpp).
    double bandTwoWindow = 1;
    static const PropagationTransfer& get();
};

// The order-2 projection of a cosine lobe max(0, n·ω) (unit n): λ_l Y_lm(n)
// with λ = π, 2π/3, π/4 (Funk-Hecke); its band 0 carries the lobe's
// integral, π, exactly.
std::array<double, kShCoefficients> shCosineLobeProjection(const Vec3& n);

class PropagationVolume final : public IndirectEstimator {
public:
    // `scene` must outlive the volume. Samples the scene's surfaces and
    // builds the geometry volume once (the scene does not move here).
    PropagationVolume(const Scene& scene, const PropagationVolumeSettings& settings);
    ~PropagationVolume() override;

    std::string name() const override;
    // Injects the source's light and propagates it (the update; one thread:
    // the cache's SamplerPool gives every thread a volume of its own).
    void setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance = 1.0) override;
    void releaseSource(size_t slot) override;
    // Deterministic: the seed is not used.
    Rgb estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override;
    IndirectStats stats() const override;

    const PropagationGrid& grid() const { return grid_; }
    const PropagationVolumeSettings& settings() const { return settings_; }
    // Steps the rule gives this grid (settings.iterations when set).
    int iterations() const;

    // What one setSource did, for tests and the bench.
    struct Report {
        double injectedFlux = 0;  // W: Σ π Lo dA over the virtual point lights (band 0 of every cell)
        double leftGrid = 0;      // W: flux propagated out through the grid's outer faces
        double blocked = 0;       // W: flux the geometry volume stopped
        double inFlight = 0;      // W: flux still moving after the last step (band 0; ringing may make it signed)
        int steps = 0;            // propagation steps run
        double injectSeconds = 0, propagateSeconds = 0;
    };
    const Report& report(size_t slot) const;

    // The geometry volume: the share of the face between cell (i, j, k)
    // and its +axis neighbour that surfaces block, in [0, 1].
    double blocking(int axis, int i, int j, int k) const;
    // The source's virtual point lights gathered per cell (SH intensity,
    // W·sr⁻¹ coefficients): what setSource propagates.
    std::vector<ShRgb> inject(const std::vector<IrradianceMeshCopy>& irradiance) const;
    // Injects raw intensity (SH coefficients, W·sr⁻¹) into cells and
    // propagates it as setSource does; for the energy tests.
    void propagateInjected(size_t slot, const std::vector<ShRgb>& injected);
    // The flux (W per channel) that reached face `side` of cell `cell`
    // (side 2a: its +a face, 2a + 1: its −a face) and was absorbed there:
    // by the geometry volume's surfaces, or by the grid's outer face.
    Rgb absorbed(size_t slot, size_t cell, int side) const;

private:
    struct SurfaceSample {
        Vec3 position, normal;  // normal: the geometric normal of the triangle
        double area = 0;
        Rgb kd{0.0};
        bool twoSided = false;  // an open mesh's face: its back reflects too
    };
    struct Source {
        // Per side (as absorbed()), per cell: the flux absorbed there.
        std::array<std::vector<Rgb>, 6> absorbed;
        Report report;
    };

    double transmittance(int axis, int i, int j, int k) const;
    // The product of the transmittances of the faces crossed from cell
    // `from` to cell `to`, one axis after another.
    double transmittanceBetween(std::array<int, 3> from, const std::array<int, 3>& to) const;
    // Adds a triangle's area inside each face box along `axis`, times
    // `cosine` (|n·axis|), over the face's area, to the geometry volume.
    void addCoverage(const std::vector<Vec3>& triangle, double cosine, int axis);
    // The share of side `side` of cell c that surfaces cover (1 on the
    // grid's outer faces), and the irradiance there of a surface facing
    // into c: the flux absorbed over the covered area; 0 where nothing is.
    double coverage(const std::array<int, 3>& c, int side) const;
    Rgb faceIrradiance(const Source& source, const std::array<int, 3>& c, int side) const;
    void propagate(Source& source, std::vector<ShRgb> moving) const;
    void finishStats(double seconds);

    const Scene& scene_;
    PropagationVolumeSettings settings_;
    PropagationGrid grid_;
    std::vector<SurfaceSample> samples_;
    // Per axis, per face between a cell and its +axis neighbour (cell
    // layout, the last layer along the axis unused): the blocked share.
    std::array<std::vector<float>, 3> blocking_;
    std::vector<std::unique_ptr<Source>> sources_;
    IndirectStats stats_;
};

}  // namespace ml
