#include "OfficeScene.h"

#include "core/Error.h"
#include "core/MeshUtil.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>
#include <utility>

namespace ml {

namespace {

// Materials, in Scene::materials order.
enum : uint32_t { kFloor, kWall, kCeiling, kDesk, kPartition, kCabinet, kPanel };

// Dimensions fixed by the layout (m); OfficeScene.h describes them.
constexpr double kMaxCell = 2.0;  // largest side of a room surface's cells
constexpr double kDeskWidth = 1.6, kDeskDepth = 0.8, kDeskTop = 0.72, kDeskThickness = 0.03;
constexpr double kLegSide = 0.05, kLegInset = 0.05;
constexpr double kDeskGap = 0.2;  // between the desks of a row
constexpr double kPartitionThickness = 0.05, kPartitionHeight = 1.5;
constexpr double kPartitionGap = 0.05;  // between the partition and each row
constexpr double kCabinetWidth = 0.8, kCabinetDepth = 0.45, kCabinetHeight = 1.2, kCabinetGap = 0.02;
constexpr double kWallGap = 0.05;  // between the end cabinets and the side walls
constexpr double kWalkway = 0.3;   // least free floor around the desk cluster
constexpr double kPanelGap = 0.01; // least gap between neighbouring panels
constexpr double kEyeHeight = 1.6, kCameraInset = 0.5;
constexpr double kHeadroom = 0.1;  // least gap between the panels and the eye or any furniture
constexpr double kMinRoom = 2.0, kMaxRoom = 1000.0;
constexpr int kMaxCount = 1000;
// The layout panelRadiance is given for: 12 panels of 0.6 × 0.6 m.
constexpr int kReferencePanels = 12;
constexpr double kReferencePanelSize = 0.6;

// The depth of the desk cluster along z: back row, partition with its gaps, front row.
constexpr double kClusterDepth = 2 * kDeskDepth + 2 * kPartitionGap + kPartitionThickness;

// The length of a row of `n` items of `size` with `gap` between neighbours.
double rowLength(int n, double size, double gap) { return n * size + (n - 1) * gap; }

int backRowDesks(int desks) { return (desks + 1) / 2; }

// Where the floor left free for the desks begins along x: past the cabinets, if any.
double freeFloorLeft(const OfficeSettings& s) { return -0.5 * s.width + (s.cabinets > 0 ? kCabinetDepth : 0.0); }

// The reason `s` cannot make an office, or empty. Each message names the
// field and the office spec key that sets it.
std::string whyInvalid(const OfficeSettings& s) {
    const std::pair<const char*, double> room[] = {{"width", s.width}, {"depth", s.depth}, {"height", s.height}};
    for (const auto& [field, v] : room)
        if (!(v >= kMinRoom && v <= kMaxRoom))
            return concat(field, " (size=WxDxH) must be in [", kMinRoom, ", ", kMaxRoom, "] m, got ", v);
    const std::pair<const char*, int> panels[] = {{"panelsX", s.panelsX}, {"panelsZ", s.panelsZ}};
    for (const auto& [field, n] : panels)
        if (n < 1 || n > kMaxCount)
            return concat(field, " (panels=NXxNZ) must be in [1, ", kMaxCount, "], got ", n);
    if (!(s.panelSize > 0) || !std::isfinite(s.panelSize))
        return concat("panelSize (panelsize=) must be a positive length in metres, got ", s.panelSize);
    if (!(s.panelDrop > 0) || !std::isfinite(s.panelDrop))
        return concat("panelDrop must be a positive length in metres, got ", s.panelDrop);
    const Rgb& ke = s.panelRadiance;
    for (double c : {ke.r, ke.g, ke.b})
        if (!(c >= 0) || !std::isfinite(c))
            return concat("panelRadiance must have finite components >= 0, got (", ke.r, ", ", ke.g, ", ", ke.b, ")");
    if (!(ke.r > 0 || ke.g > 0 || ke.b > 0)) return "panelRadiance must be positive in at least one component, got (0, 0, 0)";
    const std::pair<const char*, int> counts[] = {{"desks (desks=)", s.desks}, {"cabinets (cabinets=)", s.cabinets}};
    for (const auto& [field, n] : counts)
        if (n < 0 || n > kMaxCount) return concat(field, " must be in [0, ", kMaxCount, "], got ", n);
    if (s.partitions != 0 && s.partitions != 1)
        return concat("partitions (partitions=) must be 0 or 1, got ", s.partitions);

    // The panels: one per cell of the ceiling's grid, none touching another
    // (touching quads would merge into one light) nor the walls.
    const double cellX = s.width / s.panelsX, cellZ = s.depth / s.panelsZ;
    const double largest = std::min(cellX, cellZ) - kPanelGap;
    if (s.panelSize > largest + 1e-9)
        return concat("panels (panels=NXxNZ, panelsize=): ", s.panelsX, " x ", s.panelsZ, " panels of ",
                      s.panelSize, " m do not fit the ", s.width, " x ", s.depth, " m ceiling: its cells are ",
                      cellX, " x ", cellZ, " m and panels need ", kPanelGap,
                      " m between them; use fewer panels, panels of at most ", std::max(largest, 0.0),
                      " m or a larger room (size=)");
    const double panelY = s.height - s.panelDrop;
    const double tallest = std::max({kEyeHeight, s.partitions ? kPartitionHeight : 0.0,
                                     s.cabinets ? kCabinetHeight : 0.0, s.desks ? kDeskTop : 0.0});
    if (panelY < tallest + kHeadroom)
        return concat("panelDrop / height (size=WxDxH): the panels would hang at ", panelY,
                      " m, less than ", kHeadroom, " m above the camera's eye or the furniture (", tallest,
                      " m); the height must be at least ", tallest + kHeadroom + s.panelDrop, " m");

    if (s.cabinets > 0) {
        const double row = rowLength(s.cabinets, kCabinetWidth, kCabinetGap);
        if (row > s.depth - 2 * kWallGap)
            return concat("cabinets (cabinets=): a row of ", s.cabinets, " cabinets is ", row,
                          " m long, more than the ", s.depth, " m long left wall leaves (", s.depth - 2 * kWallGap,
                          " m with ", kWallGap, " m at each end)");
    }
    if (s.desks > 0 || s.partitions) {
        const double cluster = rowLength(std::max(backRowDesks(s.desks), 1), kDeskWidth, kDeskGap);
        const double freeWidth = 0.5 * s.width - freeFloorLeft(s);
        if (cluster + 2 * kWalkway > freeWidth)
            return concat("desks (desks=): ", s.desks, " desks in two rows need ", cluster + 2 * kWalkway,
                          " m of width with a ", kWalkway, " m walkway each side; the ", s.width,
                          " m wide room leaves ", freeWidth, " m beside the cabinets");
        if (kClusterDepth + 2 * kWalkway > s.depth)
            return concat("desks (desks=): the desk rows and partition need ", kClusterDepth + 2 * kWalkway,
                          " m of depth with a ", kWalkway, " m walkway each side; the room is ", s.depth,
                          " m deep");
    }
    return {};
}

// Appends a grid of nu × nv cells of two triangles over the parallelogram
// corner + [0,1]·u + [0,1]·v, sharing the grid's vertices, wound so that its
// front (counter-clockwise) side faces `facing`.
void addGrid(Mesh& mesh, const Vec3& corner, Vec3 u, Vec3 v, int nu, int nv, const Vec3& facing,
             uint32_t material) {
    if (glm::dot(glm::cross(u, v), facing) < 0) {
        std::swap(u, v);
        std::swap(nu, nv);
    }
    const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    const uint32_t row = static_cast<uint32_t>(nu) + 1;
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i)
            mesh.positions.push_back(corner + u * (double(i) / nu) + v * (double(j) / nv));
    for (uint32_t j = 0; j < uint32_t(nv); ++j)
        for (uint32_t i = 0; i < uint32_t(nu); ++i) {
            const uint32_t a = base + j * row + i, b = a + 1, c = a + row + 1, d = a + row;
            mesh.triangles.push_back({a, b, c});
            mesh.triangles.push_back({a, c, d});
            for (int k = 0; k < 2; ++k) {
                mesh.materials.push_back(material);
                mesh.sourceLines.push_back(0);
            }
        }
}

void addQuad(Mesh& mesh, const Vec3& corner, const Vec3& u, const Vec3& v, const Vec3& facing, uint32_t material) {
    addGrid(mesh, corner, u, v, 1, 1, facing, material);
}

// Cells of at most kMaxCell along a side of `length`.
int cellsAlong(double length) { return std::max(1, int(std::ceil(length / kMaxCell - 1e-9))); }

// One room surface: the rectangle corner + [0,1]·u + [0,1]·v in cells of at
// most kMaxCell, facing `facing` (into the room).
Mesh roomSurface(const char* name, const Vec3& corner, const Vec3& u, const Vec3& v, const Vec3& facing,
                 uint32_t material) {
    Mesh mesh;
    mesh.name = name;
    addGrid(mesh, corner, u, v, cellsAlong(glm::length(u)), cellsAlong(glm::length(v)), facing, material);
    return mesh;
}

// Faces of an axis-aligned box, as bits of a mask.
enum BoxFace : unsigned {
    kMinusX = 1, kPlusX = 2, kMinusY = 4, kPlusY = 8, kMinusZ = 16, kPlusZ = 32, kAllFaces = 63
};

// Appends the faces of the box [lo, hi] named in `faces`, facing outwards.
void addBox(Mesh& mesh, const Vec3& lo, const Vec3& hi, unsigned faces, uint32_t material) {
    const Vec3 size = hi - lo;
    for (int axis = 0; axis < 3; ++axis) {
        const int b = (axis + 1) % 3, c = (axis + 2) % 3;
        Vec3 u(0.0), v(0.0);
        u[b] = size[b];
        v[c] = size[c];
        for (int side = 0; side < 2; ++side) {
            if (!(faces & (1u << (2 * axis + side)))) continue;
            Vec3 corner = lo;
            Vec3 facing(0.0);
            if (side == 1) corner[axis] = hi[axis];
            facing[axis] = side == 1 ? 1.0 : -1.0;
            addQuad(mesh, corner, u, v, facing, material);
        }
    }
}

// A crease angle of 0 gives each face its own vertices and normal.
Mesh finishMesh(Mesh mesh) {
    computeShadingNormals(mesh, 0.0);
    return mesh;
}

// A desk whose tabletop covers x ∈ [x0, x0 + width], z ∈ [z0, z0 + depth].
Mesh desk(const std::string& name, double x0, double z0) {
    Mesh mesh;
    mesh.name = name;
    const double under = kDeskTop - kDeskThickness;
    addBox(mesh, Vec3(x0, under, z0), Vec3(x0 + kDeskWidth, kDeskTop, z0 + kDeskDepth), kAllFaces, kDesk);
    // The legs' tops are hidden under the tabletop and their bottoms on the floor.
    for (double lx : {x0 + kLegInset, x0 + kDeskWidth - kLegInset - kLegSide})
        for (double lz : {z0 + kLegInset, z0 + kDeskDepth - kLegInset - kLegSide})
            addBox(mesh, Vec3(lx, 0.0, lz), Vec3(lx + kLegSide, under, lz + kLegSide),
                   kAllFaces & ~(kMinusY | kPlusY), kDesk);
    return finishMesh(std::move(mesh));
}

// --- parseOfficeSpec's values ---------------------------------------------

std::vector<std::string> split(const std::string& text, char separator) {
    std::vector<std::string> parts;
    size_t start = 0;
    for (size_t at; (at = text.find(separator, start)) != std::string::npos; start = at + 1)
        parts.push_back(text.substr(start, at - start));
    parts.push_back(text.substr(start));
    return parts;
}

bool parseInt(const std::string& text, int& value) {
    const char* last = text.data() + text.size();
    const auto [end, ec] = std::from_chars(text.data(), last, value);
    return !text.empty() && ec == std::errc() && end == last;
}

bool parseLength(const std::string& text, double& value) {
    const char* last = text.data() + text.size();
    const auto [end, ec] = std::from_chars(text.data(), last, value);
    return !text.empty() && ec == std::errc() && end == last && std::isfinite(value);
}

}  // namespace

