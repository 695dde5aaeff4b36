// The scene's surfaces that a cache vertex on an object's border can lie in,
// edge-on: the ceiling's plane holds the top edge of a wall under it, the
// wall's plane the edge of a floor against it.
//
// The samplers look from such a point along that surface's plane, and see it
// as a line: a light above the ceiling lit the walls' top edges (the Cornell
// box of ../shared/scenes with its light raised 0.38 above the ceiling: up
// to 0.041 on the edges where the path tracer gives 0), and a floor against
// a glowing wall counted none of the wall's light. So IrradianceCache
// samples such a vertex a thousandth of its shortest edge inside its own
// faces (detail::samplePoint): the limit from inside the object, which is
// what the mesh interpolates there. Only where those faces are flat: at a
// fold (pages bound at a spine, fins on a hinge) a point moved beside the
// vertex leaves every face, and the vertex is the one point they share.
// Every other vertex is sampled where it is, so that the cache holds the
// light at its vertices exactly.
#pragma once

#include "core/BoundsGrid.h"
#include "core/Scene.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace ml {

class EdgeOnSurfaces {
public:
    EdgeOnSurfaces() = default;
    // Every triangle of the scene's meshes with an area.
    explicit EdgeOnSurfaces(const Scene& scene);

    // Whether x lies on a triangle of the scene (within kPlaneTolerance of
    // the scene's diagonal from its plane, and inside its edges) that meets
    // a surface with unit normal `normal` at an angle: not parallel to it
    // (its own faces, and what lies flat against them, are not counted).
    bool through(const Vec3& x, const Vec3& normal) const;

    // Loaded and transformed scenes put a wall's top within rounding of
    // the ceiling's plane, not on it.
    static constexpr double kPlaneTolerance = 1e-6;

    // The index of a scene, shared by every cache of it that is alive: the
    // direct meshes' and each bounce's IrradianceCache ask for the same
    // scene, and one index of a million-triangle scene holds about 130 MB.
    // `fingerprint` names the scene (detail::sceneFingerprint: its
    // geometry and materials); a scene of another fingerprint gets its own.
    static std::shared_ptr<const EdgeOnSurfaces> forScene(const Scene& scene, uint64_t fingerprint);

private:
    struct Face {
        Vec3 p0, e1, e2, n;  // a corner, the edges from it, the unit normal
        double g11, g12, g22, det;  // the edges' Gram matrix and its determinant
    };
    std::vector<Face> faces_;
    BoundsGrid grid_;
    double eps_ = 0;
};

}  // namespace ml
