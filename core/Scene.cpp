#include "Scene.h"

#include "CandelaTable.h"
#include "DisjointSets.h"
#include "Error.h"

#include <algorithm>
#include <cmath>
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

Light makeLight(const Scene& scene, uint32_t meshIndex, uint32_t material,
                    const std::vector<uint32_t>& tris) {
    const Mesh& mesh = scene.meshes[meshIndex];
    Light light;
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

// A two-sided panel (see Scene::finalize): when the triangles lie in one plane
// and face both ways, sets side[t] to 0 for those facing like the largest
// triangle, 1 for the others, and returns true; otherwise changes nothing.
bool splitBySide(const Mesh& mesh, const std::vector<uint32_t>& tris, std::vector<uint8_t>& side) {
    if (tris.size() < 2) return false;
    uint32_t largest = tris.front();
    double largestArea = 0;
    Bounds3 bounds;
    for (uint32_t t : tris) {
        const double a = glm::length(mesh.areaNormal(t));
        if (a > largestArea) largestArea = a, largest = t;
        for (const Vec3& v : mesh.triangle(t)) bounds.extend(v);
    }
    if (!(largestArea > 0)) return false;
    const Vec3 n = mesh.areaNormal(largest) / largestArea;
    const Vec3 origin = mesh.triangle(largest)[0];
    const double tol = kLightPlanarTolerance * std::max(bounds.diagonal(), 1e-300);
    std::vector<uint8_t> sides;
    sides.reserve(tris.size());
    for (uint32_t t : tris) {
        const Vec3 an = mesh.areaNormal(t);
        const double length = glm::length(an);
        if (!(length > 0)) return false;
        const Vec3 u = an / length;
        if (glm::length(u - n) <= kLightNormalTolerance) sides.push_back(0);
        else if (glm::length(u + n) <= kLightNormalTolerance) sides.push_back(1);
        else return false;
        for (const Vec3& v : mesh.triangle(t))
            if (std::abs(glm::dot(v - origin, n)) > tol) return false;
    }
    if (std::find(sides.begin(), sides.end(), 1) == sides.end()) return false;
    for (size_t k = 0; k < tris.size(); ++k) side[tris[k]] = sides[k];
    return true;
}

// The mesh's emissive triangles grouped by connection: those of one material
// and one side[t] sharing a vertex position, transitively. Keyed by a
// representative triangle; each group's triangles in increasing order.
std::map<uint32_t, std::vector<uint32_t>> connectedEmitters(const Scene& scene, const Mesh& mesh,
                                                            const std::vector<uint8_t>& side) {
    using Key = std::pair<uint64_t, Vec3>;  // (material, side), position
    DisjointSets sets(mesh.triangles.size());
    std::map<Key, uint32_t, bool (*)(const Key&, const Key&)> firstAt([](const Key& a, const Key& b) {
        if (a.first != b.first) return a.first < b.first;
        return Vec3Less{}(a.second, b.second);
    });
    for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
        const uint32_t mat = mesh.materials[t];
        if (!scene.materials[mat].emissive()) continue;
        for (const Vec3& p : mesh.triangle(t)) {
            auto [it, inserted] = firstAt.emplace(Key(2 * uint64_t(mat) + side[t], p), t);
            if (!inserted) sets.unite(t, it->second);
        }
    }
    std::map<uint32_t, std::vector<uint32_t>> groups;
    for (uint32_t t = 0; t < mesh.triangles.size(); ++t)
        if (scene.materials[mesh.materials[t]].emissive()) groups[sets.find(t)].push_back(t);
    return groups;
}

// Checks a punctual light and fills what it takes from the scene.
void finalizePunctual(const Scene& scene, Light& l) {
    PunctualEmission& e = l.emission;
    const SourceLocation at{scene.name, 0};
    if (!isFinite(e.position)) throwInputError(at, "light '", l.name, "': its position is not finite");
    const double axisLength = glm::length(e.axis);
    if (!isFinite(e.axis) || !(axisLength > 0)) throwInputError(at, "light '", l.name, "': its direction is zero or not finite");
    e.axis /= axisLength;
    // The reference half-plane (C0) made perpendicular to the axis; any
    // perpendicular when it was given along the axis or not at all.
    Vec3 r = e.reference - glm::dot(e.reference, e.axis) * e.axis;
    if (!isFinite(r) || glm::length(r) < 1e-9) {
        Vec3 b;
        orthonormalBasis(e.axis, r, b);
    }
    e.reference = glm::normalize(r);
    for (double c : {e.intensity.r, e.intensity.g, e.intensity.b})
        if (!std::isfinite(c) || c < 0) throwInputError(at, "light '", l.name, "': intensity ", c, " is not a finite non-negative number");
    if (e.profile.shape == IntensityProfile::Shape::Table) {
        if (!e.profile.table) throwInputError(at, "light '", l.name, "': a table profile without a table");
        e.profile.tablePeak = e.profile.table->maxIntensity();
    }
    if (e.profile.shape == IntensityProfile::Shape::Spot &&
        !(e.profile.cosOuter < e.profile.cosInner && e.profile.cosOuter >= -1 && e.profile.cosInner <= 1))
        throwInputError(at, "light '", l.name, "': spot cones are not 0 <= inner < outer <= 180 degrees");
    if (!(scene.metresPerUnit > 0) || !std::isfinite(scene.metresPerUnit))
        throwInputError(at, "metres per scene unit ", scene.metresPerUnit, " is not a positive number");
    const double diagonal = scene.bounds.empty() ? 1.0 : scene.bounds.diagonal();
    e.metresPerUnit = scene.metresPerUnit;
    e.minDistance = kPunctualMinDistance * diagonal;
    e.sceneRadius = 0.5 * diagonal;
    l.area = 0;
    l.planar = false;
    l.normal = e.axis;
    l.bounds = Bounds3{};
    if (l.kind == LightKind::Point) {
        l.centroid = e.position;
        l.bounds.extend(e.position);
    } else {
        l.centroid = scene.bounds.empty() ? Vec3(0.0) : scene.bounds.center();
    }
}

}  // namespace