void OfficeSettings::validate() const {
    const std::string why = whyInvalid(*this);
    if (!why.empty()) throw InputError("office scene: " + why);
}

Scene makeOfficeScene(const OfficeSettings& s) {
    s.validate();
    Scene scene;
    scene.name = "office";
    const double panels = double(s.panelsX) * double(s.panelsZ);
    // Held constant: the reference layout's power, whatever the count and size.
    const double powerScale = (kReferencePanels * (kReferencePanelSize * kReferencePanelSize)) /
                              (panels * (s.panelSize * s.panelSize));
    scene.materials = {
        Material::diffuse("floor", Rgb(0.28, 0.30, 0.32)),   // grey carpet
        Material::diffuse("wall", Rgb(0.72, 0.70, 0.67)),    // off-white paint
        Material::diffuse("ceiling", Rgb(0.8)),
        Material::diffuse("desk", Rgb(0.60, 0.48, 0.35)),    // light wood
        Material::diffuse("partition", Rgb(0.30, 0.40, 0.50)),  // blue-grey fabric
        Material::diffuse("cabinet", Rgb(0.6)),
        Material::diffuse("panel", Rgb(0.8), s.panelRadiance * powerScale),  // white housing
    };

    const double w = s.width, d = s.depth, h = s.height;
    const double x0 = -0.5 * w, z0 = -0.5 * d;
    const Vec3 ex(w, 0, 0), ey(0, h, 0), ez(0, 0, d);
    scene.meshes.push_back(roomSurface("floor", Vec3(x0, 0, z0), ex, ez, Vec3(0, 1, 0), kFloor));
    scene.meshes.push_back(roomSurface("ceiling", Vec3(x0, h, z0), ex, ez, Vec3(0, -1, 0), kCeiling));
    scene.meshes.push_back(roomSurface("wallBack", Vec3(x0, 0, z0), ex, ey, Vec3(0, 0, 1), kWall));
    scene.meshes.push_back(roomSurface("wallFront", Vec3(x0, 0, -z0), ex, ey, Vec3(0, 0, -1), kWall));
    scene.meshes.push_back(roomSurface("wallLeft", Vec3(x0, 0, z0), ez, ey, Vec3(1, 0, 0), kWall));
    scene.meshes.push_back(roomSurface("wallRight", Vec3(-x0, 0, z0), ez, ey, Vec3(-1, 0, 0), kWall));
    for (Mesh& m : scene.meshes) m = finishMesh(std::move(m));

    // Panels, one centred in each cell of the ceiling's grid.
    Mesh panelMesh;
    panelMesh.name = "panels";
    const double cellX = w / s.panelsX, cellZ = d / s.panelsZ, half = 0.5 * s.panelSize;
    const double panelY = h - s.panelDrop;
    for (int j = 0; j < s.panelsZ; ++j)
        for (int i = 0; i < s.panelsX; ++i) {
            const double cx = x0 + (i + 0.5) * cellX, cz = z0 + (j + 0.5) * cellZ;
            addQuad(panelMesh, Vec3(cx - half, panelY, cz - half), Vec3(s.panelSize, 0, 0),
                    Vec3(0, 0, s.panelSize), Vec3(0, -1, 0), kPanel);
        }
    scene.meshes.push_back(finishMesh(std::move(panelMesh)));

    // Cabinets against the left wall, in view of the camera; their backs on
    // the wall are not made.
    const double cabinetRow = rowLength(s.cabinets, kCabinetWidth, kCabinetGap);
    for (int k = 0; k < s.cabinets; ++k) {
        Mesh mesh;
        mesh.name = concat("cabinet", k);
        const double cz = -0.5 * cabinetRow + k * (kCabinetWidth + kCabinetGap);
        addBox(mesh, Vec3(x0, 0, cz), Vec3(x0 + kCabinetDepth, kCabinetHeight, cz + kCabinetWidth),
               kAllFaces & ~(kMinusY | kMinusX), kCabinet);
        scene.meshes.push_back(finishMesh(std::move(mesh)));
    }

    // The desk cluster, centred in z and in the floor beside the cabinets:
    // back row, partition, front row.
    const double xc = 0.5 * (freeFloorLeft(s) + 0.5 * w), zc = 0.0;
    const double backZ = zc - 0.5 * kPartitionThickness - kPartitionGap - kDeskDepth;
    const double frontZ = zc + 0.5 * kPartitionThickness + kPartitionGap;
    const int backDesks = backRowDesks(s.desks);
    int made = 0;
    for (const auto& [count, rowZ] : {std::make_pair(backDesks, backZ), std::make_pair(s.desks - backDesks, frontZ)}) {
        const double row = rowLength(count, kDeskWidth, kDeskGap);
        for (int k = 0; k < count; ++k)
            scene.meshes.push_back(desk(concat("desk", made++), xc - 0.5 * row + k * (kDeskWidth + kDeskGap), rowZ));
    }
    if (s.partitions) {
        Mesh mesh;
        mesh.name = "partition";
        const double length = rowLength(std::max(backDesks, 1), kDeskWidth, kDeskGap);
        addBox(mesh, Vec3(xc - 0.5 * length, 0, zc - 0.5 * kPartitionThickness),
               Vec3(xc + 0.5 * length, kPartitionHeight, zc + 0.5 * kPartitionThickness), kAllFaces & ~kMinusY,
               kPartition);
        scene.meshes.push_back(finishMesh(std::move(mesh)));
    }

    Camera camera;
    camera.position = Vec3(0.5 * w - kCameraInset, kEyeHeight, 0.5 * d - kCameraInset);
    camera.target = Vec3(0.0, 0.8, 0.0);
    camera.fovYDegrees = 60.0;
    camera.validate();
    scene.camera = camera;

    scene.finalize();
    ML_ASSERT(scene.lights.size() == size_t(s.panelsX) * size_t(s.panelsZ), scene.lights.size(),
              " lights made for ", s.panelsX, " x ", s.panelsZ, " panels");
    return scene;
}

