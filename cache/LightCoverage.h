// Where each light keeps a cache mesh of its own (the many-lights issue).
//
// One mesh per light laid over the whole scene makes cost and memory grow as
// lights × scene. But in a room of many luminaires most lights give a point
// a small share of its light. So each light l gets a weight w_l(x) in
// [0, 1]: its own mesh holds w_l·E_l and covers only the faces where w_l > 0;
// one shared mesh, laid over the whole scene, holds Σ_l (1 − w_l)·E_l,
// sampled by choosing lights in proportion to their unoccluded irradiance
// (SharedLightSampler). The two add up to every light's whole light at any
// point, whatever w is: w decides only who carries it. Nothing is dropped.
//
// The weight comes from a bound on each light's share of the direct light,
// from its power, distance and orientation only (no visibility):
//   B_l(p) = Φ_l · max(0, (N_l·v + r_l) / (|v| + r_l)) / (π (|v|² + r_l²)),
// v = p − centroid, r_l = √(A_l/π) the light's radius, N_l its normal (a
// non-planar light counts as facing every way), and for a punctual light
// π I_l(ω)/(s d)² (its intensity toward p, s metres per unit) or π E⊥ for a
// directional one; share s_l = B_l / max(Σ_k
// B_k, a quarter of the mean of Σ_k B_k over the scene): where little direct
// light arrives at all, no light needs a mesh of its own;
// w_l = 1 where s_l ≥ τ, 0 below 0.8τ, linear in between (τ =
// CacheSettings::lightShare). The ramp is narrow because a light in it
// pays for a mesh of its own to carry part of its light: from τ/2, the
// 48-panel office had 4.6 own meshes over a point carrying 38% of its light
// (1.3 of them whole); from 0.8τ, 2.0 carrying 32%, and its error at 30 s
// fell from 2.15-2.20% to 1.85-1.93% (the 12-panel office's at 15 s from
// 1.90-1.96% to 1.81-1.89%; three runs each against the bench's
// references). It is evaluated at the nodes of a grid over
// the scene (32 cells along its longest side) and interpolated trilinearly,
// so it is exactly reproducible at any point, and a face is covered when
// any node of a cell its bounding box meets has w_l > 0: w_l is zero
// everywhere outside the faces of l's mesh.
//
// A gathered light (GatheredLights.h) is in neither: w_l = 0, no face of
// its own mesh, and the shared mesh leaves it out (its light comes through
// bounce 1's gather); it does not count in the totals shares are taken of.
#pragma once

#include "core/Scene.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace ml {

class LightCoverage {
public:
    // `share`: τ in (0, 1]; typical 0.05..0.2 (CacheSettings::lightShare: 0.1). 0 keeps every light's mesh over
    // the whole scene (w = 1 everywhere, no shared mesh).
    // `gathered`: per light, 1 for a gathered light (empty: none).
    LightCoverage(const Scene& scene, double share, const std::vector<char>& gatheredLights = {}, int resolution = 32);

    size_t lightCount() const { return lights_; }
    // Some light gives part of its light to the shared mesh somewhere.
    bool sharing() const { return sharing_; }
    double share() const { return share_; }
    // Light l reaches the scene through the gather: no mesh, not shared.
    bool gathered(size_t light) const { return light < gathered_.size() && gathered_[light]; }

    // w_l(x); 1 everywhere when not sharing.
    double weight(size_t light, const Vec3& x) const;
    // Every light with w_l(x) > 0, and its weight, in light order.
    void weights(const Vec3& x, std::vector<std::pair<uint32_t, double>>& out) const;
    // w_l > 0 somewhere in the box around `triangle`: l's mesh keeps the face.
    bool covers(size_t light, const Triangle3& triangle) const;
    // The fraction of the grid's cells where w_l > 0 (for the plan).
    double coveredFraction(size_t light) const;
    // "12 lights: own meshes over 18% of the scene on average (8..31%), the rest shared (τ = 5%)"
    std::string describe() const;

private:
    size_t node(int i, int j, int k) const { return (size_t(k) * size_t(dims_[1] + 1) + size_t(j)) * size_t(dims_[0] + 1) + size_t(i); }
    // The cell holding x (clamped to the grid) and x's position in it.
    void locate(const Vec3& x, int cell[3], double t[3]) const;

    size_t lights_ = 0;
    double share_ = 0;
    std::vector<char> gathered_;
    bool sharing_ = false;
    Vec3 origin_{0.0};
    double cellSize_ = 1;
    int dims_[3] = {1, 1, 1};  // cells per axis
    // Per node, the lights with w > 0: CSR (offsets_[node] .. offsets_[node + 1]).
    std::vector<uint32_t> offsets_;
    std::vector<uint32_t> nodeLights_;
    std::vector<float> nodeWeights_;
    // Per light, a bit per cell: some corner of the cell has w_l > 0.
    std::vector<std::vector<bool>> cellCovered_;
};

}  // namespace ml
