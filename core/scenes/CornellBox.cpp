#include "CornellBox.h"

#include "core/MeshUtil.h"

#include <array>
#include <cmath>

namespace ml {

namespace {

using Quad = std::array<Vec3, 4>;

// Materials, in Scene::materials order.
enum : uint32_t { kWhite, kRed, kGreen, kLight };

Vec3 centroid(const Quad& q) { return 0.25 * (q[0] + q[1] + q[2] + q[3]); }

// Appends a quad as two triangles, wound so that its front (counter-
// clockwise) side faces `facing`. The published data lists corners in no
// consistent order, hence the check rather than trusting it.
void addQuad(Mesh& mesh, Quad q, const Vec3& facing, uint32_t material) {
    // The cross product of the diagonals is twice the vector area, also for a
    // slightly non-planar quad.
    if (glm::dot(glm::cross(q[2] - q[0], q[3] - q[1]), facing) < 0) std::swap(q[1], q[3]);
    const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), q.begin(), q.end());
    mesh.triangles.push_back({base, base + 1, base + 2});
    mesh.triangles.push_back({base, base + 2, base + 3});
    for (int k = 0; k < 2; ++k) {
        mesh.materials.push_back(material);
        mesh.sourceLines.push_back(0);
    }
}

// A crease angle of 0 gives each face its own vertices and normal; the two
// triangles of a non-planar wall each keep their exact geometric normal.
Mesh finishMesh(Mesh mesh) {
    computeShadingNormals(mesh, 0.0);
    return mesh;
}

// One wall: its front faces the inside of the box.
Mesh wall(const char* name, const Quad& q, const Vec3& boxCenter, uint32_t material) {
    Mesh mesh;
    mesh.name = name;
    addQuad(mesh, q, boxCenter - centroid(q), material);
    return finishMesh(std::move(mesh));
}

// A block standing on the floor, given its top face; its sides drop to y = 0
// and all five faces look outwards.
Mesh block(const char* name, const Quad& top) {
    Mesh mesh;
    mesh.name = name;
    const Vec3 center = centroid(top) * Vec3(1.0, 0.5, 1.0);
    addQuad(mesh, top, centroid(top) - center, kWhite);
    for (int k = 0; k < 4; ++k) {
        const Vec3& a = top[k];
        const Vec3& b = top[(k + 1) % 4];
        const Quad side{Vec3(a.x, 0.0, a.z), a, b, Vec3(b.x, 0.0, b.z)};
        addQuad(mesh, side, centroid(side) - center, kWhite);
    }
    return finishMesh(std::move(mesh));
}

}  // namespace

Scene makeCornellBox() {
    Scene scene;
    scene.name = "cornell";
    scene.metresPerUnit = 0.001;  // millimetres
    scene.materials = {
        Material::diffuse("white", Rgb(0.725, 0.71, 0.68)),
        Material::diffuse("red", Rgb(0.63, 0.065, 0.05)),
        Material::diffuse("green", Rgb(0.14, 0.45, 0.091)),
        Material::diffuse("light", Rgb(0.78), Rgb(17.0, 12.0, 4.0)),
    };

    // The measured corners. The block sides are the top corners dropped to
    // the floor, exactly as in the data.
    const Quad floor{Vec3(552.8, 0.0, 0.0), Vec3(0.0, 0.0, 0.0), Vec3(0.0, 0.0, 559.2),
                     Vec3(549.6, 0.0, 559.2)};
    const Quad ceiling{Vec3(556.0, 548.8, 0.0), Vec3(556.0, 548.8, 559.2),
                       Vec3(0.0, 548.8, 559.2), Vec3(0.0, 548.8, 0.0)};
    const Quad back{Vec3(549.6, 0.0, 559.2), Vec3(0.0, 0.0, 559.2), Vec3(0.0, 548.8, 559.2),
                    Vec3(556.0, 548.8, 559.2)};
    const Quad right{Vec3(0.0, 0.0, 559.2), Vec3(0.0, 0.0, 0.0), Vec3(0.0, 548.8, 0.0),
                     Vec3(0.0, 548.8, 559.2)};
    const Quad left{Vec3(552.8, 0.0, 0.0), Vec3(549.6, 0.0, 559.2), Vec3(556.0, 548.8, 559.2),
                    Vec3(556.0, 548.8, 0.0)};
    const Quad shortTop{Vec3(130.0, 165.0, 65.0), Vec3(82.0, 165.0, 225.0),
                        Vec3(240.0, 165.0, 272.0), Vec3(290.0, 165.0, 114.0)};
    const Quad tallTop{Vec3(423.0, 330.0, 247.0), Vec3(265.0, 330.0, 296.0),
                       Vec3(314.0, 330.0, 456.0), Vec3(472.0, 330.0, 406.0)};
    // The data puts the light in the ceiling's plane (y = 548.8); 0.5 mm
    // lower it is a separate surface that rays and rasterisers cannot confuse
    // with the ceiling.
    const double lightY = 548.3;
    const Quad light{Vec3(343.0, lightY, 227.0), Vec3(343.0, lightY, 332.0),
                     Vec3(213.0, lightY, 332.0), Vec3(213.0, lightY, 227.0)};

    Bounds3 box;
    for (const Quad* q : {&floor, &ceiling, &back, &right, &left})
        for (const Vec3& p : *q) box.extend(p);
    const Vec3 center = box.center();

    scene.meshes.push_back(wall("floor", floor, center, kWhite));
    scene.meshes.push_back(wall("ceiling", ceiling, center, kWhite));
    scene.meshes.push_back(wall("back", back, center, kWhite));
    scene.meshes.push_back(wall("left", left, center, kRed));
    scene.meshes.push_back(wall("right", right, center, kGreen));
    scene.meshes.push_back(block("shortBlock", shortTop));
    scene.meshes.push_back(block("tallBlock", tallTop));
    Mesh lightMesh;
    lightMesh.name = "light";
    addQuad(lightMesh, light, Vec3(0.0, -1.0, 0.0), kLight);
    scene.meshes.push_back(finishMesh(std::move(lightMesh)));

    Camera camera;
    camera.position = Vec3(278.0, 273.0, -800.0);
    camera.target = Vec3(278.0, 273.0, 0.0);
    camera.up = Vec3(0.0, 1.0, 0.0);
    // 35 mm focal length, 25 mm film height.
    camera.fovYDegrees = glm::degrees(2.0 * std::atan(12.5 / 35.0));
    scene.camera = camera;

    scene.finalize();
    return scene;
}

}  // namespace ml
