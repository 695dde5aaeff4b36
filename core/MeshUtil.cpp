#include "MeshUtil.h"

#include "Error.h"

#include <cmath>
#include <cstring>
#include <map>
#include <queue>
#include <stdexcept>
#include <unordered_map>

namespace ml {

namespace {

void checkPerTriangle(const Mesh& mesh, size_t size, const char* what) {
    if (size != 0 && size != mesh.triangles.size())
        throw std::invalid_argument(concat("mesh '", mesh.name, "' has ", size, " ", what, " for ",
                                           mesh.triangles.size(), " triangles"));
}

void checkIndices(const Mesh& mesh) {
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k)
            if (mesh.triangles[t][k] >= mesh.positions.size())
                throw std::invalid_argument(concat("triangle ", t, " of mesh '", mesh.name,
                                                   "' uses vertex ", mesh.triangles[t][k], " of ",
                                                   mesh.positions.size()));
}

// Exact position equality for welding: hashes the bit pattern, with -0 made
// +0 first so that the hash agrees with operator== (positions are finite here).
struct PositionHash {
    size_t operator()(const Vec3& p) const {
        size_t h = 0;
        for (int k = 0; k < 3; ++k) {
            const double v = p[k] + 0.0;
            uint64_t bits;
            std::memcpy(&bits, &v, sizeof bits);
            h ^= std::hash<uint64_t>{}(bits) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
        }
        return h;
    }
};

// Positions welded by exact equality: each distinct position gets the next
// id, in the order they are first met.
class WeldedIds {
public:
    uint32_t operator()(const Vec3& p) { return ids_.emplace(p, uint32_t(ids_.size())).first->second; }
    size_t size() const { return ids_.size(); }

private:
    std::unordered_map<Vec3, uint32_t, PositionHash> ids_;
};

}  // namespace

size_t removeDegenerateTriangles(Mesh& mesh, double relTol, std::vector<size_t>* removed) {
    if (!(relTol >= 0 && std::isfinite(relTol)))
        throw std::invalid_argument(
            concat("relative tolerance ", relTol, " is not a finite number >= 0"));
    checkPerTriangle(mesh, mesh.materials.size(), "materials");
    checkPerTriangle(mesh, mesh.sourceLines.size(), "source lines");
    checkPerTriangle(mesh, mesh.albedo.size(), "albedos");
    checkIndices(mesh);

    Bounds3 bounds;
    for (const glm::uvec3& tri : mesh.triangles)
        for (int k = 0; k < 3; ++k)
            if (isFinite(mesh.positions[tri[k]])) bounds.extend(mesh.positions[tri[k]]);
    const double minArea = std::pow(relTol * bounds.diagonal(), 2);

    size_t kept = 0;
    if (removed) removed->clear();
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const glm::uvec3 i = mesh.triangles[t];
        const Triangle3 p = mesh.triangle(t);
        const double area = mesh.area(t);
        const bool degenerate = i.x == i.y || i.y == i.z || i.z == i.x || !isFinite(p[0]) ||
                                !isFinite(p[1]) || !isFinite(p[2]) || !std::isfinite(area) ||
                                !(area > minArea);
        if (degenerate) {
            if (removed) removed->push_back(t);
            continue;
        }
        mesh.triangles[kept] = mesh.triangles[t];
        if (!mesh.materials.empty()) mesh.materials[kept] = mesh.materials[t];
        if (!mesh.sourceLines.empty()) mesh.sourceLines[kept] = mesh.sourceLines[t];
        if (!mesh.albedo.empty()) mesh.albedo[kept] = mesh.albedo[t];
        ++kept;
    }
    const size_t dropped = mesh.triangles.size() - kept;
    mesh.triangles.resize(kept);
    if (!mesh.materials.empty()) mesh.materials.resize(kept);
    if (!mesh.sourceLines.empty()) mesh.sourceLines.resize(kept);
    if (!mesh.albedo.empty()) mesh.albedo.resize(kept);
    return dropped;
}

