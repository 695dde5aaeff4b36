// Virtual point lights with negative lights for their occlusion, after
// Cochran & Steele, "Second-order illumination in real-time" (2007), which
// extends Keller's instant radiosity: the indirect light of a bounce is the
// light of N point lights standing on the surfaces that reflect the source,
// and the light those point lights would send through occluders is taken
// away again by negative point lights, so no light needs a shadow test.
//
// Placing the lights (their §3.1). The paper renders the scene from its one
// spotlight and picks N texels by a Halton sequence over the spotlight's
// sphere of directions: points in proportion to the light the spotlight
// sends there. Here the source is a bounce's cache meshes (every light's
// direct mesh, or an indirect mesh), so the lights are picked over those
// meshes' triangles in proportion to the power they reflect,
// Φ_t = Kd · area · mean(E) (Kd: the scene triangle's mean albedo under the
// cache triangle), by the Halton sequence: base 2 picks the triangle from
// the power's distribution (its remainder the corner term below), bases 3
// and 5 the point, with a density ∝ Kd·E(y) across the triangle (E is
// linear there: a mix of three densities ∝ one barycentric each). Every
// light then carries the same luminous power, Φ_i = Lo(y)·π·a_i with
// a_i = 1/(N·p(y)) the area it stands for, so the lights' power adds up to
// the source's reflected power exactly (in luminance; per channel for grey
// surfaces). Each is a cosine emitter about its surface's normal.
//
// Irradiance (§3.2): E(x) = Σ Φ_i cosθ_x cosθ_i / (π (d² + a_i/π)). The
// paper leaves 1/d² as it is. Here d² gains a_i/π, the squared radius of
// the disc of area a_i the light stands for: the on-axis irradiance of such
// a disc exactly, bounded by π·Lo where a point light's irradiance is not.
// The consequence: light from a VPL nearer than a few disc radii is too
// low, by at most a_i/(π d² + a_i) (a furnace wall 1 m from the nearest
// other wall, 1,024 lights over 24 m²: 0.7%), so corners and contacts,
// lit by lights on the surfaces beside them, are darker than they should
// be (a wall 3 mm above the Cornell box's floor: a third of its light with
// 1,024 lights); and a point on a light's own plane gets nothing from it
// (cos = 0), as from the surface.
//
// Beyond the paper: the clamp's bias compensated (Kollig & Keller's idea,
// with the cache in place of their paths). What the lights' mean leaves out
// is exactly ∫ Lo(y) cosθ_x · (a(y)/π)/(d² + a(y)/π) dω over the directions
// from x, a(y) = 1/(N p(y)) the area a light at y stands for: a gather
// weighted towards what is near, which `nearRays` cosine-weighted, jittered
// Embree rays estimate, reading the source's cached irradiance where they
// land (as the ray gather does; mirrors and glass are not followed). It
// sees true visibility, so a contact's light is right, at the cost of
// rays: each estimate is then noisy, its mean over seeds the answer.
//
// Occlusion (§3.3): simple indirect light I_s ignores visibility; the true
// I_c = I_s − I_n, and negative lights estimate I_n. The paper takes the
// camera's visible points, computes at each the light from the VPLs behind
// it (the normal negated), i.e. the light that would leave through it, and
// picks negative lights among them by the Halton sequence, each at such a
// point, emitting that light about the mean direction it travels. Here, with
// no camera (an estimate may be asked anywhere), and with Embree at hand:
//   - candidate points are spread over every side of the scene's surfaces
//     (the front, and the back of open meshes), uniformly by area, by the
//     Halton sequence (`sites` of them);
//   - at each, the light arriving from the VPLs in front of that side,
//     counted only from VPLs a ray reaches (Embree): the light whose first
//     surface this is. Every path VPL → x crossing a surface before x has
//     exactly one first crossing, so the negative lights at first crossings
//     take each blocked path away once. The paper's exit points, with no
//     visibility, subtract a path once per surface it crosses;
//   - it continues through the surface about its mean direction (weighted
//     by the light, as the paper's), and a candidate whose continuation
//     reaches no surface (the back of an outer wall: the light leaves the
//     scene) is dropped, so the negative lights are spent where they shade;
//   - the negative lights are picked among the candidates in proportion to
//     that light, by the Halton sequence, each carrying the same luminous
//     power about its mean direction. The paper's lobe is a cosine, whose
//     directions' mean resultant length (E[cos]) is 2/3; light through a
//     block's face from a few walls is more focused than that (in the
//     Cornell box the lobes' mean m is 2, ρ = 3/4), and a cosine spreads
//     what it takes away over places the light never went (the test's floor
//     point: 1.33 of the path tracer with cosines, 1.20 with matched lobes). Here the lobe is cos^m with m set so that its
//     E[cos] = (m + 1)/(m + 2) is the light's own resultant length ρ,
//     m = (2ρ − 1)/(1 − ρ), within [0, 64] (`matchSpread`).
// What stays approximate: the light through a point goes on in the
// directions it came from, which a lobe about their mean replaces (a
// shadow's edge is blurred and its depth off by the lobe's spread), and
// the sum, which may fall below zero where the negative lights overshoot,
// is clamped at 0 per channel.
#pragma once

#include "cache/IndirectEstimator.h"
#include "core/Scene.h"

#include <memory>
#include <vector>

