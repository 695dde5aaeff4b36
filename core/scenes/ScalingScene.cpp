#include "ScalingScene.h"

#include "core/Error.h"
#include "core/Random.h"
#include "core/scenes/CornellBox.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace ml {

namespace {

// One level of midpoint subdivision of a mesh's non-emissive triangles.
Mesh splitInFour(const Mesh& in, const std::vector<Material>& materials) {
    Mesh out;
    out.name = in.name;
    out.positions = in.positions;
    out.normals = in.normals;
    out.triangles.reserve(in.triangles.size() * 4);
    out.materials.reserve(in.triangles.size() * 4);
    out.sourceLines.reserve(in.triangles.size() * 4);
    // Edge (lower index, higher index) -> its midpoint, made once for both sides.
    std::unordered_map<uint64_t, uint32_t> midpoints;
    midpoints.reserve(in.triangles.size() * 2);
    auto midpoint = [&](uint32_t a, uint32_t b) {
        const uint64_t key = (uint64_t(std::min(a, b)) << 32) | std::max(a, b);
        auto [it, inserted] = midpoints.emplace(key, uint32_t(out.positions.size()));
        if (inserted) {
            ML_ASSERT(out.positions.size() < UINT32_MAX, "mesh '", in.name, "' outgrows 32-bit indices");
            out.positions.push_back(0.5 * (in.positions[a] + in.positions[b]));
            const Vec3 n = in.normals[a] + in.normals[b];
            out.normals.push_back(glm::length(n) > 0 ? glm::normalize(n) : in.normals[a]);
        }
        return it->second;
    };
    for (size_t t = 0; t < in.triangles.size(); ++t) {
        const glm::uvec3 v = in.triangles[t];
        const uint32_t material = in.materials[t];
        const int line = in.sourceLines.empty() ? 0 : in.sourceLines[t];
        auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
            out.triangles.push_back({a, b, c});
            out.materials.push_back(material);
            out.sourceLines.push_back(line);
        };
        if (materials[material].emissive()) {
            add(v.x, v.y, v.z);
            continue;
        }
        const uint32_t ab = midpoint(v.x, v.y), bc = midpoint(v.y, v.z), ca = midpoint(v.z, v.x);
        // Same winding as the parent, so every child faces the same way.
        add(v.x, ab, ca);
        add(ab, v.y, bc);
        add(ca, bc, v.z);
        add(ab, bc, ca);
    }
    return out;
}

// Uniform in [0, 1) from a 32-bit hash: the same on every platform, unlike
// the standard library's distributions.
double unitFrom(uint32_t h) { return (double(h) + 0.5) * (1.0 / 4294967296.0); }

}  // namespace

Scene subdivideScene(const Scene& base, int levels) {
    if (levels < 0 || levels > 12)
        throw InputError(concat("subdivided scene: levels must be in 0..12, got ", levels));
    Scene scene;
    scene.name = levels ? concat(base.name, "-x4^", levels) : base.name;
    scene.materials = base.materials;
    scene.camera = base.camera;
    scene.warnings = base.warnings;
    scene.meshes = base.meshes;
    for (Mesh& mesh : scene.meshes)
        for (int k = 0; k < levels; ++k) mesh = splitInFour(mesh, scene.materials);
    scene.finalize();
    return scene;
}

Scene makeCornellLightGrid(int lights) {
    if (lights < 1 || lights > 1024)
        throw InputError(concat("Cornell light grid: the number of lights must be in 1..1024, got ", lights));
    const Scene cornell = makeCornellBox();
    Scene scene;
    scene.name = concat("cornell-", lights, "-lights");
    scene.materials = cornell.materials;
    scene.camera = cornell.camera;
    const Mesh* original = nullptr;
    for (const Mesh& m : cornell.meshes) {
        if (m.name == "light") original = &m;
        else scene.meshes.push_back(m);
    }
    ML_ASSERT(original && cornell.lights.size() == 1, "the Cornell box should have one light mesh");
    const Light& light0 = cornell.lights.front();

    constexpr double kSide = 40.0;      // mm, each light
    constexpr double kRegion = 400.0;   // mm, the square the grid covers
    constexpr double kCeilingY = 548.8, kLightY = 548.3;  // as makeCornellBox: 0.5 mm below the ceiling
    const Vec3 centre(278.0, kLightY, 279.6);
    const int cols = int(std::ceil(std::sqrt(double(lights))));
    const int rows = (lights + cols - 1) / cols;
    const double cellX = kRegion / cols, cellZ = kRegion / rows;
    static_assert(kLightY < kCeilingY);

    Material& material = scene.materials[light0.material];
    material.ke = light0.radiance * (light0.area / (double(lights) * kSide * kSide));

    Mesh mesh;
    mesh.name = "light";
    for (int i = 0; i < lights; ++i) {
        const int r = i / cols, c = i % cols;
        const Vec3 mid = centre + Vec3(-0.5 * kRegion + (c + 0.5) * cellX, 0.0, -0.5 * kRegion + (r + 0.5) * cellZ);
        const uint32_t b = uint32_t(mesh.positions.size());
        const double h = 0.5 * kSide;
        // Counter-clockwise seen from below: the lights face −y, into the box.
        for (const Vec3& corner : {Vec3(-h, 0, -h), Vec3(h, 0, -h), Vec3(h, 0, h), Vec3(-h, 0, h)}) {
            mesh.positions.push_back(mid + corner);
            mesh.normals.push_back(Vec3(0.0, -1.0, 0.0));
        }
        for (const glm::uvec3& t : {glm::uvec3(b, b + 1, b + 2), glm::uvec3(b, b + 2, b + 3)}) {
            mesh.triangles.push_back(t);
            mesh.materials.push_back(light0.material);
            mesh.sourceLines.push_back(0);
        }
    }
    scene.meshes.push_back(std::move(mesh));
    scene.finalize();
    ML_ASSERT(scene.lights.size() == size_t(lights), scene.lights.size(), " lights made for ", lights);
    ML_ASSERT(scene.lights.front().normal.y < 0, "grid lights should face down");
    return scene;
}

std::vector<ReceiverPoint> surfaceReceivers(const Scene& scene, size_t count, uint32_t seed) {
    std::vector<Triangle3> triangles;
    std::vector<double> cumulative;  // running sum of areas
    double total = 0;
    for (const Mesh& mesh : scene.meshes)
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const double area = mesh.area(t);
            if (scene.materials[mesh.materials[t]].emissive() || !(area > 0)) continue;
            triangles.push_back(mesh.triangle(t));
            cumulative.push_back(total += area);
        }
    std::vector<ReceiverPoint> points;
    if (triangles.empty()) return points;
    points.reserve(count);
    for (size_t i = 0; i < count; ++i) {
        const uint32_t id = uint32_t(i);
        const double pick = unitFrom(seedFor(seed, id, 0)) * total;
        const size_t k = std::min(size_t(std::upper_bound(cumulative.begin(), cumulative.end(), pick) -
                                         cumulative.begin()),
                                  triangles.size() - 1);
        const Triangle3& t = triangles[k];
        // Uniform over the triangle: the square-root warp of Osada et al.
        const double r = std::sqrt(unitFrom(seedFor(seed, id, 1))), s = unitFrom(seedFor(seed, id, 2));
        const Vec3 p = (1 - r) * t[0] + r * (1 - s) * t[1] + r * s * t[2];
        points.push_back({p, glm::normalize(glm::cross(t[1] - t[0], t[2] - t[0]))});
    }
    return points;
}

}  // namespace ml
