// Caustic irradiance on a cache mesh of its own: light that reached a
// diffuse surface through or off mirrors and glass (CausticPhotons), held
// at the vertices of a mesh laid over the scene like the indirect ones and
// shown through the same path as an indirect bounce (it is indirect light:
// CacheSnapshot::indirect holds it after the bounces).
//
// Progressive photon mapping (Hachisuka, Ogaki and Jensen 2008) with the
// mesh's vertices as the measurement points. Each vertex i keeps a radius
// R_i, a photon count N_i and a flux τ_i. A round traces P photons; the M
// photons that land within R_i of the vertex (in 3D, arriving on its side:
// their normal within 45° of its normal) with power Φ update them by
//   N' = N + αM,   R'² = R² (N + αM)/(N + M),   τ' = (τ + Φ)(N + αM)/(N + M),
// and the vertex's irradiance is τ / (π R² · photons emitted). R shrinks
// while N grows without bound (α < 1), so the estimate's bias (the kernel's
// blur, its overlap past a surface's border) and its noise (≈ 1/√N) both go
// to zero: it converges, round after round, to the caustic irradiance at
// the vertex. Between vertices the mesh interpolates linearly, so a caustic
// is resolved to the mesh's edge (CausticSettings::edgeFraction), not finer:
// the mesh is not refined.
#pragma once

#include "CausticPhotons.h"
#include "IrradianceCache.h"

#include <cstdint>
#include <memory>
#include <optional>

namespace ml {

class EmbreeScene;
namespace detail {
class PointGrid;
}

struct CausticSettings {
    // The caustic mesh's edges, at most this fraction of the scene's
    // diagonal; typical 1/64 (CornellBox-Water: about 27,000 vertices).
    // Finer resolves a focused caustic better but costs bounce 1's gather,
    // which looks the mesh up at every ray's end: at 1/128 (108,000
    // vertices) its gathers took 2.9 ms instead of 1.2 ms without it.
    double edgeFraction = 1.0 / 64;
    // Photons emitted per round; typical 2^15 (about 0.15 s on two cores in
    // CornellBox-Sphere, as long as a few rounds of direct light).
    size_t photonsPerRound = size_t(1) << 15;
    // Each vertex's first kernel radius, a fraction of the scene's
    // diagonal: the mesh's edge, so that a caustic spot between vertices
    // reaches the nearest ones, and a broad caustic (a mirror sphere's
    // light over a ceiling) gathers enough photons early (1/128 gathered
    // too few); it shrinks as they come.
    double radiusFraction = 1.0 / 64;
    // Progressive photon mapping's α in (0, 1): the share of new photons a
    // round keeps (Hachisuka et al. use 0.7).
    double alpha = 0.7;
    // Converged when the relative noise of the caustic (its vertices'
    // 1/√N, weighted by their irradiance²) is below this; halved at each
    // refinement level (tighten).
    double tolerance = 0.02;
    void validate() const;  // InputError naming the field out of range
};

class CausticCache {
public:
    // Finds the lights' targets (CausticPhotons) and, when there are any,
    // lays the mesh. `scene` must outlive this object.
    CausticCache(const Scene& scene, const CausticSettings& settings = {});
    ~CausticCache();
    CausticCache(const CausticCache&) = delete;
    CausticCache& operator=(const CausticCache&) = delete;

    // Some light sees a specular object (otherwise there is no mesh and no
    // round does anything).
    bool active() const;
    // CausticPhotons::describe().
    std::string describe() const;
    const CausticSettings& settings() const { return settings_; }

    // One round: photonsPerRound photons, numbered on from the last round's
    // (a run repeats bit for bit), and every vertex updated.
    void round(uint32_t seed);
    uint64_t rounds() const { return rounds_; }
    uint64_t photonsEmitted() const { return emitted_; }
    size_t vertexCount() const;

    // The relative noise (see CausticSettings::tolerance); 1 before the
    // first round, 0 when no photon has landed anywhere.
    double estimatedError() const;
    // Under the tolerance at the current level.
    bool converged() const;
    // One more refinement level (tolerance halved), up to
    // IrradianceCache::kMaxRefinementLevel; false at the last one.
    bool tighten();
    int level() const { return level_; }

    // The mesh with each vertex's caustic irradiance (W·m⁻²), its photon
    // count as samples and τ/(πR²·emitted)/√N as standard error.
    IrradianceMeshCopy copyMesh() const;

private:
    const Scene& scene_;
    CausticSettings settings_;
    std::unique_ptr<EmbreeScene> rays_;
    std::unique_ptr<CausticPhotons> photons_;
    IrradianceMeshCopy mesh_;        // geometry only; irradiance filled by copyMesh
    double firstRadius_ = 0;         // every vertex's kernel radius before its first photon, scene units
    std::unique_ptr<detail::PointGrid> vertices_;  // the mesh's vertices, binned by firstRadius_
    std::vector<double> radius2_;    // R² per vertex, scene units²
    std::vector<double> count_;      // N per vertex
    std::vector<Rgb> flux_;          // τ per vertex
    uint64_t emitted_ = 0;
    uint64_t rounds_ = 0;
    int level_ = 0;
};

}  // namespace ml
