// The irradiance volume of Nijasure, Pattanaik & Goel (2005): a uniform
// grid of probes over the scene; each probe captures the radiance arriving
// from every direction, keeps it as order-2 spherical harmonics (9
// coefficients per channel, core/SphericalHarmonics.h), and a surface point
// takes the trilinear blend of its 8 surrounding probes' fields, convolved
// with the cosine for its normal. Bounce after bounce: the IndirectSolver
// gives bounce n−1's mesh as source n−1, and the probes capture it again.
//
// Capture. The paper rasterises a 16×16 cube map per probe on the GPU and
// projects its pixels, each weighted by its solid angle (their eq. 2). Here
// the same cube map is traced: one Embree ray per texel centre from the
// probe, reading the cache meshes' radiance where it lands exactly as the
// ray gather does (Kd/π × the source's irradiance on the side the ray
// arrives from, black inside a closed mesh). On this machine's llvmpipe the
// two cost about the same (bench indirect prints both: a 16-pixel hemicube
// of the radiance proxy, five of a cube map's six draws with half its
// pixels, 0.64-0.72 ms; a probe's 1,536 rays 0.6-1.1 ms, over three runs on
// a shared machine), and the rays read the cache itself rather than a proxy
// resampled at voxels. The grid's fields are arrays of
// ShRgb, one per probe (the paper's 3D textures, on the CPU).
//
// Beyond the paper (its §6 weights probes 0/1 by a shadow cube map, on the
// CPU, and leaves it out of its GPU path):
//   - visibility: each of the 8 probes counts only if a ray from the point
//     (lifted off its surface) reaches it, so light does not leak through
//     a wall between a point and a probe on its other side;
//   - facing: a probe in front of the surface weighs more than one behind
//     it, ((1 + cos)/2)² + 0.05 (cos between the normal and the direction
//     to the probe): a probe behind sees the surface's own back half;
//   - inside: a probe whose rays meet back faces over more than half of the
//     sphere, or the inside of a closed mesh over a quarter, is inside
//     something solid (or behind a wall, outside the scene) and never used;
//   - probes on the bounds: the outer layers stand 5% of the spacing inside
//     the scene's bounds, not half a cell, so a room's walls, floor and
//     ceiling interpolate between probes that see what they see;
//   - axis correction: order 2 rings, and a probe just above a directly
//     lit floor, which sends it 8-20× the light of the hemisphere
//     above, gets 12-50% too little irradiance facing up (the l ≥ 4 band
//     it cannot hold: a few per cent of the floor's irradiance). Each probe
//     also keeps, for the 6 axis normals, the exact irradiance of its rays
//     minus the SH's; a normal n adds Σ n_a² × the residual of the axis on
//     its side (an ambient cube of residuals), so axis-aligned surfaces get
//     their probes' exact irradiance and others a blend.
// A point none of whose 8 probes is usable (a crevice narrower than the
// spacing) takes the blend without visibility, and 0 when all 8 are inside.
//
// Error. Away from the bounds a probe stands up to a cell's diagonal from
// the point and sees the scene from there: a block's top takes the layer
// above it (60 mm up at 8 probes in the Cornell box, 42% less light facing
// the dark ceiling), a corner probes that see more of the room than it
// does (bench indirect measures it against the path tracer); order 2 adds
// a few per cent of its own where the axis correction does not reach.
#pragma once

#include "cache/IndirectEstimator.h"
#include "core/Scene.h"
#include "core/SphericalHarmonics.h"

#include <array>
#include <map>
#include <memory>
#include <vector>

namespace ml {

class EmbreeScene;
class MeshIrradianceLookup;

struct IrradianceVolumeSettings {
    // Probes along the scene's longest side, its ends included; the other
    // sides get as many as keep the cells near cubes (at least 1). The
    // paper's is 4; typical 4..16 (Cornell box at 8: 512 probes, 78 mm apart).
    int probes = 8;
    // Rays per cube-map face side per probe: 6·faceSize² rays. The paper's 16.
    // A weaker bounce (importance s) gets faceSize·√s, at least 8 (or
    // faceSize if smaller): its light is a fraction s of bounce 1's, so its
    // aliasing is too.
    int faceSize = 16;
    bool visibility = true;      // weight probes by a ray test from the point
    bool skipInside = true;      // drop probes inside solid objects
    bool axisCorrection = true;  // add the SH's residual at the 6 axis normals (6 more RGB per probe)
    // Threads capturing the probes (parallelFor, a probe at a time; the
    // fields are the same for any count). 1: the calling thread alone, as
    // inside the cache's workers, which already use every core. The
    // real-time stand-in uses one per core: its estimate is what the next
    // frames show (realtimeEstimatorFactory).
    int threads = 1;
    void validate() const;  // InputError unless 1 <= probes <= 64, 2 <= faceSize <= 128, 1 <= threads <= 1024
};

// The probe grid laid over bounds: probes at the corners of cells of
// `cell` per axis, the outer layers kInset of the spacing inside the
// bounds' faces. Where walls lie on the bounds (a room's floor, walls and
// ceiling, most of its surface), their points interpolate between probes
// 5% of a cell in front of them instead of taking the light of probes half
// a cell away (bench indirect --quick, 8 along the Cornell box's side: 7.6%
// RMS from the path tracer against 18.9% with probes at cell centres). Not
// closer: a probe must not stand in the gap behind something mounted on a
// wall (the Cornell box's light hangs 0.5 mm below its ceiling; at 1e-4 of
// the side the probes above it saw its dark back, 5× too little light).
struct ProbeGrid {
    static constexpr double kInset = 0.05;  // of the spacing
    std::array<int, 3> dims{1, 1, 1};
    Vec3 lo{0.0}, cell{0.0};  // the first probe, and the spacing (0 on an axis of one probe)

