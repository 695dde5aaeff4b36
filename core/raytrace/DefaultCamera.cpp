#include "DefaultCamera.h"

#include "EmbreeScene.h"
#include "core/Error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace ml {

namespace {

// Whether x (unit normal n, the side facing `towards`) sees one of `lights`'
// centroids, in front of that light and on the side it faces.
bool seesALight(const EmbreeScene& rays, const std::vector<size_t>& lights, const Vec3& x, const Vec3& n,
                const Vec3& towards) {
    const Scene& scene = rays.scene();
    const Vec3 side = glm::dot(n, towards) >= 0 ? n : -n;
    for (size_t l : lights) {
        const Light& light = scene.lights[l];
        const Vec3 d = light.centroid - x;
        if (!(glm::dot(d, side) > 0) || !(glm::dot(-d, light.normal) > 0)) continue;
        const Vec3 o = rays.spawnPoint(x, side, d);
        if (!rays.occluded(o, light.centroid - o, 0, 1 - 1e-6, RayFilter{int(l), -1, false})) return true;
    }
    return false;
}

}  // namespace

ViewHits viewHits(const EmbreeScene& rays, const Camera& camera, double aspect, const std::vector<size_t>& lights) {
    constexpr int kColumns = 32, kRows = 18;
    Vec3 forward, right, up;
    camera.basis(forward, right, up);
    const double halfY = std::tan(glm::radians(camera.fovYDegrees) * 0.5), halfX = halfY * aspect;
    ViewHits h;
    for (int r = 0; r < kRows; ++r)
        for (int c = 0; c < kColumns; ++c) {
            const double x = (2 * (c + 0.5) / kColumns - 1) * halfX, y = (1 - 2 * (r + 0.5) / kRows) * halfY;
            const Vec3 d = glm::normalize(forward + x * right + y * up);
            ++h.rays;
            RayHit hit;
            if (!rays.intersect(camera.position, d, 0, std::numeric_limits<double>::infinity(), hit)) continue;
            const Vec3 n = glm::normalize(rays.scene().meshes[hit.mesh].areaNormal(hit.triangle));
            (glm::dot(n, d) < 0 ? h.front : h.back) += 1;
            if (seesALight(rays, lights, camera.position + hit.t * d, n, -d)) {
                ++h.lit;
                h.litArea += hit.t * hit.t;
            }
        }
    return h;
}

namespace {

// The free distance from p along unit d (the scene's diagonal where nothing is met).
double freeDistance(const EmbreeScene& rays, const Vec3& p, const Vec3& d, double diagonal) {
    RayHit hit;
    return rays.intersect(p, d, 0, diagonal, hit) ? hit.t : diagonal;
}

}  // namespace

CameraChoice chooseDefaultCamera(const Scene& scene, double aspect) {
    CameraChoice choice{Camera::framing(scene.bounds, aspect), "none in the file: framing the scene from +z"};
    if (scene.triangleCount() == 0) return choice;
    std::vector<size_t> lights;
    for (size_t l = 0; l < scene.lights.size(); ++l)
        if (!scene.lights[l].punctual() && scene.lights[l].planar) lights.push_back(l);
    if (lights.empty()) return choice;
    std::sort(lights.begin(), lights.end(), [&](size_t a, size_t b) {
        return luminance(scene.lights[a].power()) > luminance(scene.lights[b].power());
    });
    if (lights.size() > 4) lights.resize(4);
    const EmbreeScene rays(scene);
    const ViewHits outside = viewHits(rays, choice.camera, aspect, lights);
    // An object, or a room open to the camera: its light is in view.
    if (4 * outside.lit >= outside.front + outside.back) return choice;
    // The other sides, level, as far out: the one that sees the most lit
    // surfaces, if a quarter of what it meets is lit.
    const Vec3 centre = scene.bounds.center();
    const double distance = glm::length(choice.camera.position - centre);
    const Camera plusZ = choice.camera;
    int bestSide = 0;
    for (const auto& [dir, name] : {std::pair<Vec3, const char*>{Vec3(0, 0, -1), "-z"}, {Vec3(1, 0, 0), "+x"},
                                    {Vec3(-1, 0, 0), "-x"}}) {
        Camera c = plusZ;
        c.position = centre + distance * dir;
        const ViewHits h = viewHits(rays, c, aspect, lights);
        if (4 * h.lit < h.front + h.back || h.lit <= bestSide) continue;
        bestSide = h.lit;
        choice.camera = c;
        choice.reason = concat("none in the file; from +z, ", outside.lit, " of ", outside.rays,
                               " rays meet a surface that sees a light, so framing it from ", name, " (", h.lit,
                               " of ", h.rays, " lit)");
    }
    if (bestSide > 0) return choice;
    // A closed interior: from inside, the view showing the most lit area.
    double best = 0;
    // Inside: under each light, looking level each of 8 ways.
    const double diagonal = scene.bounds.diagonal();
    for (size_t l : lights) {
        const Light& light = scene.lights[l];
        const Vec3 n = light.normal;
        const Vec3 from = rays.spawnPoint(light.centroid, n, n);
        const double below = freeDistance(rays, from, n, diagonal);
        if (!(below > 0) || below >= diagonal) continue;  // nothing below: not a room's light
        const Vec3 eye = from + 0.55 * below * n;
        const Vec3 t = glm::normalize(std::abs(n.x) < 0.9 ? glm::cross(n, Vec3(1, 0, 0)) : glm::cross(n, Vec3(0, 1, 0)));
        const Vec3 b = glm::cross(n, t);
        for (int k = 0; k < 8; ++k) {
            const double phi = k * kPi / 4;
            const Vec3 d = std::cos(phi) * t + std::sin(phi) * b;
            Camera c;
            c.position = eye;
            c.target = eye + 0.5 * freeDistance(rays, eye, d, diagonal) * d;
            c.up = -n;
            c.fovYDegrees = 60;
            const ViewHits h = viewHits(rays, c, aspect, lights);
            if (h.litArea <= best) continue;
            best = h.litArea;
            choice.camera = c;
            choice.reason = concat("none in the file; from outside (+z, -z, +x, -x) at most a quarter of the surfaces "
                                   "seen see a light (", outside.lit, " of ", outside.rays, " rays from +z): a closed "
                                   "interior, so inside, under light '", light.name, "', looking level (", h.lit,
                                   " of ", h.rays, " rays lit)");
        }
    }
    return choice;
}

}  // namespace ml