void Scene::finalize() {
    bounds = Bounds3{};
    for (const Mesh& m : meshes) {
        for (const Vec3& p : m.positions) bounds.extend(p);
        ML_ASSERT(m.texcoords.empty() || m.texcoords.size() == m.positions.size(), "mesh '", m.name, "' has ",
                  m.texcoords.size(), " texcoords for ", m.positions.size(), " vertices");
        ML_ASSERT(m.albedo.empty() || m.albedo.size() == m.triangles.size(), "mesh '", m.name, "' has ",
                  m.albedo.size(), " albedos for ", m.triangles.size(), " triangles");
    }

    std::vector<Light> punctual;
    for (Light& l : lights)
        if (l.punctual()) punctual.push_back(std::move(l));
    lights.clear();
    // An area light is named after its material, with "#k" where the scene
    // (not only its mesh) has several lights of that material, so that each
    // light's name, a column of `probe`'s CSV and a name in view scripts, is
    // its own.
    std::vector<uint32_t> lightMaterial;
    std::vector<int> lightLine;
    for (uint32_t mi = 0; mi < meshes.size(); ++mi) {
        const Mesh& mesh = meshes[mi];
        // Grouped by connection; grouped again where a two-sided panel splits.
        // The second grouping repeats the first's unions for the sets that do
        // not split, so their representatives (and light names) stay.
        std::vector<uint8_t> side(mesh.triangles.size(), 0);
        std::map<uint32_t, std::vector<uint32_t>> groups = connectedEmitters(*this, mesh, side);
        bool split = false;
        for (const auto& [root, tris] : groups) split |= splitBySide(mesh, tris, side);
        if (split) groups = connectedEmitters(*this, mesh, side);
        for (auto& [root, tris] : groups) {
            const uint32_t mat = mesh.materials[tris.front()];
            lights.push_back(makeLight(*this, mi, mat, tris));
            lightMaterial.push_back(mat);
            lightLine.push_back(mesh.sourceLines.empty() ? 0 : mesh.sourceLines[tris.front()]);
        }
    }
    std::map<uint32_t, int> perMaterial, seen;
    for (uint32_t mat : lightMaterial) perMaterial[mat]++;
    for (size_t i = 0; i < lights.size(); ++i) {
        Light& light = lights[i];
        const uint32_t mat = lightMaterial[i];
        light.name = materials[mat].name;
        if (perMaterial[mat] > 1) light.name += "#" + std::to_string(seen[mat]++);
        if (!(light.area > 0))
            throw InputError(SourceLocation{name, lightLine[i]}, concat("light '", light.name, "' has zero area"));
    }
    for (Light& l : punctual) {
        finalizePunctual(*this, l);
        // A punctual light named as an area light (or as another punctual
        // one) takes the first free "#k" after its name.
        const auto taken = [&](const std::string& n) {
            return std::any_of(lights.begin(), lights.end(), [&](const Light& o) { return o.name == n; });
        };
        if (taken(l.name)) {
            int k = 1;
            while (taken(l.name + "#" + std::to_string(k))) ++k;
            l.name += "#" + std::to_string(k);
        }
        lights.push_back(std::move(l));
    }
}

std::string lightGroupOf(const std::string& name) {
    size_t end = name.size();
    while (end > 0 && name[end - 1] >= '0' && name[end - 1] <= '9') --end;
    if (end == name.size() || end < 2) return name;  // no suffix, or nothing before it
    const char sep = name[end - 1];
    if (sep == '.' || sep == '_' || sep == ' ' || sep == '#' || sep == '-') return name.substr(0, end - 1);
    return name;
}

size_t Scene::triangleCount() const {
    size_t n = 0;
    for (const Mesh& m : meshes) n += m.triangles.size();
    return n;
}

double Scene::meanFreePath() const {
    double area = 0;
    for (const Mesh& m : meshes)
        for (size_t t = 0; t < m.triangles.size(); ++t) area += m.area(t);
    const Vec3 e = bounds.extent();
    const double volume = e.x * e.y * e.z;
    return area > 0 && volume > 0 ? 4 * volume / area : 0.0;
}

Camera Scene::cameraOrDefault(double aspect) const {
    return camera ? *camera : Camera::framing(bounds, aspect);
}

bool Scene::hasGlossy() const {
    for (const Material& m : materials)
        if (m.glossy()) return true;
    return false;
}

bool Scene::hasTextures() const {
    for (const Mesh& m : meshes)
        if (!m.texcoords.empty())
            for (uint32_t mat : m.materials)
                if (materials[mat].kdMap || materials[mat].keMap || materials[mat].alphaMap) return true;
    return false;
}

}  // namespace ml
