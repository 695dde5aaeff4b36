#include "SceneChange.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace ml {

namespace {

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Rotation by `radians` about the unit `axis` (Rodrigues), right-handed.
Mat3 axisRotation(const Vec3& axis, double radians) {
    const double c = std::cos(radians), s = std::sin(radians), t = 1 - c;
    const Vec3 a = axis;
    // glm is column-major: m[column][row].
    Mat3 m;
    m[0] = Vec3(t * a.x * a.x + c, t * a.x * a.y + s * a.z, t * a.x * a.z - s * a.y);
    m[1] = Vec3(t * a.x * a.y - s * a.z, t * a.y * a.y + c, t * a.y * a.z + s * a.x);
    m[2] = Vec3(t * a.x * a.z + s * a.y, t * a.y * a.z - s * a.x, t * a.z * a.z + c);
    return m;
}

// The shortest rotation taking unit `from` to unit `to`; half a turn about
// any perpendicular when they are opposite.
Mat3 rotationBetween(const Vec3& from, const Vec3& to) {
    const Vec3 c = glm::cross(from, to);
    const double s = glm::length(c), d = glm::dot(from, to);
    if (s < 1e-12) {
        if (d > 0) return Mat3(1.0);
        const Vec3 other = std::abs(from.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
        return axisRotation(glm::normalize(glm::cross(from, other)), M_PI);
    }
    return axisRotation(c / s, std::atan2(s, d));
}

const Light& lightOf(const Scene& scene, const SceneChange& change) {
    if (change.light >= scene.lights.size())
        throwInputError(change.where, "no light ", change.light, " in the scene (",
                        scene.lights.empty() ? std::string("it has no lights")
                                             : concat("lights 0 to ", scene.lights.size() - 1),
                        ")");
    return scene.lights[change.light];
}

size_t meshNamed(const Scene& scene, const SceneChange& change) {
    for (size_t m = 0; m < scene.meshes.size(); ++m)
        if (scene.meshes[m].name == change.object) return m;
    std::string names;
    for (const Mesh& m : scene.meshes) names += (names.empty() ? "" : ", ") + m.name;
    throwInputError(change.where, "no object '", change.object, "' in the scene (objects: ", names, ")");
}

// Gives the triangles `moving` of mesh `m` vertices of their own wherever
// they share one with a triangle that stays, so that moving them does not
// drag (and tear) the rest of the mesh. Returns the vertices to move;
// `detached` tells whether any was copied.
std::vector<uint32_t> detachTriangles(Mesh& m, const std::vector<uint32_t>& moving, bool& detached) {
    std::vector<char> moves(m.triangles.size(), 0);
    for (uint32_t t : moving) moves[t] = 1;
    std::vector<char> usedByStaying(m.positions.size(), 0);
    for (size_t t = 0; t < m.triangles.size(); ++t)
        if (!moves[t])
            for (int k = 0; k < 3; ++k) usedByStaying[m.triangles[t][k]] = 1;
    std::map<uint32_t, uint32_t> copyOf;
    std::vector<uint32_t> vertices;
    for (uint32_t t : moving)
        for (int k = 0; k < 3; ++k) {
            uint32_t& v = m.triangles[t][k];
            if (usedByStaying[v]) {
                auto it = copyOf.find(v);
                if (it == copyOf.end()) {
                    it = copyOf.emplace(v, uint32_t(m.positions.size())).first;
                    m.positions.push_back(m.positions[v]);
                    m.normals.push_back(m.normals[v]);
                    if (!m.texcoords.empty()) m.texcoords.push_back(m.texcoords[v]);
                }
                v = it->second;
            }
            vertices.push_back(v);
        }
    detached = !copyOf.empty();
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    return vertices;
}

// Moves the triangles `moving` of mesh `mesh` rigidly (out.rotation, pivot,
// translation) and records where they were and are.
void moveTriangles(AppliedChange& out, size_t mesh, std::vector<uint32_t> moving) {
    Mesh& m = out.scene.meshes[mesh];
    std::sort(moving.begin(), moving.end());
    moving.erase(std::unique(moving.begin(), moving.end()), moving.end());
    out.mesh = long(mesh);
    out.triangles = moving;
    for (uint32_t v : detachTriangles(m, moving, out.detached)) {
        out.before.extend(m.positions[v]);
        m.positions[v] = out.transform(m.positions[v]);
        m.normals[v] = glm::normalize(out.rotation * m.normals[v]);
        out.after.extend(m.positions[v]);
    }
}

}  // namespace

SceneChange SceneChange::moveLight(size_t light, const Vec3& to) {
    SceneChange c;
    c.kind = Kind::MoveLight;
    c.light = light;
    c.point = to;
    return c;
}

SceneChange SceneChange::aimLight(size_t light, const Vec3& at) {
    SceneChange c;
    c.kind = Kind::AimLight;
    c.light = light;
    c.point = at;
    return c;
}

SceneChange SceneChange::moveObject(const std::string& name, const Vec3& by) {
    SceneChange c;
    c.kind = Kind::MoveObject;
    c.object = name;
    c.offset = by;
    return c;
}

SceneChange SceneChange::rotateObject(const std::string& name, const Vec3& axis, double degrees) {
    SceneChange c;
    c.kind = Kind::RotateObject;
    c.object = name;
    c.axis = axis;
    c.degrees = degrees;
    return c;
}

std::string SceneChange::describe() const {
    const auto v = [](const Vec3& p) { return concat("(", p.x, ", ", p.y, ", ", p.z, ")"); };
    switch (kind) {
        case Kind::MoveLight: return concat("light ", light, " move to ", v(point));
        case Kind::AimLight: return concat("light ", light, " aim at ", v(point));
        case Kind::MoveObject: return concat("object '", object, "' move by ", v(offset));
        case Kind::RotateObject: return concat("object '", object, "' rotate ", degrees, " degrees about ", v(axis));
    }
    return {};
}

AppliedChange applySceneChange(const Scene& scene, const SceneChange& change) {
    AppliedChange out;
    out.scene = scene;
    if (change.movesLight()) {
        const Light& light = lightOf(scene, change);
        if (!finite(change.point)) throwInputError(change.where, "light ", change.light, ": the target is not finite");
        Light& moved = out.scene.lights[change.light];
        const bool directional = light.kind == LightKind::Directional;
        if (change.kind == SceneChange::Kind::MoveLight) {
            if (directional)
                throwInputError(change.where, "light ", change.light, " ('", light.name,
                                "') is directional: it has no position to move (aim it instead)");
            out.translation = change.point - light.centroid;
        } else {
            // A directional light is aimed along the direction given; the
            // others at the point given, from where they are.
            const Vec3 d = directional ? change.point : change.point - light.centroid;
            if (!(glm::length(d) > 0))
                throwInputError(change.where, "light ", change.light, " ('", light.name, "') cannot aim at ",
                                directional ? "a zero direction" : "its own position");
            out.rotation = rotationBetween(light.normal, glm::normalize(d));
            out.pivot = light.centroid;
        }
        out.lights.push_back(change.light);
        if (light.punctual()) {
            PunctualEmission& e = moved.emission;
            e.position = out.transform(e.position);
            e.axis = glm::normalize(out.rotation * e.axis);
            e.reference = glm::normalize(out.rotation * e.reference);
        } else {
            moveTriangles(out, light.mesh, light.triangles);
        }
    } else {
        const size_t mesh = meshNamed(scene, change);
        const Mesh& m = scene.meshes[mesh];
        Bounds3 b;
        for (const Vec3& p : m.positions) b.extend(p);
        if (change.kind == SceneChange::Kind::MoveObject) {
            if (!finite(change.offset)) throwInputError(change.where, "object '", change.object, "': the offset is not finite");
            out.translation = change.offset;
        } else {
            if (!finite(change.axis) || !(glm::length(change.axis) > 0) || !std::isfinite(change.degrees))
                throwInputError(change.where, "object '", change.object,
                                "': a rotation needs a non-zero finite axis and a finite angle");
            out.rotation = axisRotation(glm::normalize(change.axis), change.degrees * M_PI / 180);
            out.pivot = b.center();
        }
        std::vector<uint32_t> all(m.triangles.size());
        for (size_t t = 0; t < all.size(); ++t) all[t] = uint32_t(t);
        moveTriangles(out, mesh, all);
        for (size_t l = 0; l < scene.lights.size(); ++l)
            if (!scene.lights[l].punctual() && scene.lights[l].mesh == mesh) out.lights.push_back(l);
    }
    out.scene.finalize();
    return out;
}

}  // namespace ml
