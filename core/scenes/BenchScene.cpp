#include "BenchScene.h"

#include "core/Error.h"

namespace ml {

namespace {

// A parallelogram corner + [0,1]·edgeU + [0,1]·edgeV split into
// subdivisions² cells of two triangles, facing edgeU × edgeV.
Mesh makeQuad(const std::string& name, uint32_t material, const Vec3& corner, const Vec3& edgeU,
              const Vec3& edgeV, int subdivisions) {
    Mesh mesh;
    mesh.name = name;
    const Vec3 normal = glm::normalize(glm::cross(edgeU, edgeV));
    const uint32_t side = static_cast<uint32_t>(subdivisions) + 1;
    for (uint32_t j = 0; j < side; ++j)
        for (uint32_t i = 0; i < side; ++i) {
            mesh.positions.push_back(corner + edgeU * (double(i) / subdivisions) +
                                     edgeV * (double(j) / subdivisions));
            mesh.normals.push_back(normal);
        }
    for (uint32_t j = 0; j + 1 < side; ++j)
        for (uint32_t i = 0; i + 1 < side; ++i) {
            const uint32_t a = j * side + i;
            const uint32_t b = a + 1;
            const uint32_t c = a + side + 1;
            const uint32_t d = a + side;
            mesh.triangles.push_back({a, b, c});
            mesh.triangles.push_back({a, c, d});
        }
    mesh.materials.assign(mesh.triangles.size(), material);
    mesh.sourceLines.assign(mesh.triangles.size(), 0);
    return mesh;
}

Material makeMaterial(const std::string& name, double kd, double ke) {
    Material m;
    m.name = name;
    m.kd = Rgb(kd);
    m.ke = Rgb(ke);
    return m;
}

}  // namespace

Scene makeBenchScene(int occluderSubdivisions) {
    if (occluderSubdivisions < 1)
        throw InputError(concat("bench scene: occluder subdivisions must be at least 1, got ",
                                occluderSubdivisions));
    Scene scene;
    scene.name = "bench";
    // The light does not reflect, so that indirect light comes from the
    // occluder and the floor only.
    scene.materials = {makeMaterial("light", 0.0, 1.0), makeMaterial("occluder", 0.5, 0.0),
                       makeMaterial("floor", 0.5, 0.0)};
    const Vec3 x(1, 0, 0), z(0, 0, 1);
    // x × z = −y: the light and the occluder face down, the floor (z × x) up.
    scene.meshes.push_back(makeQuad("light", 0, Vec3(-0.5, 1.0, -0.5), x, z, 1));
    scene.meshes.push_back(
        makeQuad("occluder", 1, Vec3(-0.2, 0.5, -0.3), 0.5 * x, 0.5 * z, occluderSubdivisions));
    scene.meshes.push_back(makeQuad("floor", 2, Vec3(-1.5, 0.0, -1.5), 3.0 * z, 3.0 * x, 1));

    // Looking down at the floor from below the light, so that both the shadow
    // and the emitting face are in view.
    Camera camera;
    camera.position = Vec3(0.0, 0.8, 2.8);
    camera.target = Vec3(0.0, 0.15, 0.0);
    camera.fovYDegrees = 45.0;
    scene.camera = camera;

    scene.finalize();
    return scene;
}

std::vector<ReceiverPoint> makeBenchReceivers(int perSide) {
    if (perSide < 1)
        throw InputError(concat("bench receivers: points per side must be at least 1, got ", perSide));
    constexpr double kHalfWidth = 1.2;
    const double cell = 2 * kHalfWidth / perSide;
    std::vector<ReceiverPoint> points;
    points.reserve(size_t(perSide) * size_t(perSide));
    for (int j = 0; j < perSide; ++j)
        for (int i = 0; i < perSide; ++i)
            points.push_back({Vec3(-kHalfWidth + (i + 0.5) * cell, 0.0, -kHalfWidth + (j + 0.5) * cell),
                              Vec3(0.0, 1.0, 0.0)});
    return points;
}

}  // namespace ml