namespace ml {

class EmbreeScene;
class MeshIrradianceLookup;

struct VirtualPointLightSettings {
    // Positive lights per source at importance 1; the paper's 100..450. A
    // weaker source (importance s) gets lights × s, at least min(lights, 32).
    int lights = 256;
    // Negative lights as a share of the positive ones (the paper's 1:2,
    // Table 1), and candidate points per positive light they are picked from.
    double negativeShare = 0.5;
    int sitesPerLight = 4;
    // Negative lights' lobes as focused as the light they take away (m from
    // its spread, see above); false: the paper's cosine.
    bool matchSpread = true;
    bool visibility = true;  // false: no negative lights (the paper's simple indirect light I_s)
    // Rays per estimate compensating the clamp near x (above); 0: none, the
    // clamp's bias stays (the paper's own). Typical 16..64.
    int nearRays = 16;
    // Threads a batch of estimates is spread over (estimateBatch; each
    // point's sum is on its own, so the results do not depend on it). The
    // real-time stand-in uses every core (realtimeEstimatorFactory); inside
    // the cache's workers, which already do, one.
    int threads = 1;
    void validate() const;   // InputError unless 1 <= lights <= 65536, 0 <= negativeShare <= 4, 1 <= sitesPerLight <= 64, 0 <= nearRays <= 4096, 1 <= threads <= 1024
};

// A point light standing for a patch of surface: it emits flux Φ in a lobe
// cos^m about `axis` (intensity Φ·(m + 1)/(2π)·cos^m; m = 1: a diffuse
// surface's cosine, Φ·cos/π), and stands for `area` (m²) of surface, the
// disc whose on-axis irradiance bounds its own.
struct VirtualLight {
    Vec3 position{0.0};
    Vec3 axis{0.0, 1.0, 0.0};  // unit
    Rgb flux{0.0};             // W
    double area = 0;           // m²
    double exponent = 1;       // m
};

// Irradiance at x (unit normal n) from these lights, unclamped and without
// visibility: Σ Φ (m + 1)/2 cos^m θ_l cosθ_x / (π (d² + area/π)).
Rgb virtualLightIrradiance(const std::vector<VirtualLight>& lights, const Vec3& x, const Vec3& n);

// The i-th point (i ≥ 0) of the radical inverse in `base`: Halton's Φ_base(i).
double radicalInverse(uint32_t base, uint64_t i);

// A point of a triangle with density ∝ Σ_k f_k b_k (barycentrics b, weights
// f_k ≥ 0, not all 0) from three uniforms: `pick` chooses the corner term k
// in proportion to f_k, `u` and `v` place the point with density ∝ b_k
// (b_k of a Beta(2,2) by its inverse, the rest uniform across). Returns the
// barycentrics.
Vec3 sampleLinearDensity(const Vec3& f, double pick, double u, double v);

class VirtualPointLights final : public IndirectEstimator {
public:
    // `scene` must outlive the lights. Builds its own Embree scene.
    VirtualPointLights(const Scene& scene, const VirtualPointLightSettings& settings);
    ~VirtualPointLights() override;

    std::string name() const override;
    // The update: places the positive lights over these meshes' reflected
    // power, then (with visibility) the negative ones. One thread; the
    // cache's SamplerPool gives every thread lights of its own, and the
    // Halton sequence places the same lights in each.
    void setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance = 1.0) override;
    void releaseSource(size_t slot) override;
    // The lights' sum, plus the near field's compensation when nearRays > 0
    // (jittered from `seed`; without it the seed is not used).
    Rgb estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override;
    // The same for every request, on `threads` threads (each result what
    // estimate gives for it).
    void estimateBatch(size_t slot, const std::vector<SampleRequest>& requests,
                       std::vector<VertexSample>& results) override;
    IndirectStats stats() const override;

    const std::vector<VirtualLight>& positive(size_t slot) const;
    const std::vector<VirtualLight>& negative(size_t slot) const;
    // What the source's surfaces reflect in all, Σ Kd·∫E dA over its
    // meshes' triangles (W), which the positive lights carry.
    Rgb reflectedPower(size_t slot) const;
    // Cache triangles whose scene surface no ray found (their light is left
    // out), over all sources built.
    uint64_t unplacedTriangles() const { return unplaced_; }

private:
    struct Source {
        std::vector<VirtualLight> positive, negative;
        Rgb power{0.0};
        int placed = 0;  // N, the positive lights asked for: a(y) = lum(power)/(N lum(Kd E(y)))
        // The source meshes, looked up by the compensation's rays.
        std::vector<IrradianceMeshCopy> meshes;
        std::vector<std::unique_ptr<MeshIrradianceLookup>> lookups;
    };
    struct Side {
        uint32_t mesh = 0, triangle = 0;
        bool back = false;  // the triangle's back (an open mesh's other side)
    };

    const Source& source(size_t slot) const;
    std::vector<VirtualLight> placePositive(const std::vector<IrradianceMeshCopy>& irradiance, int count, Rgb& power);
    std::vector<VirtualLight> placeNegative(const std::vector<VirtualLight>& positive, int sites, int count) const;
    // Whether light leaving `origin` along `direction` meets a surface that
    // is lit from that side (anything but a closed mesh's inside).
    bool reachesASurface(const Vec3& origin, const Vec3& direction) const;
    // estimate's value, touching nothing (thread-safe).
    Rgb irradianceAt(const Source& source, const Vec3& x, const Vec3& n, uint32_t seed) const;
    // What the clamp leaves out near x (see above), from nearRays rays.
    Rgb nearCompensation(const Source& source, const Vec3& x, const Vec3& n, uint32_t seed) const;

    const Scene& scene_;
    VirtualPointLightSettings settings_;
    std::unique_ptr<EmbreeScene> rays_;
    std::vector<char> closed_;         // per scene mesh: its back is an inside
    std::vector<Side> sides_;          // every side a negative light may stand on
    std::vector<double> sideCdf_;      // their areas, cumulative, normalised
    double sideArea_ = 0;              // m², all sides
    std::vector<std::unique_ptr<Source>> sources_;
    IndirectStats stats_;
    uint64_t unplaced_ = 0;
};

}  // namespace ml
