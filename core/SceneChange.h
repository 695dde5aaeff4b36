// A light or an object that moves (issue 17), as data: what the viewer's
// script and panel ask for, what the cache is told (cache/CacheInvalidation.h)
// and what `bench dynamic` replays.
//
// Applying a change gives the changed scene, finalized again (lights
// derived anew from the moved emitting faces). A light is named by its
// index in Scene::lights, an object by its Scene::meshes name; an unknown
// one is an InputError naming it (and `where`, the script line that asked).
#pragma once

#include "Error.h"
#include "Scene.h"

#include <string>

namespace ml {

struct SceneChange {
    enum class Kind {
        MoveLight,     // light `light` to `point` (a punctual light's position; an area light's centroid)
        AimLight,      // light `light` towards `point` (a punctual light's axis; an area light's mean normal)
        MoveObject,    // mesh `object` by `offset`, scene units
        RotateObject,  // mesh `object` by `degrees` about `axis` through its bounds' centre (right-handed)
    };
    Kind kind = Kind::MoveLight;
    size_t light = 0;
    std::string object;
    Vec3 point{0.0};
    Vec3 offset{0.0};
    Vec3 axis{0.0, 1.0, 0.0};
    double degrees = 0;
    SourceLocation where;  // the script line that asked (empty: none)

    static SceneChange moveLight(size_t light, const Vec3& to);
    static SceneChange aimLight(size_t light, const Vec3& at);
    static SceneChange moveObject(const std::string& name, const Vec3& by);
    static SceneChange rotateObject(const std::string& name, const Vec3& axis, double degrees);

    bool movesLight() const { return kind == Kind::MoveLight || kind == Kind::AimLight; }
    // "light 0 move to (1, 2, 3)"
    std::string describe() const;
};

// What a change did to the geometry, for the cache (CacheInvalidation.h).
struct AppliedChange {
    Scene scene;            // the changed scene, finalized
    // The mesh whose vertices moved (an object, or the mesh holding an area
    // light's faces); -1 for a punctual light, which moves no geometry.
    long mesh = -1;
    // Where that mesh's moved triangles were and are: the moved vertices'
    // bounds before and after (empty for a punctual light).
    Bounds3 before, after;
    // The rigid motion of the moved vertices: p' = rotation (p − pivot) + pivot + translation.
    Mat3 rotation{1.0};
    Vec3 pivot{0.0};
    Vec3 translation{0.0};
    // Triangles of `mesh` that moved (all of an object's; a light's own faces).
    std::vector<uint32_t> triangles;
    // The lights whose emission moved (a moved object's emitting faces too).
    std::vector<size_t> lights;
    // The moved faces shared vertices with faces of their mesh that stay
    // (an emitting panel cut into a ceiling): they were given vertices of
    // their own, which a cache made for the scene before cannot follow.
    bool detached = false;

    Vec3 transform(const Vec3& p) const { return rotation * (p - pivot) + pivot + translation; }
};

// The scene after `change`. Throws InputError for an unknown light or
// object, a non-finite target, a zero rotation axis, aiming a light at its
// own position, or aiming a directional light's nonexistent position.
AppliedChange applySceneChange(const Scene& scene, const SceneChange& change);

}  // namespace ml
