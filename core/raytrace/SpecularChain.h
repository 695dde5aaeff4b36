// Rays through mirrors and glass: one interface's choice between reflection
// and refraction, and a ray followed through a chain of them to the diffuse
// surface where it ends. Shared by the photons that carry caustics
// (cache/CausticPhotons) and the indirect ray gather (RayGather), so that
// what is emitted through glass and what is gathered through it agree.
//
// Normals. A smooth layer reflects and refracts about the surface's shading
// normal (Mesh::normals, interpolated), turned to the side the ray arrives
// on: a tessellated sphere then focuses light like the sphere it stands for
// rather than like its facets. A direction that the shading normal sends to
// the wrong side of the geometric surface (a grazing ray near a silhouette)
// is dropped: it carries no light rather than light leaking through.
#pragma once

#include "EmbreeScene.h"
#include "core/SmoothSpecular.h"

#include <functional>
#include <vector>

namespace ml {

// What a ray does at a smooth layer.
struct SpecularScatter {
    Vec3 direction{0.0};  // unit, the new direction of travel
    Rgb weight{0.0};      // the layer's response over the probability of the branch taken
    bool transmitted = false;
};

// At a hit of `layer` by a ray travelling along unit `travel`, with the hit's
// geometric normal `geometric` and shading normal `shading` (any side),
// takes the reflected branch with probability u < P_r = lum(R)/(lum(R)+lum(T))
// and the transmitted one otherwise (R and T from specularResponse), with
// weight R/P_r or T/(1 − P_r): an unbiased choice of one branch, whose weight
// never exceeds 1/(lum R + lum T) × the response. False when the layer
// sends nothing on (R = T = 0) or the branch points to the wrong side of the
// geometric surface.
bool scatterSpecular(const SmoothSpecular& layer, const Vec3& travel, const Vec3& geometric, const Vec3& shading,
                     double u, SpecularScatter& out);

// Where a followed ray is read: a diffuse surface (the chain's end) or a
// specular one, whose diffuse Kd under the layer is read too.
struct ChainVertex {
    RayHit hit;
    SurfacePoint surface;
    Vec3 side{0.0};       // unit geometric normal on the side the ray arrives from
    Rgb weight{1.0};      // product of the layers' weights before this surface
    int layers = 0;       // smooth layers crossed before this surface
    bool specular = false;
};

struct SpecularChainSettings {
    // Smooth layers followed at most (a ray through a glass sphere meets
    // two; a light between two mirrors, many); typical 8.
    int maxDepth = 8;
};

// Follows origin + t·direction (unit): calls `visit` at every surface it hits,
// specular ones included, until it reaches a diffuse surface (visited last)
// or leaves the scene, or the layers' weight falls to zero, or maxDepth
// layers have been crossed. The inside of a closed diffuse object
// (closedMeshes[mesh] != 0, seen from behind) ends it unvisited: it is
// black. `random` draws the uniform numbers of each interface's branch.
// Returns the number of layers crossed.
int followSpecularChain(const EmbreeScene& rays, const std::vector<char>& closedMeshes, const Vec3& origin,
                        const Vec3& direction, const SpecularChainSettings& settings,
                        const std::function<double()>& random, const std::function<void(const ChainVertex&)>& visit);

}  // namespace ml
