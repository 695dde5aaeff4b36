#include "Scene.h"

#include "DisjointSets.h"
#include "Error.h"

#include <map>

namespace ml {

namespace {

struct Vec3Less {
    bool operator()(const Vec3& a, const Vec3& b) const {
        if (a.x != b.x) return a.x < b.x;
        if (a.y != b.y) return a.y < b.y;
        return a.z < b.z;
    }
};

AreaLight makeLight(const Scene& scene, uint32_t meshIndex, uint32_t material,
                    const std::vector<uint32_t>& tris) {
    const Mesh& mesh = scene.meshes[meshIndex];
    AreaLight light;
    light.mesh = meshIndex;
    light.material = material;
    light.triangles = tris;
    light.radiance = scene.materials[material].ke;
    Vec3 weightedNormal(0.0), weightedCentroid(0.0);
    for (uint32_t t : tris) {
        const Triangle3 p = mesh.triangle(t);
        light.geometry.push_back(p);
        const Vec3 an = mesh.areaNormal(t);
        const double a = 0.5 * glm::length(an);
        light.area += a;
        weightedNormal += 0.5 * an;
        weightedCentroid += a * (p[0] + p[1] + p[2]) / 3.0;
        for (const Vec3& v : p) light.bounds.extend(v);
    }
    light.centroid = weightedCentroid / light.area;
    const double nlen = glm::length(weightedNormal);
    light.normal = nlen > 0 ? weightedNormal / nlen : Vec3(0.0);
    // Planar when every vertex lies within 1e-6 of the light's size from the
    // mean plane and every triangle faces the same way.
    const double tol = kLightPlanarTolerance * std::max(light.bounds.diagonal(), 1e-300);
    light.planar = nlen > 0;
    for (size_t k = 0; k < tris.size() && light.planar; ++k) {
        const Vec3 an = glm::normalize(mesh.areaNormal(tris[k]));
        if (glm::dot(an, light.normal) < 1.0 - 1e-9) light.planar = false;
        for (const Vec3& v : light.geometry[k])
            if (std::abs(glm::dot(v - light.centroid, light.normal)) > tol) light.planar = false;
    }
    return light;
}

}  // namespace

void Scene::finalize() {
    bounds = Bounds3{};
    for (const Mesh& m : meshes)
        for (const Vec3& p : m.positions) bounds.extend(p);

    lights.clear();
    for (uint32_t mi = 0; mi < meshes.size(); ++mi) {
        const Mesh& mesh = meshes[mi];
        // Emissive triangles sharing a vertex position, per material, form one light.
        DisjointSets sets(mesh.triangles.size());
        std::map<std::pair<uint32_t, Vec3>, uint32_t,
                 bool (*)(const std::pair<uint32_t, Vec3>&, const std::pair<uint32_t, Vec3>&)>
            firstAt([](const std::pair<uint32_t, Vec3>& a, const std::pair<uint32_t, Vec3>& b) {
                if (a.first != b.first) return a.first < b.first;
                return Vec3Less{}(a.second, b.second);
            });
        for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
            const uint32_t mat = mesh.materials[t];
            if (!materials[mat].emissive()) continue;
            for (const Vec3& p : mesh.triangle(t)) {
                auto [it, inserted] = firstAt.emplace(std::make_pair(mat, p), t);
                if (!inserted) sets.unite(t, it->second);
            }
        }
        std::map<uint32_t, std::vector<uint32_t>> groups;  // root -> triangles, in order
        for (uint32_t t = 0; t < mesh.triangles.size(); ++t)
            if (materials[mesh.materials[t]].emissive()) groups[sets.find(t)].push_back(t);
        std::map<uint32_t, int> perMaterial;
        for (auto& [root, tris] : groups) perMaterial[mesh.materials[tris.front()]]++;
        std::map<uint32_t, int> seen;
        for (auto& [root, tris] : groups) {
            const uint32_t mat = mesh.materials[tris.front()];
            AreaLight light = makeLight(*this, mi, mat, tris);
            light.name = materials[mat].name;
            if (perMaterial[mat] > 1) light.name += "#" + std::to_string(seen[mat]++);
            if (!(light.area > 0))
                throw InputError(SourceLocation{name, mesh.sourceLines.empty() ? 0 : mesh.sourceLines[tris.front()]},
                                 concat("light '", light.name, "' has zero area"));
            lights.push_back(std::move(light));
        }
    }
}

size_t Scene::triangleCount() const {
    size_t n = 0;
    for (const Mesh& m : meshes) n += m.triangles.size();
    return n;
}

Camera Scene::cameraOrDefault(double aspect) const {
    return camera ? *camera : Camera::framing(bounds, aspect);
}

bool Scene::hasGlossy() const {
    for (const Material& m : materials)
        if (m.glossy()) return true;
    return false;
}

}  // namespace ml
