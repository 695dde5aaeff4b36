#include "SpecularChain.h"

namespace ml {

bool scatterSpecular(const SmoothSpecular& layer, const Vec3& travel, const Vec3& geometric, const Vec3& shading,
                     double u, SpecularScatter& out) {
    // The side the ray arrives on: the front (outside) when it travels
    // against the geometric normal.
    const bool entering = glm::dot(geometric, travel) < 0;
    const Vec3 ng = entering ? geometric : -geometric;
    Vec3 ns = glm::dot(shading, ng) < 0 ? -shading : shading;
    const Vec3 wo = -travel;
    if (!(glm::dot(wo, ns) > 0)) ns = ng;  // the shading normal turns its back on the ray
    const SpecularResponse r = specularResponse(layer, glm::dot(wo, ns), entering);
    const double lr = luminance(r.reflected), lt = luminance(r.transmitted);
    if (!(lr + lt > 0)) return false;
    const double pr = lr / (lr + lt);
    if (u < pr) {
        out.direction = glm::normalize(reflectDirection(wo, ns));
        out.weight = r.reflected / pr;
        out.transmitted = false;
        return glm::dot(out.direction, ng) > 0;
    }
    Vec3 wt;
    if (!refractDirection(wo, ns, entering ? layer.ior : 1.0 / layer.ior, wt)) return false;
    out.direction = glm::normalize(wt);
    out.weight = r.transmitted / (1.0 - pr);
    out.transmitted = true;
    return glm::dot(out.direction, ng) < 0;
}

int followSpecularChain(const EmbreeScene& rays, const std::vector<char>& closedMeshes, const Vec3& origin,
                        const Vec3& direction, const SpecularChainSettings& settings,
                        const std::function<double()>& random, const std::function<void(const ChainVertex&)>& visit) {
    const Scene& scene = rays.scene();
    Vec3 o = origin, w = direction;
    ChainVertex v;
    for (;;) {
        if (!rays.intersect(o, w, 0.0, kInf, v.hit)) return v.layers;
        v.surface = rays.surface(v.hit);
        const Material& m = scene.materials[v.surface.material];
        v.side = v.surface.geometricNormal;
        const bool back = glm::dot(v.side, w) > 0;
        if (back) v.side = -v.side;
        v.specular = m.specular();
        if (!v.specular) {
            if (!(back && v.hit.mesh < closedMeshes.size() && closedMeshes[v.hit.mesh])) visit(v);
            return v.layers;
        }
        visit(v);  // the diffuse Kd under the layer
        if (v.layers >= settings.maxDepth) return v.layers;
        SpecularScatter s;
        if (!scatterSpecular(m.smooth, w, v.surface.geometricNormal, v.surface.shadingNormal, random(), s))
            return v.layers;
        v.weight *= s.weight;
        if (!(luminance(v.weight) > 0)) return v.layers;
        ++v.layers;
        o = rays.spawnPoint(v.surface.position, v.surface.geometricNormal, s.direction);
        w = s.direction;
    }
}

}  // namespace ml
