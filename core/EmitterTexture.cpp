#include "EmitterTexture.h"

#include <algorithm>
#include <limits>

namespace ml {

EmitterTexture::EmitterTexture(const Scene& scene, const Light& light) {
    if (light.punctual() || light.material >= scene.materials.size() || light.mesh >= scene.meshes.size()) return;
    const Material& m = scene.materials[light.material];
    const Mesh& mesh = scene.meshes[light.mesh];
    if (!m.keMap || mesh.texcoords.empty()) return;
    map_ = &m.keMap;
    for (int c = 0; c < 3; ++c) inverseMean[c] = m.ke[c] > 0 ? 1.0 / m.ke[c] : 0.0;
    faces_.reserve(light.geometry.size());
    for (size_t k = 0; k < light.geometry.size(); ++k) {
        const Triangle3& p = light.geometry[k];
        const glm::uvec3 v = mesh.triangles[light.triangles[k]];
        faces_.push_back({p[0], p[1] - p[0], p[2] - p[0], mesh.texcoords[v.x], mesh.texcoords[v.y],
                          mesh.texcoords[v.z]});
    }
}

std::vector<EmitterTexture> EmitterTexture::forLights(const Scene& scene) {
    std::vector<EmitterTexture> out;
    out.reserve(scene.lights.size());
    for (const Light& l : scene.lights) out.emplace_back(scene, l);
    return out;
}

Rgb EmitterTexture::weight(size_t t, double b1, double b2) const {
    if (!map_) return Rgb(1.0);
    const Face& f = faces_[t];
    const Vec2 uv = f.uv0 + b1 * (f.uv1 - f.uv0) + b2 * (f.uv2 - f.uv0);
    return map_->value(uv) * inverseMean;
}

Rgb EmitterTexture::weightAlong(const Vec3& eye, const Vec3& dir) const {
    if (!map_) return Rgb(1.0);
    // Möller–Trumbore in double, emitting faces only: the ray meets their
    // CCW side, dir · (e1 × e2) < 0, i.e. det = e1 · (dir × e2) > 0. The nearest face the ray meets inside
    // wins; failing any, the one whose smallest barycentric is largest.
    size_t best = faces_.size();
    double bestS = std::numeric_limits<double>::infinity(), bestInside = -std::numeric_limits<double>::infinity();
    double b1Best = 0, b2Best = 0;
    for (size_t k = 0; k < faces_.size(); ++k) {
        const Face& f = faces_[k];
        const Vec3 q = glm::cross(dir, f.e2);
        const double det = glm::dot(f.e1, q);
        if (!(det > 0)) continue;  // parallel, or its back faces the eye
        const Vec3 o = eye - f.p0;
        const double b1 = glm::dot(o, q) / det;
        const Vec3 r = glm::cross(o, f.e1);
        const double b2 = glm::dot(dir, r) / det;
        const double s = glm::dot(f.e2, r) / det;
        if (!(s > 0)) continue;
        const double inside = std::min({b1, b2, 1.0 - b1 - b2});
        const bool hit = inside >= 0;
        const bool bestHit = bestInside >= 0;
        if ((hit && (!bestHit || s < bestS)) || (!hit && !bestHit && inside > bestInside)) {
            best = k;
            bestS = s;
            bestInside = inside;
            b1Best = b1;
            b2Best = b2;
        }
    }
    if (best == faces_.size()) return Rgb(1.0);  // no emitting face ahead: the mean
    if (bestInside < 0) {                         // onto the face: barycentrics clamped and renormalised
        double b0 = std::max(0.0, 1.0 - b1Best - b2Best);
        b1Best = std::max(0.0, b1Best);
        b2Best = std::max(0.0, b2Best);
        const double sum = b0 + b1Best + b2Best;
        b1Best /= sum;
        b2Best /= sum;
    }
    return weight(best, b1Best, b2Best);
}

}  // namespace ml
