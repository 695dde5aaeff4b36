// Direct light for the cache meshes when lights share (LightCoverage.h):
// mesh l < L holds w_l·E_l, mesh L (the shared one) Σ_l (1 − w_l)·E_l.
//
// The shared mesh's estimator is a control variate, like the light
// sampler's own: with U_l the unoccluded irradiance of light l at the point
// (Lambert's closed form, exact) and O_l = U_l − E_l its occluded part,
//   Σ (1 − w_l) E_l = Σ (1 − w_l) U_l − Σ (1 − w_l) O_l,
// where the first sum is computed exactly and the second estimated from K
// lights drawn with probability p_l ∝ (1 − w_l) U_l, each O_l from the
// wrapped sampler (O_l = U_l − its estimate of E_l): unbiased, and exact
// wherever nothing occludes the drawn lights (the sampler answers those on
// the CPU, exactly U_l). Noise comes only from occlusion, where refinement
// resamples it away. To that end each estimate reports its draws' scatter
// as its own variance (VertexSample::ownVariance): a vertex sampled once
// counts as exact otherwise (outside penumbrae the per-light samplers are),
// and a floor under 192 panels, whose draws are each all or nothing where
// the partition and the desks hide some of the lights, kept blotches of
// ±10% that no resample removed (that office at 20 s: direct light's share
// of the error 4.30% before, 2.24% with K = 4 and the own variance).
//
// Where more lights are left to draw than K (the 48- and 192-panel
// offices' floors, lit by tens of panels each), their occluded part comes
// from R shadow rays instead (rayDraws, CacheSettings::sharedRays, 256 by
// default): each goes to a light drawn as above, stratified, and to a point
// y drawn uniformly on its area, and adds (1 − w_l) L_l g(y) (1 − V) /
// (R p_l), g(y) = A cos θx cos θy / r²: unbiased, and zero for every light
// in full view. A drawn pair was all or nothing for one light where the
// desks hide some; a ray is as much so, but 256 of them took half the time
// of up to 16 pairs (227 µs an estimate against 449 µs, 192 panels).
// Punctual lights take their one exact ray; a textured light's ray adds
// (1 − w_l) L̄_l g(y) (1 − τ(y) V) / (R p_l), τ = L(y) / L̄_l (nonzero in
// view too, as the pairs' O_l); curved lights are still drawn as pairs.
// The rays are Embree's, made for each sampler at its first such
// estimate, as the ray gather's.
// Measured on the 192-panel office (render office:panels=16x12,panelsize=0.4
// --width 320 --height 180 --time 20, direct light's share of the image's
// error against depth-1 and full references): 2.23-2.24 %² with 16 pairs,
// 0.57-0.59 %² with 256 rays (0.71 %² with 64, 0.51 %² with 1,024); the
// image's 2.45-2.46% → 1.93%.
//
// Lights answered without the GPU are not drawn. Before drawing, the
// wrapped sampler is asked for the kAskedLights brightest (1 − w_l) U_l at
// the point whether it answers them without the GPU (sampleWithoutGpu: in
// the way of nothing, E_l = U_l; hidden behind one polygon, E_l = 0; a few
// microseconds each); those lights' O_l is then known and subtracted
// exactly, and the K draws go to the rest, p_l ∝ (1 − w_l) U_l among them.
// Still unbiased, and never noisier: a draw's variance is that of the
// occluded share among the lights drawn from, times the square of their
// light. Under a desk most lights are hidden behind its top and a few
// glimpsed past its edge; on the open floor most are in view and a few are
// hidden by the partition: drawn from all, each draw was all or nothing
// (blotches on the floor); drawn from the uncertain few, far less. Which
// lights are known depends on the point alone and is kept for the vertex's
// next samples. A first pass (VertexSampler::firstSamples) asks none.
//
// A textured light (EmitterTexture.h): U_l is still Lambert's form at the
// light's mean radiance, now only a control for the textured E_l the wrapped
// sampler estimates, so O_l = U_l − E_l may be negative (the point sees the
// light's brighter part) and is not clamped; such a light's shared estimate
// is unbiased but no longer exact where nothing occludes.
#pragma once

#include "DirectSampler.h"
#include "LightCoverage.h"
#include "core/EmitterTexture.h"
#include "core/raytrace/EmbreeScene.h"

#include <array>
#include <cstring>
#include <memory>
#include <unordered_map>

namespace ml {

class SharedLightSampler final : public DirectSampler {
public:
    // `lights`: K, the lights drawn per shared estimate; `firstLights` in a
    // first pass (firstSamples). Where no more than K lights are left to
    // draw, each is taken once instead, and the estimate is exact.
    //
    // K: at a point under many lights, each estimate also computes every
    // light's U_l and its CDF, so a draw costs a fraction of the estimate:
    // more draws an estimate take less time per unit of variance. Measured
    // on the 192-panel office (render office:panels=16x12,panelsize=0.4
    // --width 320 --height 180 --time 20; direct light's share of the
    // error against depth-1 and full references), K = 4, 8, 16 in every
    // pass: 2.24%, 1.82%, 1.73%. A first pass keeps 4 (its estimates are
    // the first complete image's wait) and each estimate's work is its K,
    // so those weigh a quarter in a vertex's mean: 1.78% (cache/README.md).
    SharedLightSampler(const Scene& scene, std::shared_ptr<const LightCoverage> coverage,
                       std::unique_ptr<DirectSampler> perLight, int lights = kDraws, int firstLights = kFirstDraws,
                       int rayDraws = kRayDraws);
    ~SharedLightSampler() override;
    static constexpr int kDraws = 16, kFirstDraws = 4;
    static constexpr int kRayDraws = 256;  // CacheSettings::sharedRays
    // The brightest lights asked. 48 panels at 5.3 s (render office:panels=8x6, 320x180), direct light's error /
    // the image's: asking none, 3.86% / 5.48%; 4 lights, 2.74% / 4.75%; 8, 1.46% / 4.33%; 16, within the
    // reference's noise / 3.99%; all (~40), within noise / 6.67%, for asking took the indirect gathers' time.
    static constexpr int kAskedLights = 16;