    ProbeGrid() = default;
    ProbeGrid(const Bounds3& bounds, int probesAlongLongest);
    size_t count() const { return size_t(dims[0]) * size_t(dims[1]) * size_t(dims[2]); }
    size_t index(int i, int j, int k) const { return (size_t(k) * size_t(dims[1]) + size_t(j)) * size_t(dims[0]) + size_t(i); }
    Vec3 position(int i, int j, int k) const { return lo + Vec3(i, j, k) * cell; }
    // The 8 probes around x (indices into the grid, repeated where an axis
    // has one probe) and their trilinear weights; x beyond the outer probes
    // takes the outer ones (clamped).
    void corners(const Vec3& x, std::array<size_t, 8>& index, std::array<double, 8>& weight,
                 std::array<Vec3, 8>& position) const;
};

// The directions and solid angles of a cube map's texel centres: 6·size²
// unit vectors whose weights add up to 4π exactly (their eq. 2's A(ω)).
// With each texel, its exact ∫ max(0, ω·a) dω for the 6 signed axes a
// (+x, −x, +y, −y, +z, −z), which add up to π per axis: the irradiance
// the texels give a surface facing a, exact for radiance constant over
// each texel (the hemicube's form factors, TriangleGather.h).
struct CubeMapDirections {
    std::vector<Vec3> direction;
    std::vector<double> solidAngle;
    std::vector<std::array<double, 6>> axisCosine;
    explicit CubeMapDirections(int size);
};

class IrradianceVolume final : public IndirectEstimator {
public:
    // `scene` must outlive the volume. Builds its own Embree scene.
    IrradianceVolume(const Scene& scene, const IrradianceVolumeSettings& settings);
    ~IrradianceVolume() override;

    std::string name() const override;
    // Captures every probe from these meshes (the update: all probes, one
    // thread; the cache's SamplerPool gives every thread a volume of its own,
    // and each captures the same probes).
    void setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance = 1.0) override;
    void releaseSource(size_t slot) override;
    // Deterministic: the seed is not used (the probes are captured once).
    Rgb estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override;
    IndirectStats stats() const override;

    const ProbeGrid& grid() const { return grid_; }
    // Probes of source `slot` found inside solid objects; whether probe
    // `index` is one.
    size_t insideProbes(size_t slot) const;
    bool insideProbe(size_t slot, size_t index) const;
    // Estimates so far whose 8 probes were all hidden from the point (they
    // took the blend without visibility) or all inside (they gave 0).
    uint64_t unseenFallbacks() const { return unseen_; }
    uint64_t insideFallbacks() const { return allInside_; }
    // The captured field of probe `index` of source `slot`.
    const ShRgb& probe(size_t slot, size_t index) const;
    // Probe `index`'s irradiance for unit normal n: its field's, plus the
    // axis correction when on; what estimate() blends, unclamped.
    Rgb probeIrradiance(size_t slot, size_t index, const Vec3& n) const;

private:
    // What one probe's rays saw.
    struct Capture {
        ShRgb field;
        std::array<Rgb, 6> axisIrradiance{};  // of these rays, for normals +x, −x, +y, −y, +z, −z
        double backSolidAngle = 0;            // sr of back faces seen
        double closedBackSolidAngle = 0;      // of those, the insides of closed meshes
    };
    Capture capture(const Vec3& p, const CubeMapDirections& directions,
                    const MeshIrradianceLookup& lookup) const;

    struct Source {
        std::vector<ShRgb> fields;  // one per probe, ProbeGrid::index order
        // Per probe, exact minus SH irradiance for normals +x, −x, +y, −y,
        // +z, −z (zero without the axis correction).
        std::vector<std::array<Rgb, 6>> residual;
        std::vector<char> inside;   // per probe: inside a solid object
        size_t insideCount = 0;
    };

    const Scene& scene_;
    IrradianceVolumeSettings settings_;
    ProbeGrid grid_;
    // The cube maps for each face size in use (weaker bounces use smaller ones).
    std::map<int, CubeMapDirections> directions_;
    std::unique_ptr<EmbreeScene> rays_;
    std::vector<char> closed_;  // per scene mesh: its back is an inside (black)
    std::vector<std::unique_ptr<Source>> sources_;
    IndirectStats stats_;
    uint64_t unseen_ = 0, allInside_ = 0;
};

}  // namespace ml
