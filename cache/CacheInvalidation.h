// What a moved light or object (core/SceneChange.h) invalidates in the
// cache, and the cache made to follow it (issue 17, "moving things").
//
// The cache keeps every sample that is still valid and forgets the rest;
// forgotten vertices are unsampled again, so refinement takes them before
// any other work (IrradianceCache::refine samples unsampled vertices
// first), and copies fill them from their sampled neighbours meanwhile.
//  - A moved light: its own direct mesh is laid again on the base mesh,
//    unsampled (its refinement followed shadows that have moved: sampling
//    it again costs more than a fresh base, measured by bench dynamic);
//    with lights sharing, the shared mesh is forgotten where that light has
//    weight in it (LightCoverage weight < 1). Coverage itself is kept: its
//    weights split each light between its own mesh and the shared one, and
//    any split adds up to the light, so the sum stays exact (only less
//    economical until the cache is made again).
//  - A moved object: in every light's mesh, the vertices whose view of that
//    light the object may have blocked or may now block: those for which
//    the object's old or new bounding box meets the convex hull of the
//    vertex and the light's bounds (hullMeets: exact for a point and a box,
//    so the test is conservative only by the object's box). The object's
//    own cache faces move with it (every direct mesh) and are forgotten.
//    A mesh where any vertex was forgotten is then laid again on the base,
//    keeping the samples of the base vertices that still have them
//    (IrradianceCache::rebuildKeepingBase): its refinement was densest
//    where the shadows were, and sampling those vertices again (most need
//    the rasteriser) took far longer than refining anew (bench dynamic).
//  - Indirect light: every bounce is stale; the bounces are made again from
//    base meshes and gathered bounce after bounce, the old indirect meshes
//    shown meanwhile (IndirectSolver::sceneChanged).
//  - Meshes nothing was forgotten in keep their refinement and samples.
#pragma once

#include "IndirectSolver.h"
#include "IrradianceCache.h"
#include "LightCoverage.h"
#include "core/SceneChange.h"

namespace ml {

// What invalidateCache did: vertices forgotten and kept, over every mesh.
struct InvalidationReport {
    size_t lightVertices = 0;     // direct vertices dropped or forgotten because their light moved
    size_t shadowVertices = 0;    // direct vertices forgotten because the object may change what they see
    size_t movedVertices = 0;     // direct vertices on the moved faces, moved with them
    size_t keptVertices = 0;      // direct vertices that keep their samples
    size_t indirectVertices = 0;  // indirect vertices dropped (every bounce's, made again)
    // The moved lights' share of the scene's light (luminance of
    // Light::power; 0 when only objects moved).
    double movedLightShare = 0;
    // The old indirect light is shown until every bounce is gathered again
    // (IndirectSolver::sceneChanged's keepOld): only emitters moved (a
    // punctual light, an area light's own faces), holding at most
    // kKeepOldLightShare of the light.
    bool oldIndirectKept = false;
    std::string describe() const;
};

// A change that moves only emitters (lights, not an object around them)
// holding at most this share of the scene's light keeps the old indirect light in the image until
// every bounce is gathered again, instead of a real-time estimate or
// bounces partly gathered. The old light is off by about the share moved,
// where it moved: measured by bench dynamic on the office, one panel of 12
// moved 0.6 m, the image with the old bounces 2.9% from the converged one,
// with vpl's estimate 27-30% (the methods from direct light there: volume
// 9%, lpv 13%, vpl 26%; on the Cornell box, whose one light moved, 1.7-5.6%),
// and with the cache's own bounce 1, shown from a sixteenth gathered, 12.8%. Taken at an
// eighth, so that the old light's error (about 4% at this share, by that
// measure) stays within the methods' on the Cornell box, where they do best.
// An object's move keeps the stand-in: its old light lies on the old
// geometry.
constexpr double kKeepOldLightShare = 1.0 / 8;

// Where light `l` of `scene` can be seen from: its bounds (a point light's
// position); for a directional light, a point two scene diagonals away
// against its direction, from `x`.
Bounds3 lightVolume(const Scene& scene, size_t l, const Vec3& x);

// The convex hull of `x` and box `light` meets box `box` (exact: the hull
// is the union of `light` shrunk towards x by every factor t in [0, 1], and
// the boxes meeting `box` form one interval of t).
bool hullMeets(const Vec3& x, const Bounds3& light, const Bounds3& box);

// Makes `direct` and `indirect` (null: none) follow `change`, applied to
// `before`, whose result change.scene the caller's scene already holds.
// `coverage`: where lights keep meshes of their own (null: no sharing).
// Throws InputError when the moved faces are part of a cache object that
// does not move whole (faces sharing vertices with faces that stay), which
// the cache cannot follow without being made again.
InvalidationReport invalidateCache(IrradianceCache& direct, IndirectSolver* indirect, const LightCoverage* coverage,
                                   const Scene& before, const AppliedChange& change);

}  // namespace ml
