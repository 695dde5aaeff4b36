#include "EdgeOnSurfaces.h"

#include <cmath>
#include <map>
#include <mutex>

namespace ml {

EdgeOnSurfaces::EdgeOnSurfaces(const Scene& scene) : eps_(kPlaneTolerance * scene.bounds.diagonal()) {
    std::vector<Bounds3> boxes;
    for (const Mesh& m : scene.meshes)
        for (size_t t = 0; t < m.triangles.size(); ++t) {
            const Triangle3 p = m.triangle(t);
            const Vec3 n = m.areaNormal(t);
            const double len = glm::length(n);
            if (!(len > 0) || !isFinite(n)) continue;
            Face f;
            f.p0 = p[0], f.e1 = p[1] - p[0], f.e2 = p[2] - p[0], f.n = n / len;
            f.g11 = glm::dot(f.e1, f.e1), f.g12 = glm::dot(f.e1, f.e2), f.g22 = glm::dot(f.e2, f.e2);
            f.det = f.g11 * f.g22 - f.g12 * f.g12;
            if (!(f.det > 0)) continue;
            faces_.push_back(f);
            Bounds3 b;
            for (const Vec3& q : p) b.extend(q);
            b.lo -= Vec3(eps_), b.hi += Vec3(eps_);
            boxes.push_back(b);
        }
    Bounds3 domain = scene.bounds;
    if (domain.empty()) for (const Bounds3& b : boxes) domain.extend(b);
    grid_ = BoundsGrid(domain, boxes);
}

bool EdgeOnSurfaces::through(const Vec3& x, const Vec3& normal) const {
    return grid_.anyAt(x, [&](uint32_t i) {
        const Face& f = faces_[i];
        if (std::abs(glm::dot(normal, f.n)) > 0.999) return false;  // parallel: its own surface, or flat on it
        const Vec3 d = x - f.p0;
        if (std::abs(glm::dot(d, f.n)) > eps_) return false;
        // Barycentric coordinates of x's projection, allowed eps_ outside
        // the edges (a wall's corner on the ceiling's border).
        const double d1 = glm::dot(d, f.e1), d2 = glm::dot(d, f.e2);
        const double b1 = (f.g22 * d1 - f.g12 * d2) / f.det, b2 = (f.g11 * d2 - f.g12 * d1) / f.det;
        const double slack1 = eps_ / std::sqrt(f.g11), slack2 = eps_ / std::sqrt(f.g22);
        return b1 >= -slack1 && b2 >= -slack2 && b1 + b2 <= 1 + slack1 + slack2;
    });
}

std::shared_ptr<const EdgeOnSurfaces> EdgeOnSurfaces::forScene(const Scene& scene, uint64_t fingerprint) {
    static std::mutex mutex;
    static std::map<uint64_t, std::weak_ptr<const EdgeOnSurfaces>> alive;
    std::lock_guard<std::mutex> lock(mutex);
    for (auto i = alive.begin(); i != alive.end();) i = i->second.expired() ? alive.erase(i) : std::next(i);
    std::weak_ptr<const EdgeOnSurfaces>& slot = alive[fingerprint];
    if (std::shared_ptr<const EdgeOnSurfaces> kept = slot.lock()) return kept;
    auto made = std::make_shared<const EdgeOnSurfaces>(scene);
    slot = made;
    return made;
}

}  // namespace ml