void computeShadingNormals(Mesh& mesh, double creaseAngleDegrees) {
    if (!(creaseAngleDegrees >= 0 && creaseAngleDegrees <= 180))
        throw std::invalid_argument(
            concat("crease angle ", creaseAngleDegrees, " degrees is not in [0, 180]"));
    checkIndices(mesh);
    const size_t triangleCount = mesh.triangles.size();
    const size_t cornerCount = 3 * triangleCount;

    // Unit face normal per triangle and interior angle per corner (corner c is
    // vertex c % 3 of triangle c / 3).
    std::vector<Vec3> faceNormal(triangleCount);
    std::vector<double> cornerAngle(cornerCount);
    for (size_t t = 0; t < triangleCount; ++t) {
        const Vec3 an = mesh.areaNormal(t);
        const double len = glm::length(an);
        if (!(len > 0 && std::isfinite(len)))
            throw std::invalid_argument(concat("triangle ", t, " of mesh '", mesh.name,
                                               "' has zero or non-finite area; remove degenerate "
                                               "triangles before computing normals"));
        faceNormal[t] = an / len;
        const Triangle3 p = mesh.triangle(t);
        for (int k = 0; k < 3; ++k) {
            const Vec3 e1 = p[(k + 1) % 3] - p[k];
            const Vec3 e2 = p[(k + 2) % 3] - p[k];
            // atan2 stays accurate for angles near 0 and pi, where acos does not.
            cornerAngle[3 * t + k] = std::atan2(glm::length(glm::cross(e1, e2)), glm::dot(e1, e2));
        }
    }

    // Corners grouped by welded position, as a compressed list: the corners of
    // group g are groupCorners[groupStart[g] .. groupStart[g + 1]).
    WeldedIds groupOf;
    std::vector<uint32_t> cornerGroup(cornerCount);
    for (size_t c = 0; c < cornerCount; ++c) cornerGroup[c] = groupOf(mesh.positions[mesh.triangles[c / 3][c % 3]]);
    std::vector<size_t> groupStart(groupOf.size() + 1, 0);
    for (uint32_t g : cornerGroup) ++groupStart[g + 1];
    for (size_t g = 0; g < groupOf.size(); ++g) groupStart[g + 1] += groupStart[g];
    std::vector<size_t> groupCorners(cornerCount);
    {
        std::vector<size_t> fill(groupStart.begin(), groupStart.end() - 1);
        for (size_t c = 0; c < cornerCount; ++c) groupCorners[fill[cornerGroup[c]]++] = c;
    }

    // The tolerance lets triangles of one plane, whose normals differ only by
    // rounding, share vertices even at a crease angle of 0.
    const double minCos = std::cos(glm::radians(creaseAngleDegrees)) - 1e-12;
    const bool hasTexcoords = !mesh.texcoords.empty();
    std::vector<Vec3> positions, normals;
    std::vector<Vec2> texcoords;
    std::vector<glm::uvec3> triangles(triangleCount);
    for (size_t g = 0; g + 1 < groupStart.size(); ++g) {
        const size_t groupFirstVertex = positions.size();
        for (size_t a = groupStart[g]; a < groupStart[g + 1]; ++a) {
            const size_t corner = groupCorners[a];
            const Vec3& own = faceNormal[corner / 3];
            // Summed in the same order for every corner of the group, so two
            // corners with the same neighbour set get bit-identical normals
            // and share a vertex below.
            Vec3 sum(0.0);
            for (size_t b = groupStart[g]; b < groupStart[g + 1]; ++b) {
                const size_t other = groupCorners[b];
                const Vec3& n = faceNormal[other / 3];
                if (glm::dot(own, n) >= minCos) sum += cornerAngle[other] * n;
            }
            // Above 90 degrees opposite faces (a two-sided sheet) can cancel.
            const double len = glm::length(sum);
            const Vec3 normal = len > 1e-12 ? sum / len : own;

            const uint32_t original = mesh.triangles[corner / 3][corner % 3];
            const Vec2 uv = hasTexcoords ? mesh.texcoords[original] : Vec2(0.0);
            size_t v = groupFirstVertex;
            while (v < normals.size() && (normals[v] != normal || (hasTexcoords && texcoords[v] != uv))) ++v;
            if (v == normals.size()) {
                positions.push_back(mesh.positions[original]);
                normals.push_back(normal);
                if (hasTexcoords) texcoords.push_back(uv);
            }
            triangles[corner / 3][corner % 3] = uint32_t(v);
        }
    }
    mesh.positions = std::move(positions);
    mesh.normals = std::move(normals);
    mesh.texcoords = std::move(texcoords);
    mesh.triangles = std::move(triangles);
}