    std::string name() const override;
    VertexSample sample(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed) override;
    // Where the wrapped sampler answers every pair it needs without the GPU
    // (for the shared mesh: every light drawn).
    bool sampleWithoutGpu(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed, VertexSample& out) override;
    DirectPhaseTimes phaseTimes() const override { return perLight_->phaseTimes(); }
    // A first pass draws from every light, asking none: asking is an
    // investment over a point's later samples and its refined neighbours,
    // and the first complete image would wait for it and for the GPU pairs
    // its draws then need (asking in the first pass too, bench lights' 12
    // panels reached 10% at 2.8 s instead of 1.8 s).
    void firstSamples(bool first) override { firstSamples_ = first; }

private:
    // The estimate of mesh `mesh`, each light's sample from
    // `take(light, seed, sample)`, which may decline (false): then false.
    template <class Take>
    bool estimate(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed, Take take, VertexSample& out);
    template <class Take>
    bool estimateShared(const Vec3& x, const Vec3& n, uint32_t seed, Take take, VertexSample& out);

    // A light reaching the point, carried (partly) by the shared mesh.
    struct Reaching {
        uint32_t light;
        double shared;  // 1 − w_l
        double y;       // (1 − w_l) Y(U_l), its draw weight
        Rgb unoccluded; // U_l
    };
    void reaching(const Vec3& x, const Vec3& n, Rgb& total, double& all);
    // The lights at (x, n) the wrapped sampler answered without the GPU,
    // from reaching_ as reaching() left it for that point: asked once per
    // point and kept (a vertex is sampled many times; what is
    // kept depends on the point alone, so no result depends on it).
    struct Known {
        std::vector<uint32_t> lights;  // increasing
        Rgb occluded{0.0};             // Σ (1 − w_l) O_l over them
        double visible = 0;            // Σ (1 − w_l) Y(U_l) · visibility over them
    };
    const Known& known(const Vec3& x, const Vec3& n, uint32_t seed);
    using Key = std::array<uint64_t, 6>;
    struct KeyHash {
        size_t operator()(const Key& k) const {
            uint64_t h = 0x9e3779b97f4a7c15ull;
            for (uint64_t v : k) h = (h ^ v) * 0x100000001b3ull + (h >> 29);
            return size_t(h);
        }
    };
    static uint64_t bits(double v) {
        uint64_t b;
        std::memcpy(&b, &v, sizeof b);
        return b;
    }
    // Points kept (each under 200 bytes: some 25 MB at most per sampler).
    static constexpr size_t kMaxKnown = size_t(1) << 17;
    std::unordered_map<Key, Known, KeyHash> known_;

    const Scene& scene_;
    std::shared_ptr<const LightCoverage> coverage_;
    std::unique_ptr<DirectSampler> perLight_;
    int draws_, firstDraws_, rayDraws_;
    // Per light, its triangles' cumulative areas (rays' points are drawn by area).
    std::vector<std::vector<double>> areaCdf_;
    std::unique_ptr<EmbreeScene> rays_;  // made at the first estimate drawn by rays
    bool rayDrawn(uint32_t light) const;
    bool shadowRay(uint32_t light, const Vec3& x, const Vec3& n, uint32_t seed, double& g, Rgb& tau) const;
    bool firstSamples_ = false;
    std::vector<std::pair<uint32_t, double>> weights_;  // scratch
    std::vector<Reaching> reaching_;  // scratch
    std::vector<double> order_;       // scratch
    // A CDF over reaching_ entries, by their draw weights y.
    struct DrawCdf {
        std::vector<double> steps;    // cumulative y
        std::vector<size_t> entries;  // the reaching_ entry of each step
        void clear() { steps.clear(), entries.clear(); }
        void add(size_t entry, double y) {
            steps.push_back((steps.empty() ? 0.0 : steps.back()) + y);
            entries.push_back(entry);
        }
        size_t size() const { return steps.size(); }
        double total() const { return steps.empty() ? 0.0 : steps.back(); }
        // Draw d of `count`, stratified: u in [d/count, (d+1)/count) of the
        // total, its offset from the hash of `s`. The step drawn, and its
        // weight 1/(count p), p the step's share of the total.
        std::pair<size_t, double> pick(uint32_t s, size_t d, size_t count) const;
    };
    DrawCdf pairCdf_, rayCdf_;  // scratch: the lights drawn by pairs and by rays
    std::vector<EmitterTexture> emitters_;  // per light, its emission texture (untextured: weight 1)
};

// U_l at x: light l's irradiance with nothing in the way, from the light's
// triangles whose emitting side faces x, Lambert's formula at x itself (as
// the light sampler's control variate computes it).
Rgb unoccludedIrradiance(const Light& light, const Vec3& x, const Vec3& n);

}  // namespace ml