OfficeSettings parseOfficeSpec(const std::string& spec) {
    const std::string where = concat("office spec '", spec, "': ");
    OfficeSettings s;
    const std::string prefix = "office";
    if (spec.compare(0, prefix.size(), prefix) != 0 ||
        (spec.size() > prefix.size() && spec[prefix.size()] != ':'))
        throw InputError(where + "expected 'office' or 'office:KEY=VALUE[,KEY=VALUE]...'");
    if (spec.size() > prefix.size()) {
        std::set<std::string> seen;
        for (const std::string& item : split(spec.substr(prefix.size() + 1), ',')) {
            const size_t eq = item.find('=');
            if (eq == std::string::npos)
                throw InputError(concat(where, "'", item, "' is not KEY=VALUE (keys: panels, size, panelsize, "
                                        "desks, partitions, cabinets)"));
            const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
            if (!seen.insert(key).second) throw InputError(concat(where, key, ": given more than once"));
            const auto bad = [&](const char* expected) {
                return InputError(concat(where, key, ": expected ", expected, ", got '", value, "'"));
            };
            if (key == "panels") {
                const std::vector<std::string> n = split(value, 'x');
                if (n.size() != 2 || !parseInt(n[0], s.panelsX) || !parseInt(n[1], s.panelsZ) || s.panelsX < 1 ||
                    s.panelsZ < 1)
                    throw bad("NXxNZ with two positive integers, e.g. 8x6");
            } else if (key == "size") {
                const std::vector<std::string> m = split(value, 'x');
                if (m.size() != 3 || !parseLength(m[0], s.width) || !parseLength(m[1], s.depth) ||
                    !parseLength(m[2], s.height))
                    throw bad("WxDxH in metres, e.g. 10x8x3");
            } else if (key == "panelsize") {
                if (!parseLength(value, s.panelSize)) throw bad("a length in metres, e.g. 0.4");
            } else if (key == "desks") {
                if (!parseInt(value, s.desks) || s.desks < 0) throw bad("an integer >= 0");
            } else if (key == "partitions") {
                if (value != "0" && value != "1") throw bad("0 or 1");
                s.partitions = value == "1";
            } else if (key == "cabinets") {
                if (!parseInt(value, s.cabinets) || s.cabinets < 0) throw bad("an integer >= 0");
            } else {
                throw InputError(concat(where, "unknown key '", key,
                                        "' (keys: panels, size, panelsize, desks, partitions, cabinets)"));
            }
        }
    }
    const std::string why = whyInvalid(s);
    if (!why.empty()) throw InputError(where + why);
    return s;
}

}  // namespace ml