bool isClosedMesh(const Mesh& m) {
    WeldedIds weld;
    std::vector<uint32_t> id(m.positions.size());
    for (size_t v = 0; v < m.positions.size(); ++v) id[v] = weld(m.positions[v]);
    std::map<std::pair<uint32_t, uint32_t>, int> uses;
    for (const glm::uvec3& t : m.triangles)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = id[t[k]], b = id[t[(k + 1) % 3]];
            uses[{std::min(a, b), std::max(a, b)}]++;
        }
    for (const auto& [edge, n] : uses)
        if (n % 2) return false;
    return true;
}

size_t bisectLongEdges(Mesh& m, double maxLength) {
    if (!(maxLength > 0) || !std::isfinite(maxLength))
        throw std::invalid_argument(concat("bisectLongEdges: maxLength ", maxLength, " is not positive and finite"));
    checkPerTriangle(m, m.materials.size(), "materials");
    checkPerTriangle(m, m.sourceLines.size(), "source lines");
    checkPerTriangle(m, m.albedo.size(), "albedo values");
    const size_t before = m.positions.size();
    // Positions welded: an edge is the pair of its ends' ids.
    WeldedIds weld;
    std::vector<uint32_t> id;
    for (const Vec3& p : m.positions) id.push_back(weld(p));
    const auto key = [&](uint32_t a, uint32_t b) {
        const uint64_t x = id[a], y = id[b];
        return x < y ? x << 32 | y : y << 32 | x;
    };
    std::unordered_map<uint64_t, std::vector<uint32_t>> faces;  // edge -> triangles beside it
    std::priority_queue<std::pair<double, uint64_t>> queue;     // (length, edge), longest first
    const auto addEdge = [&](uint32_t a, uint32_t b, uint32_t t) {
        std::vector<uint32_t>& list = faces[key(a, b)];
        if (list.empty()) {
            const double length = glm::length(m.positions[b] - m.positions[a]);
            if (length > maxLength) queue.push({length, key(a, b)});
        }
        list.push_back(t);
    };
    for (uint32_t t = 0; t < m.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) addEdge(m.triangles[t][k], m.triangles[t][(k + 1) % 3], t);
    while (!queue.empty()) {
        const uint64_t edge = queue.top().second;
        queue.pop();
        const auto it = faces.find(edge);
        if (it == faces.end()) continue;  // split already
        const std::vector<uint32_t> beside = std::move(it->second);
        faces.erase(it);
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;  // per (a, b) as a triangle holds them
        for (const uint32_t t : beside) {
            const glm::uvec3 tri = m.triangles[t];
            int k = 0;
            while (k < 3 && key(tri[k], tri[(k + 1) % 3]) != edge) ++k;
            ML_ASSERT(k < 3, "bisectLongEdges: triangle ", t, " listed beside an edge it lacks");
            const uint32_t a = tri[k], b = tri[(k + 1) % 3], c = tri[(k + 2) % 3];
            const auto [mid, added] = midpoints.emplace(std::minmax(a, b), uint32_t(m.positions.size()));
            const uint32_t v = mid->second;
            if (added) {
                m.positions.push_back(0.5 * (m.positions[a] + m.positions[b]));
                const Vec3 n = m.normals[a] + m.normals[b];
                m.normals.push_back(glm::length(n) > 1e-12 ? glm::normalize(n) : m.normals[a]);
                if (!m.texcoords.empty()) m.texcoords.push_back(0.5 * (m.texcoords[a] + m.texcoords[b]));
                id.push_back(weld(m.positions.back()));
            }
            // (a, b, c) becomes (a, v, c) in place and (v, b, c) at the end;
            // the edges (b, c) and (v, c) move to or join the new triangle.
            const uint32_t u = uint32_t(m.triangles.size());
            m.triangles[t] = glm::uvec3(a, v, c);
            m.triangles.push_back(glm::uvec3(v, b, c));
            if (!m.materials.empty()) m.materials.push_back(m.materials[t]);
            if (!m.sourceLines.empty()) m.sourceLines.push_back(m.sourceLines[t]);
            if (!m.albedo.empty()) m.albedo.push_back(m.albedo[t]);
            std::vector<uint32_t>& bc = faces[key(b, c)];
            for (uint32_t& f : bc)
                if (f == t) f = u;
            addEdge(a, v, t);
            addEdge(v, c, t);
            addEdge(v, b, u);
            faces[key(v, c)].push_back(u);
        }
    }
    return m.positions.size() - before;
}

}  // namespace ml
