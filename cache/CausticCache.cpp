#include "CausticCache.h"

#include "core/Error.h"
#include "core/raytrace/EmbreeScene.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace ml {

void CausticSettings::validate() const {
    if (!(edgeFraction > 1e-5 && edgeFraction <= 1))
        throw InputError(concat("caustic mesh edge fraction ", edgeFraction, " is not in (1e-5, 1]"));
    if (photonsPerRound < 1 || photonsPerRound > (size_t(1) << 26))
        throw InputError(concat("caustic photons per round ", photonsPerRound, " is not in 1..2^26"));
    if (!(radiusFraction > 1e-7 && radiusFraction <= 1))
        throw InputError(concat("caustic kernel radius fraction ", radiusFraction, " is not in (1e-7, 1]"));
    if (!(alpha > 0 && alpha < 1)) throw InputError(concat("caustic alpha ", alpha, " is not in (0, 1)"));
    if (!(tolerance > 0 && tolerance < 1))
        throw InputError(concat("caustic tolerance ", tolerance, " is not in (0, 1)"));
}

namespace detail {

// Points binned in a uniform grid of cells `size` wide, sorted by cell.
class PointGrid {
public:
    PointGrid(const std::vector<Vec3>& points, double size) : points_(points), size_(size) {
        keys_.reserve(points.size());
        for (uint32_t i = 0; i < points.size(); ++i) keys_.push_back({key(cell(points[i])), i});
        std::sort(keys_.begin(), keys_.end());
    }
    // Calls f(index) for every point within `radius` (≤ the cell size) of x,
    // in the order of the cells' keys, then of the points.
    template <class F>
    void near(const Vec3& x, double radius, F&& f) const {
        const glm::i64vec3 c = cell(x);
        const double r2 = radius * radius;
        // Each key once: cells that share a key share its list.
        std::array<uint64_t, 27> keys;
        size_t n = 0;
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) keys[n++] = key(c + glm::i64vec3(dx, dy, dz));
        std::sort(keys.begin(), keys.end());
        for (size_t i = 0; i < keys.size(); ++i) {
            if (i > 0 && keys[i] == keys[i - 1]) continue;
            auto it = std::lower_bound(keys_.begin(), keys_.end(), std::make_pair(keys[i], uint32_t(0)));
            for (; it != keys_.end() && it->first == keys[i]; ++it) {
                const Vec3 d = points_[it->second] - x;
                if (glm::dot(d, d) < r2) f(it->second);
            }
        }
    }

private:
    glm::i64vec3 cell(const Vec3& p) const { return glm::i64vec3(glm::floor(p / size_)); }
    static uint64_t key(const glm::i64vec3& c) {
        // Cells hashed to 64 bits; a collision makes a list longer (near()
        // visits each key once and tests every point's distance).
        return uint64_t(c.x) * 0x9e3779b97f4a7c15ull + uint64_t(c.y) * 0xc2b2ae3d27d4eb4full +
               uint64_t(c.z) * 0x165667b19e3779f9ull;
    }
    const std::vector<Vec3>& points_;
    double size_;
    std::vector<std::pair<uint64_t, uint32_t>> keys_;
};

}  // namespace detail

CausticCache::CausticCache(const Scene& scene, const CausticSettings& settings)
    : scene_(scene), settings_(settings) {
    settings_.validate();
    bool specular = false;
    for (const Material& m : scene.materials) specular |= m.specular();
    if (!specular || scene.lights.empty()) return;  // no BVH for scenes that cannot have caustics
    rays_ = std::make_unique<EmbreeScene>(scene);
    photons_ = std::make_unique<CausticPhotons>(scene, *rays_);
    if (!photons_->active()) return;
    // The mesh: the cache's base mesh at the caustic's edge length over the
    // objects photons can land on (not those wholly of mirror or glass,
    // often finely tessellated: bounce 1's gather looks this mesh up where
    // its rays end, and a sphere's thousand faces in a few lookup cells
    // doubled a gather's cost), sides as for direct light (a light shining
    // on a surface from behind can send photons there too).
    Scene receivers;
    receivers.name = scene.name;
    receivers.materials = scene.materials;
    receivers.lights = scene.lights;
    receivers.bounds = scene.bounds;
    for (const Mesh& m : scene.meshes)
        if (std::any_of(m.materials.begin(), m.materials.end(),
                        [&](uint32_t k) { return !scene.materials[k].specular(); }))
            receivers.meshes.push_back(m);
    CacheSettings c;
    c.maxEdgeFraction = settings_.edgeFraction;
    c.minEdgeFraction = settings_.edgeFraction;
    CacheLayout layout;
    layout.meshes = 1;
    layout.backFaces = CacheLayout::BackFaces::LitFromBehind;
    mesh_ = IrradianceCache(receivers, c, layout).copyMesh(0);
    mesh_.irradiance.clear();
    mesh_.samples.clear();
    mesh_.standardError.clear();
    firstRadius_ = settings_.radiusFraction * std::max(scene.bounds.diagonal(), 1e-30);
    vertices_ = std::make_unique<detail::PointGrid>(mesh_.positions, firstRadius_);
    radius2_.assign(mesh_.positions.size(), firstRadius_ * firstRadius_);
    count_.assign(mesh_.positions.size(), 0.0);
    flux_.assign(mesh_.positions.size(), Rgb(0.0));
}

CausticCache::~CausticCache() = default;

bool CausticCache::active() const { return photons_ && photons_->active(); }

std::string CausticCache::describe() const {
    if (!photons_) return scene_.lights.empty() ? "no lights" : "no specular materials";
    return photons_->describe();
}

size_t CausticCache::vertexCount() const { return mesh_.positions.size(); }

void CausticCache::round(uint32_t seed) {
    if (!active()) return;
    std::vector<CausticPhoton> landed;
    photons_->trace(emitted_, settings_.photonsPerRound, seed, landed);
    emitted_ += settings_.photonsPerRound;
    ++rounds_;
    // Each photon to the vertices whose kernel holds it (radii only shrink,
    // so the grid of the first radius finds them all), in photon order.
    std::vector<double> found(radius2_.size(), 0.0);
    std::vector<Rgb> power(radius2_.size(), Rgb(0.0));
    std::vector<uint32_t> touched;
    for (const CausticPhoton& p : landed)
        vertices_->near(p.position, firstRadius_, [&](uint32_t v) {
            const Vec3 d = p.position - mesh_.positions[v];
            if (glm::dot(d, d) >= radius2_[v]) return;
            if (glm::dot(p.normal, mesh_.normals[v]) < 0.7071) return;  // another side, or another surface at a crease
            if (found[v] == 0) touched.push_back(v);
            found[v] += 1;
            power[v] += p.power;
        });
    const double a = settings_.alpha;
    for (uint32_t v : touched) {
        const double shrink = (count_[v] + a * found[v]) / (count_[v] + found[v]);
        count_[v] += a * found[v];
        radius2_[v] *= shrink;
        flux_[v] = (flux_[v] + power[v]) * shrink;
    }
}

double CausticCache::estimatedError() const {
    if (!active()) return 0;
    if (rounds_ == 0) return 1;
    double noise = 0, level = 0;
    for (size_t v = 0; v < flux_.size(); ++v) {
        if (count_[v] <= 0) continue;
        const double e = luminance(flux_[v]) / radius2_[v];
        noise += e * e / count_[v];
        level += e * e;
    }
    return level > 0 ? std::sqrt(noise / level) : 0.0;
}

bool CausticCache::converged() const {
    return !active() || estimatedError() <= std::ldexp(settings_.tolerance, -level_);
}

bool CausticCache::tighten() {
    if (!active() || level_ >= IrradianceCache::kMaxRefinementLevel) return false;
    ++level_;
    return true;
}

IrradianceMeshCopy CausticCache::copyMesh() const {
    IrradianceMeshCopy m = mesh_;
    const size_t n = m.positions.size();
    m.irradiance.assign(n, Rgb(0.0));
    m.samples.assign(n, 0);
    m.standardError.assign(n, Rgb(0.0));
    if (emitted_ == 0) return m;
    for (size_t v = 0; v < n; ++v) {
        if (count_[v] <= 0) continue;
        m.irradiance[v] = flux_[v] / (kPi * radius2_[v] * double(emitted_));
        m.samples[v] = uint32_t(std::min(count_[v], 4e9));
        m.standardError[v] = m.irradiance[v] / std::sqrt(count_[v]);
    }
    // What the image's error estimate composites (ImageErrorEstimate.h):
    // each vertex's photon noise (its kernel's blur, shrinking as PPM goes
    // on, is not counted).
    m.predictedError = m.standardError;
    m.predictedNoise = m.standardError;
    return m;
}

}  // namespace ml
