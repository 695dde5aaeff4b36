// glTF 2.0 through tinygltf, which parses the JSON, the .glb container and the
// buffers; everything else is checked here (tinygltf keeps indices and byte
// ranges as the file gives them).
//
// Images are left to us (TINYGLTF_NO_STB_IMAGE, TINYGLTF_NO_EXTERNAL_IMAGE):
// tinygltf would decode every image, normal and metal maps included, and only
// warns when an image file is missing. We decode the few textures that are
// averaged into Kd and Ke (TextureMean.h).
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include "GltfLoader.h"

#include "LuminaireLayout.h"
#include "PhotometricFile.h"
#include "TextureMean.h"

#include "core/Error.h"
#include "core/image/Photometry.h"
#include "core/MeshUtil.h"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <set>

namespace ml {

namespace {

namespace fs = std::filesystem;
namespace tg = tinygltf;

// Triangles with an area <= (1e-6 · mesh diagonal)² are dropped as degenerate.
constexpr double kDegenerateRelTol = 1e-6;

// An accessor without a buffer view (zeros, or sparse values only) may not
// have more elements than this: its count is not bounded by any data.
constexpr size_t kMaxUnbackedCount = size_t(1) << 26;

// A metal or a transmitting material this smooth or smoother is drawn as a
// perfect mirror or perfect glass (core/SmoothSpecular.h): at roughness 0.05
// (α = 0.0025 in glTF's GGX) the lobe is a fraction of a degree wide, less
// than a pixel of a typical view of what it reflects.
constexpr double kMirrorRoughness = 0.05;

// "meshes[2]"
std::string item(const std::string& array, size_t index) { return concat(array, "[", index, "]"); }

// "1 triangle", "3 triangles"
std::string count(size_t n, const char* singular, const char* plural) {
    return concat(n, " ", n == 1 ? singular : plural);
}

bool startsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

// Extensions a file may require: read, or approximated with a warning.
bool isHandledExtension(const std::string& name) {
    return name == "KHR_lights_punctual" || startsWith(name, "KHR_materials_");
}

const char* typeName(int type) {
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    case TINYGLTF_TYPE_MAT2: return "MAT2";
    case TINYGLTF_TYPE_MAT3: return "MAT3";
    case TINYGLTF_TYPE_MAT4: return "MAT4";
    default: return "unknown";
    }
}

const char* componentTypeName(int componentType) {
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return "byte";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return "unsigned byte";
    case TINYGLTF_COMPONENT_TYPE_SHORT: return "short";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return "unsigned short";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return "unsigned int";
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return "float";
    default: return "unknown";
    }
}

// One little-endian component as a double; normalized integers map to
// [0, 1] or [-1, 1] as glTF defines.
double readComponent(const unsigned char* p, int componentType, bool normalized) {
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float v;
        std::memcpy(&v, p, sizeof v);
        return v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        int8_t v;
        std::memcpy(&v, p, sizeof v);
        return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        std::memcpy(&v, p, sizeof v);
        return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        std::memcpy(&v, p, sizeof v);
        return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    default: {  // unsigned int: the only type left once the caller has checked
        uint32_t v;
        std::memcpy(&v, p, sizeof v);
        return v;
    }
    }
}

// A sampler's wrap mode (checked to be one of the three).
TextureWrap wrapMode(int mode) {
    if (mode == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE) return TextureWrap::ClampToEdge;
    if (mode == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT) return TextureWrap::MirroredRepeat;
    return TextureWrap::Repeat;
}

// The JSON chunk of a .glb (12-byte header, then chunk length, type "JSON"
// and data); empty when malformed, which tinygltf then reports.
std::string glbJson(const std::vector<unsigned char>& bytes) {
    if (bytes.size() < 20 || std::memcmp(bytes.data() + 16, "JSON", 4) != 0) return {};
    uint32_t length;
    std::memcpy(&length, bytes.data() + 12, sizeof length);
    if (length > bytes.size() - 20) return {};
    return std::string(bytes.begin() + 20, bytes.begin() + 20 + length);
}

// tinygltf's image callback: keeps the encoded bytes of images given as data
// URIs. Images in buffer views are read later, with their byte range checked
// (tinygltf does not check it); image files are read when needed.
// File access for a glTF read from memory (loadGltfFromMemory): none, so
// that no URI reaches the disk, whatever the bytes say.
bool noFileExists(const std::string&, void*) { return false; }
bool noFileRead(std::vector<unsigned char>*, std::string* error, const std::string& path, void*) {
    if (error) *error += "no files for a glTF read from memory: " + path;
    return false;
}
bool noFileWrite(std::string* error, const std::string&, const std::vector<unsigned char>&, void*) {
    if (error) *error += "no files for a glTF read from memory";
    return false;
}

using EncodedImages = std::map<int, std::vector<unsigned char>>;
bool keepEncodedImage(tg::Image* image, const int index, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void* encoded) {
    if (image->bufferView < 0)
        (*static_cast<EncodedImages*>(encoded))[index].assign(bytes, bytes + size);
    return true;
}

// A primitive as the file gives it, in its mesh's space.
struct Primitive {
    std::string at;    // "meshes[0].primitives[1]"
    std::string name;  // for Mesh::name
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;                   // empty: computed
    std::map<int, std::vector<Vec2>> texcoords;  // by set n of TEXCOORD_n
    std::vector<glm::uvec3> triangles;
    int material = -1;  // glTF material, -1 for the default
};

// A primitive under one node, in world space.
struct Piece {
    const Primitive* primitive = nullptr;
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;          // empty: computed
    std::vector<glm::uvec3> triangles;  // counter-clockwise front faces in world space
};

// What becomes of a glTF material.
struct MaterialChoice {
    Material material;
    bool dropped = false;      // alphaMode MASK cuts it away entirely
    bool backToo = false;      // doubleSided emitter: its triangles reversed as well
    int sceneIndex = -1;       // set when a kept triangle first uses it
    int texCoord = -1;         // the TEXCOORD_n set its textures read (Mesh::texcoords); -1: none
};

// Drops the vertices no triangle uses (the file's unused ones, those of
// removed triangles), keeping the order of the others.
void compactVertices(Mesh& mesh) {
    std::vector<uint32_t> newIndex(mesh.positions.size(), UINT32_MAX);
    Mesh out;
    for (glm::uvec3& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            uint32_t& n = newIndex[t[k]];
            if (n == UINT32_MAX) {
                n = static_cast<uint32_t>(out.positions.size());
                out.positions.push_back(mesh.positions[t[k]]);
                if (!mesh.normals.empty()) out.normals.push_back(mesh.normals[t[k]]);
                if (!mesh.texcoords.empty()) out.texcoords.push_back(mesh.texcoords[t[k]]);
            }
            t[k] = n;
        }
    mesh.positions = std::move(out.positions);
    mesh.normals = std::move(out.normals);
    mesh.texcoords = std::move(out.texcoords);
}

class GltfReader {
public:
    // `memory`: the file's bytes, read from memory with no disk access at
    // all (loadGltfFromMemory); null: read `path`.
    GltfReader(const std::string& path, const GltfOptions& options, const std::vector<unsigned char>* memory = nullptr)
        : path_(path), options_(options), memory_(memory) {}

    Scene read();

private:
    template <typename... Args>
    [[noreturn]] void fail(const Args&... args) const {
        throwInputError(SourceLocation{path_}, args...);
    }
    template <typename... Args>
    void warn(const Args&... args) {
        scene_.warnings.push_back(concat(path_, ": ", args...));
    }
    // One warning per file for things that may repeat (skins, vertex colours).
    template <typename... Args>
    void warnOnce(const std::string& key, const Args&... args) {
        if (warnedOnce_.insert(key).second) warn(args...);
    }
    // v[index], or an error naming the field that refers to it.
    template <typename T>
    const T& element(const std::vector<T>& v, int index, const char* array,
                     const std::string& field) const {
        if (index < 0 || static_cast<size_t>(index) >= v.size())
            fail(field, ": ", item(array, index), " does not exist (the file has ", v.size(), ")");
        return v[static_cast<size_t>(index)];
    }

    // The file
    void readModel();
    fs::path requireFile(const std::string& field, const std::string& uri) const;
    void checkBufferFiles(const std::string& json) const;
    void checkExtensions();

    // Nodes
    void traverse();
    Mat4 localTransform(int node) const;
    void readCamera(int node, const Mat4& world);
    void readLight(int node, const Mat4& world);
    void readLuminaire(int node, const Mat4& world);

    // Accessors and primitives
    struct ByteRange {
        const unsigned char* data;
        size_t size;
        size_t stride;  // the view's byteStride, 0 when packed
    };
    ByteRange viewBytes(int view, const std::string& field) const;
    std::vector<double> readAccessor(int index, const std::string& usedBy, int type,
                                     std::initializer_list<int> componentTypes) const;
    void applySparse(const tg::Accessor& a, const std::string& at, size_t components,
                     std::vector<double>& values) const;
    std::vector<Vec3> readVec3(int accessor, const std::string& usedBy) const;
    const Primitive& primitive(int mesh, int index);
    std::vector<glm::uvec3> assemble(const tg::Primitive& p, const std::string& at,
                                     const std::vector<uint32_t>& indices) const;
    Piece place(const Primitive& prim, const Mat4& world) const;

    // Materials
    void chooseMaterials();
    MaterialChoice chooseMaterial(int index);
    bool chooseSmoothLayer(const tg::Material& m, const std::string& at, Material& out,
                           const std::function<void(const std::string&)>& ignore);
    std::shared_ptr<const Texture> texture(const tg::TextureInfo& info, const std::string& field);
    Rgb textureMean(const Texture& tex, int texCoord, int material, const std::string& field,
                    bool perTriangle = false);
    uint32_t sceneMaterial(int gltfMaterial);

    // Meshes
    void buildMeshes();
    void addBackFaces(const Mesh& front);

    std::string path_;
    GltfOptions options_;
    const std::vector<unsigned char>* memory_;  // the file's bytes when read from memory
    fs::path baseDir_;
    tg::Model model_;
    EncodedImages encodedImages_;
    Scene scene_;
    std::set<std::string> warnedOnce_;

    struct Instance {
        int node;
        int mesh;
        Mat4 world;
    };
    std::vector<Instance> instances_;
    std::map<std::pair<int, int>, Primitive> primitives_;
    std::vector<Piece> pieces_;
    std::map<int, std::shared_ptr<const Texture>> textures_;  // by glTF texture index
    // Per piece (index into pieces_), each triangle's base colour texture
    // mean over its footprint (before the factor); empty: not textured.
    std::vector<std::vector<Rgb>> footprints_;
    std::vector<MaterialChoice> materials_;             // by glTF material index
    int defaultMaterial_ = -1;

    std::optional<Camera> camera_;  // target set once the scene's size is known
    Vec3 cameraForward_{0.0};       // unit
    std::vector<Light> punctual_;  // KHR_lights_punctual, in traversal order
    std::set<int> rangeWarned_;
    std::map<std::string, std::shared_ptr<const CandelaTable>> luminaireTables_;  // by file: read once

    size_t pointsAndLines_ = 0;
    std::string firstPointsAndLines_;
    size_t degenerate_ = 0;
    std::string firstDegenerate_;
};

Scene GltfReader::read() {
    if (!(options_.creaseAngleDegrees >= 0 && options_.creaseAngleDegrees <= 180))
        throw InputError(concat("crease angle ", options_.creaseAngleDegrees,
                                " degrees is not in [0, 180]"));
    if (!(options_.emissionScale >= 0 && std::isfinite(options_.emissionScale)))
        throw InputError(concat("emission scale ", options_.emissionScale,
                                " is not a finite number >= 0"));
    scene_.name = path_;
    readModel();
    checkExtensions();
    traverse();
    for (const Instance& in : instances_) {
        const tg::Mesh& mesh = model_.meshes[static_cast<size_t>(in.mesh)];
        for (size_t p = 0; p < mesh.primitives.size(); ++p) {
            const Primitive& prim = primitive(in.mesh, static_cast<int>(p));
            if (!prim.triangles.empty()) pieces_.push_back(place(prim, in.world));
        }
    }
    if (pointsAndLines_ > 0)
        warn(count(pointsAndLines_, "primitive", "primitives"),
             " of points or lines skipped (first ", firstPointsAndLines_, ")");
    chooseMaterials();
    buildMeshes();
    scene_.metresPerUnit = 1;  // glTF's unit
    for (Light& l : punctual_) {
        // Names as unique as probe columns and the viewer's panel need.
        std::string name = l.name;
        for (int k = 1; std::any_of(scene_.lights.begin(), scene_.lights.end(),
                                    [&](const Light& o) { return o.name == name; });
             ++k)
            name = concat(l.name, "#", k);
        l.name = name;
        scene_.lights.push_back(std::move(l));
    }
    scene_.finalize();
    if (camera_) {  // looking half the scene's size ahead: only the direction matters
        camera_->target = camera_->position + 0.5 * scene_.bounds.diagonal() * cameraForward_;
        scene_.camera = camera_;
    }
    if (scene_.lights.empty()) warn("no emissive surface and no light: the image will be black");
    return std::move(scene_);
}

// The file ------------------------------------------------------------------

void GltfReader::readModel() {
    std::error_code ec;
    const fs::path file(path_);
    std::vector<unsigned char> bytes;
    std::string error;
    if (memory_) {
        bytes = *memory_;
    } else {
        if (!fs::is_regular_file(file, ec) || !tg::ReadWholeFile(&bytes, &error, path_, nullptr))
            fail("cannot open glTF file");
        baseDir_ = fs::absolute(file, ec).parent_path();
    }
    if (bytes.size() > UINT32_MAX) fail("file larger than 4 GiB");
    const bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
    checkBufferFiles(binary ? glbJson(bytes) : std::string(bytes.begin(), bytes.end()));

    tg::TinyGLTF parser;
    parser.SetImageLoader(&keepEncodedImage, &encodedImages_);
    if (memory_) parser.SetFsCallbacks({&noFileExists, &tg::ExpandFilePath, &noFileRead, &noFileWrite, nullptr});
    std::string warnings;
    bool ok = false;
    try {
        const auto size = static_cast<unsigned int>(bytes.size());
        ok = binary ? parser.LoadBinaryFromMemory(&model_, &error, &warnings, bytes.data(), size,
                                                  baseDir_.string())
                    : parser.LoadASCIIFromString(&model_, &error, &warnings,
                                                 reinterpret_cast<const char*>(bytes.data()),
                                                 size, baseDir_.string());
    } catch (const std::exception& e) {  // tinygltf is not exception-free on bad input
        error += e.what();
    }
    auto lines = [](const std::string& text) {
        std::vector<std::string> out;
        std::istringstream in(text);
        for (std::string line; std::getline(in, line);)
            if (!line.empty()) out.push_back(line);
        return out;
    };
    for (const std::string& line : lines(warnings)) warn("tinygltf: ", line);
    if (!ok) {
        std::string message;
        for (const std::string& line : lines(error)) message += (message.empty() ? "" : "; ") + line;
        fail(binary ? "not a valid .glb file: " : "not a valid glTF JSON file: ",
             message.empty() ? "tinygltf gives no reason" : message);
    }
    for (size_t i = 0; i < model_.images.size(); ++i)
        if (model_.images[i].bufferView < 0 && !encodedImages_.count(static_cast<int>(i)))
            requireFile(item("images", i) + ".uri", model_.images[i].uri);
}

// The file a URI names, relative to the glTF's folder only (tinygltf would
// also look in the working directory); an empty path for a data URI.
fs::path GltfReader::requireFile(const std::string& field, const std::string& uri) const {
    if (tg::IsDataURI(uri)) return {};
    if (memory_) fail(field, ": file '", uri, "' not found (the glTF is read from memory, with no files)");
    const fs::path file = (baseDir_ / tg::dlib::urldecode(uri)).lexically_normal();
    std::error_code ec;
    if (uri.empty() || !fs::is_regular_file(file, ec))
        fail(field, ": file '", uri, "' not found (", file.string(), ")");
    return file;
}

// tinygltf reports a missing buffer file as "File not found : scene.bin"
// without saying which buffer; this names it first.
void GltfReader::checkBufferFiles(const std::string& json) const {
    const nlohmann::json doc = nlohmann::json::parse(json, nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) return;
    const auto buffers = doc.find("buffers");
    if (buffers == doc.end() || !buffers->is_array()) return;
    for (size_t i = 0; i < buffers->size(); ++i) {
        const nlohmann::json& b = (*buffers)[i];
        if (!b.is_object()) continue;
        const auto uri = b.find("uri");
        if (uri != b.end() && uri->is_string())
            requireFile(item("buffers", i) + ".uri", uri->get<std::string>());
    }
}

void GltfReader::checkExtensions() {
    for (const std::string& name : model_.extensionsRequired)
        if (!isHandledExtension(name)) fail("extensionsRequired: '", name, "' is not supported");
    for (const std::string& name : model_.extensionsUsed)
        if (!isHandledExtension(name)) warn("extensionsUsed: '", name, "' is not supported; ignored");
}

// Nodes -----------------------------------------------------------------------

void GltfReader::traverse() {
    std::vector<int> roots;
    std::string rootsField;
    if (!model_.scenes.empty()) {
        const int s = model_.defaultScene >= 0 ? model_.defaultScene : 0;
        roots = element(model_.scenes, s, "scenes", "scene").nodes;
        rootsField = item("scenes", s) + ".nodes";
    } else {  // no scene: every node that is nobody's child
        std::vector<bool> isChild(model_.nodes.size());
        for (const tg::Node& n : model_.nodes)
            for (int c : n.children)
                if (c >= 0 && static_cast<size_t>(c) < isChild.size()) isChild[c] = true;
        for (size_t n = 0; n < isChild.size(); ++n)
            if (!isChild[n]) roots.push_back(static_cast<int>(n));
        rootsField = "nodes";
    }

    // Depth first, children in order, without recursion (a deep file cannot
    // overflow the stack).
    struct Pending {
        int node;
        Mat4 parent;
        std::string from;
    };
    std::vector<Pending> stack;
    for (auto r = roots.rbegin(); r != roots.rend(); ++r) stack.push_back({*r, Mat4(1.0), rootsField});
    std::vector<bool> reached(model_.nodes.size());
    while (!stack.empty()) {
        const Pending p = std::move(stack.back());
        stack.pop_back();
        const tg::Node& node = element(model_.nodes, p.node, "nodes", p.from);
        const std::string at = item("nodes", p.node);
        if (reached[p.node])
            fail(p.from, ": ", at, " is reached a second time (a node has one parent at most)");
        reached[p.node] = true;
        const Mat4 world = p.parent * localTransform(p.node);
        if (node.mesh >= 0 || node.mesh < -1) {
            element(model_.meshes, node.mesh, "meshes", at + ".mesh");
            instances_.push_back({p.node, node.mesh, world});
        }
        if (node.camera != -1) readCamera(p.node, world);
        readLight(p.node, world);
        if (node.skin >= 0) warnOnce("skin", at, ": skins are not supported; the rest pose is used");
        for (auto c = node.children.rbegin(); c != node.children.rend(); ++c)
            stack.push_back({*c, world, at + ".children"});
    }
}

Mat4 GltfReader::localTransform(int index) const {
    const tg::Node& n = model_.nodes[static_cast<size_t>(index)];
    const std::string at = item("nodes", index);
    auto check = [&](const std::vector<double>& values, size_t expected, const char* field) {
        if (!values.empty() && values.size() != expected)
            fail(at, ".", field, " has ", values.size(), " values, expected ", expected);
        for (double v : values)
            if (!std::isfinite(v)) fail(at, ".", field, " has a value that is not finite");
    };
    check(n.matrix, 16, "matrix");
    check(n.translation, 3, "translation");
    check(n.rotation, 4, "rotation");
    check(n.scale, 3, "scale");
    if (!n.matrix.empty()) return glm::make_mat4(n.matrix.data());  // both column-major
    Mat4 m(1.0);
    if (!n.translation.empty()) m = glm::translate(m, glm::make_vec3(n.translation.data()));
    if (!n.rotation.empty()) {
        const glm::dquat q(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]);
        const double length = glm::length(q);
        if (!(length > 0) || !std::isfinite(length)) fail(at, ".rotation is not a unit quaternion");
        m *= glm::mat4_cast(q / length);
    }
    if (!n.scale.empty()) m = glm::scale(m, glm::make_vec3(n.scale.data()));
    return m;
}

void GltfReader::readCamera(int node, const Mat4& world) {
    const std::string at = item("nodes", node) + ".camera";
    const int index = model_.nodes[static_cast<size_t>(node)].camera;
    const tg::Camera& c = element(model_.cameras, index, "cameras", at);
    const std::string cam = item("cameras", index);
    if (c.type != "perspective") {
        warnOnce(cam, cam, " '", c.name, "': ", c.type.empty() ? "untyped" : c.type.c_str(),
                 " camera not supported; ignored");
        return;
    }
    if (camera_) return;
    const double yfov = c.perspective.yfov;
    if (!(yfov > 0 && yfov < kPi)) fail(cam, ".perspective.yfov ", yfov, " is not in (0, pi)");
    const Mat3 m(world);
    const Vec3 forward = m * Vec3(0, 0, -1), up = m * Vec3(0, 1, 0);
    const double fl = glm::length(forward), ul = glm::length(up);
    if (!(fl > 0 && ul > 0 && std::isfinite(fl) && std::isfinite(ul)) ||
        glm::length(glm::cross(forward / fl, up / ul)) < 1e-6)
        fail(item("nodes", node), ": the camera's transform is singular");
    Camera camera;
    camera.position = Vec3(world[3]);
    camera.up = up / ul;
    camera.fovYDegrees = yfov * 180 / kPi;
    camera_ = camera;
    cameraForward_ = forward / fl;
}

// KHR_lights_punctual: the light a node carries, placed by the node's world
// transform (it shines along the node's −Z). Intensity: candela for point
// and spot lights, lux for directional ones; turned into W·sr⁻¹ and W·m⁻²
// with K = 179 lm/W (core/PunctualLight.h), times the linear RGB colour.
void GltfReader::readLight(int node, const Mat4& world) {
    const tg::Node& n = model_.nodes[static_cast<size_t>(node)];
    readLuminaire(node, world);
    const auto ext = n.extensions.find("KHR_lights_punctual");
    if (ext == n.extensions.end() || !ext->second.IsObject() || !ext->second.Has("light")) return;
    const std::string field = item("nodes", node) + ".extensions.KHR_lights_punctual.light";
    const tg::Value& v = ext->second.Get("light");
    if (!v.IsNumber()) fail(field, " is not a number");
    const int index = v.GetNumberAsInt();
    const tg::Light& light = element(model_.lights, index, "KHR_lights_punctual.lights", field);
    const std::string at = item("KHR_lights_punctual.lights", index);
    Light l;
    l.name = !n.name.empty() ? n.name : !light.name.empty() ? light.name : concat("light", index);
    l.group = lightGroupOf(n.name);
    Rgb colour(1.0);
    if (!light.color.empty()) {
        if (light.color.size() != 3) fail(at, ".color has ", light.color.size(), " values, expected 3");
        colour = Rgb(light.color[0], light.color[1], light.color[2]);
    }
    for (double c : {colour.r, colour.g, colour.b})
        if (!(c >= 0 && std::isfinite(c))) fail(at, ".color ", c, " is not a finite number >= 0");
    if (!(light.intensity >= 0 && std::isfinite(light.intensity)))
        fail(at, ".intensity ", light.intensity, " is not a finite number >= 0");
    const Mat3 m(world);
    const Vec3 axis = m * Vec3(0, 0, -1), reference = m * Vec3(1, 0, 0);
    if (!(glm::length(axis) > 0) || !isFinite(axis))
        fail(item("nodes", node), ": the light's transform is singular");
    l.emission.axis = glm::normalize(axis);
    l.emission.reference = reference;
    l.emission.intensity = colour * (light.intensity / kRadianceEfficacy);
    if (light.type == "point" || light.type == "spot") {
        l.kind = LightKind::Point;
        l.emission.position = Vec3(world[3]);
        if (light.type == "spot") {
            const double inner = light.spot.innerConeAngle, outer = light.spot.outerConeAngle;
            if (!(inner >= 0 && inner < outer && outer <= kPi / 2))
                fail(at, ".spot: cone angles inner ", inner, " and outer ", outer,
                     " are not 0 <= inner < outer <= pi/2");
            l.emission.profile.shape = IntensityProfile::Shape::Spot;
            l.emission.profile.cosInner = std::cos(inner);
            l.emission.profile.cosOuter = std::cos(outer);
        }
    } else if (light.type == "directional") {
        l.kind = LightKind::Directional;
    } else {
        fail(at, ".type '", light.type, "' is not point, spot or directional");
    }
    if (light.range > 0 && rangeWarned_.insert(index).second)
        warn(at, " '", light.name, "': range ", light.range,
             " m ignored: light falls off by the inverse-square law at every distance");
    punctual_.push_back(std::move(l));
}

// A photometric luminaire on a node: extras {"photometry": "file.ies" or
// ".ldt" (relative to the glTF file), "multiplier": 1, "group": "..."},
// placed at the node's origin, aimed along its −Z with C0 along its +X (as
// KHR_lights_punctual aims lights). The node's name names the light.
void GltfReader::readLuminaire(int node, const Mat4& world) {
    const tg::Node& n = model_.nodes[static_cast<size_t>(node)];
    if (!n.extras.IsObject() || !n.extras.Has("photometry")) return;
    const std::string at = item("nodes", node) + ".extras";
    const tg::Value& file = n.extras.Get("photometry");
    if (!file.IsString() || file.Get<std::string>().empty()) fail(at, ".photometry is not a file name");
    if (memory_) fail(at, ".photometry: file '", file.Get<std::string>(), "' not found (the glTF is read from memory, with no files)");
    LuminairePlacement p;
    if (n.extras.Has("multiplier")) {
        const tg::Value& m = n.extras.Get("multiplier");
        if (!m.IsNumber() || !(m.GetNumberAsDouble() >= 0) || !std::isfinite(m.GetNumberAsDouble()))
            fail(at, ".multiplier is not a finite number >= 0");
        p.multiplier = m.GetNumberAsDouble();
    }
    std::string group;
    if (n.extras.Has("group")) {
        if (!n.extras.Get("group").IsString()) fail(at, ".group is not a string");
        group = n.extras.Get("group").Get<std::string>();
    }
    const Mat3 m(world);
    p.position = Vec3(world[3]);
    p.aim = m * Vec3(0, 0, -1);
    p.reference = m * Vec3(1, 0, 0);
    if (!(glm::length(p.aim) > 0) || !isFinite(p.aim)) fail(item("nodes", node), ": the luminaire's transform is singular");
    const std::string path = (baseDir_ / file.Get<std::string>()).lexically_normal().string();
    auto& table = luminaireTables_[path];
    if (!table) table = std::make_shared<const CandelaTable>(loadPhotometricFile(path));
    const std::string name = n.name.empty() ? concat("luminaire", node) : n.name;
    punctual_.push_back(luminaireLight(table, p, name, group.empty() ? lightGroupOf(name) : group));
}

// Accessors and primitives ---------------------------------------------------

GltfReader::ByteRange GltfReader::viewBytes(int view, const std::string& field) const {
    const tg::BufferView& v = element(model_.bufferViews, view, "bufferViews", field);
    const std::string at = item("bufferViews", view);
    const tg::Buffer& buffer = element(model_.buffers, v.buffer, "buffers", at + ".buffer");
    const size_t size = buffer.data.size();
    if (v.byteOffset > size || v.byteLength > size - v.byteOffset)
        fail(at, ": bytes ", v.byteOffset, " to ", v.byteOffset + v.byteLength, " are outside ",
             item("buffers", v.buffer), " (", size, " bytes)");
    return {buffer.data.data() + v.byteOffset, v.byteLength, v.byteStride};
}

std::vector<double> GltfReader::readAccessor(int index, const std::string& usedBy, int type,
                                             std::initializer_list<int> componentTypes) const {
    const tg::Accessor& a = element(model_.accessors, index, "accessors", usedBy);
    const std::string at = concat(usedBy, " (", item("accessors", index), ")");
    if (a.type != type) fail(at, ": type ", typeName(a.type), ", expected ", typeName(type));
    if (std::find(componentTypes.begin(), componentTypes.end(), a.componentType) ==
        componentTypes.end()) {
        std::string allowed;
        for (int t : componentTypes) allowed += (allowed.empty() ? "" : ", ") + std::string(componentTypeName(t));
        fail(at, ": componentType ", a.componentType, " (", componentTypeName(a.componentType),
             ") is not allowed here (", allowed, ")");
    }
    const size_t components = static_cast<size_t>(tg::GetNumComponentsInType(a.type));
    const size_t componentSize = static_cast<size_t>(tg::GetComponentSizeInBytes(a.componentType));
    const size_t elementSize = components * componentSize;

    std::vector<double> values;
    if (a.bufferView >= 0) {
        const ByteRange bytes = viewBytes(a.bufferView, concat(item("accessors", index), ".bufferView"));
        const size_t stride = bytes.stride ? bytes.stride : elementSize;
        if (stride < elementSize)
            fail(item("bufferViews", a.bufferView), ".byteStride ", stride, " is smaller than an element of ",
                 at, " (", elementSize, " bytes)");
        // Written so that nothing overflows: every term is at most bytes.size.
        const bool fits = a.byteOffset <= bytes.size && elementSize <= bytes.size - a.byteOffset &&
                          (a.count == 0 || a.count - 1 <= (bytes.size - a.byteOffset - elementSize) / stride);
        if (!fits)
            fail(at, ": ", a.count, " elements of ", elementSize, " bytes every ", stride,
                 " bytes from byteOffset ", a.byteOffset, " do not fit in ",
                 item("bufferViews", a.bufferView), " (", bytes.size, " bytes)");
        values.resize(a.count * components);
        for (size_t e = 0; e < a.count; ++e)
            for (size_t c = 0; c < components; ++c)
                values[e * components + c] = readComponent(
                    bytes.data + a.byteOffset + e * stride + c * componentSize, a.componentType, a.normalized);
    } else {
        if (a.count > kMaxUnbackedCount)
            fail(at, ": count ", a.count, " without a bufferView is more than ", kMaxUnbackedCount);
        values.assign(a.count * components, 0.0);  // glTF: zeros, unless sparse replaces some
    }
    if (a.sparse.isSparse) applySparse(a, at, components, values);
    if (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT)
        for (size_t k = 0; k < values.size(); ++k)
            if (!std::isfinite(values[k])) fail(at, ": element ", k / components, " is not finite");
    return values;
}

void GltfReader::applySparse(const tg::Accessor& a, const std::string& at, size_t components,
                             std::vector<double>& values) const {
    const auto& s = a.sparse;
    const std::string sparseAt = at + ".sparse";
    if (s.count < 0 || static_cast<size_t>(s.count) > a.count)
        fail(sparseAt, ".count ", s.count, " is not in [0, ", a.count, "]");
    const size_t n = static_cast<size_t>(s.count);
    const int indexType = s.indices.componentType;
    if (indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        fail(sparseAt, ".indices.componentType ", indexType, " is not an unsigned integer type");
    const size_t indexSize = static_cast<size_t>(tg::GetComponentSizeInBytes(static_cast<uint32_t>(indexType)));
    const size_t componentSize = static_cast<size_t>(tg::GetComponentSizeInBytes(a.componentType));
    const size_t elementSize = components * componentSize;
    // Indices, then values: each tightly packed from its byteOffset.
    auto range = [&](int view, int offset, size_t size, const char* what) {
        const ByteRange bytes = viewBytes(view, concat(sparseAt, ".", what, ".bufferView"));
        if (offset < 0 || static_cast<size_t>(offset) > bytes.size ||
            (size > 0 && n > (bytes.size - static_cast<size_t>(offset)) / size))
            fail(sparseAt, ".", what, ": ", n, " elements of ", size, " bytes from byteOffset ", offset,
                 " do not fit in ", item("bufferViews", view), " (", bytes.size, " bytes)");
        return bytes.data + offset;
    };
    const unsigned char* indices = range(s.indices.bufferView, s.indices.byteOffset, indexSize, "indices");
    const unsigned char* data = range(s.values.bufferView, s.values.byteOffset, elementSize, "values");
    for (size_t k = 0; k < n; ++k) {
        const double target = readComponent(indices + k * indexSize, indexType, false);
        if (target >= static_cast<double>(a.count))
            fail(sparseAt, ".indices: index ", target, " is out of range (count ", a.count, ")");
        for (size_t c = 0; c < components; ++c)
            values[static_cast<size_t>(target) * components + c] =
                readComponent(data + k * elementSize + c * componentSize, a.componentType, a.normalized);
    }
}

std::vector<Vec3> GltfReader::readVec3(int accessor, const std::string& usedBy) const {
    const std::vector<double> v =
        readAccessor(accessor, usedBy, TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT});
    std::vector<Vec3> out(v.size() / 3);
    for (size_t i = 0; i < out.size(); ++i) out[i] = Vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    return out;
}

const Primitive& GltfReader::primitive(int meshIndex, int index) {
    const auto [it, inserted] = primitives_.try_emplace({meshIndex, index});
    Primitive& out = it->second;
    if (!inserted) return out;
    const tg::Mesh& mesh = model_.meshes[static_cast<size_t>(meshIndex)];
    const tg::Primitive& p = mesh.primitives[static_cast<size_t>(index)];
    out.at = item("meshes", meshIndex) + item(".primitives", index);
    out.name = mesh.name.empty() ? item("meshes", meshIndex) : mesh.name;
    if (mesh.primitives.size() > 1) out.name += concat("#", index);
    if (p.mode < 0 || p.mode > TINYGLTF_MODE_TRIANGLE_FAN)
        fail(out.at, ".mode ", p.mode, " is not a glTF primitive mode (0 to 6)");
    if (p.mode < TINYGLTF_MODE_TRIANGLES) {
        if (pointsAndLines_++ == 0) firstPointsAndLines_ = out.at;
        return out;
    }
    if (p.material != -1) element(model_.materials, p.material, "materials", out.at + ".material");
    out.material = p.material;

    const auto position = p.attributes.find("POSITION");
    if (position == p.attributes.end()) fail(out.at, ".attributes: POSITION is missing");
    out.positions = readVec3(position->second, out.at + ".attributes.POSITION");
    const size_t vertices = out.positions.size();
    auto checkCount = [&](size_t n, const std::string& field) {
        if (n != vertices)
            fail(field, ": ", count(n, "element", "elements"), ", but POSITION has ", vertices);
    };
    for (const auto& [name, accessor] : p.attributes) {
        const std::string field = out.at + ".attributes." + name;
        if (name == "NORMAL") {
            out.normals = readVec3(accessor, field);
            checkCount(out.normals.size(), field);
            for (Vec3& n : out.normals) {
                const double length = glm::length(n);
                if (!(length > 0)) {
                    warn(field, ": zero-length normals; normals computed instead");
                    out.normals.clear();
                    break;
                }
                n /= length;
            }
        } else if (startsWith(name, "TEXCOORD_")) {
            const std::vector<double> uv = readAccessor(
                accessor, field, TINYGLTF_TYPE_VEC2,
                {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                 TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT});
            checkCount(uv.size() / 2, field);
            std::vector<Vec2>& set = out.texcoords[std::atoi(name.c_str() + 9)];
            for (size_t i = 0; i < vertices; ++i) set.emplace_back(uv[2 * i], uv[2 * i + 1]);
        } else if (startsWith(name, "COLOR_")) {
            warnOnce("color", field, ": vertex colours are not supported; ignored");
        } else if (startsWith(name, "JOINTS_") || startsWith(name, "WEIGHTS_")) {
            warnOnce("skin", field, ": skins are not supported; the rest pose is used");
        }
    }
    if (!p.targets.empty()) warnOnce("morph", out.at, ": morph targets are not supported; ignored");

    std::vector<uint32_t> indices;
    if (p.indices >= 0 || p.indices < -1) {
        const std::string field = out.at + ".indices";
        const std::vector<double> raw =
            readAccessor(p.indices, field, TINYGLTF_TYPE_SCALAR,
                         {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                          TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT});
        indices.reserve(raw.size());
        for (size_t k = 0; k < raw.size(); ++k) {
            if (raw[k] >= static_cast<double>(vertices))
                fail(field, " (", item("accessors", p.indices), "): index ", raw[k], " at position ",
                     k, " is out of range (", count(vertices, "vertex", "vertices"), ")");
            indices.push_back(static_cast<uint32_t>(raw[k]));
        }
    } else {
        if (vertices > UINT32_MAX) fail(out.at, ": more than 2^32 vertices");
        indices.resize(vertices);
        for (size_t i = 0; i < vertices; ++i) indices[i] = static_cast<uint32_t>(i);
    }
    out.triangles = assemble(p, out.at, indices);
    return out;
}

// Triangles from a triangle list, strip or fan (glTF 2.0, section 3.7.2.1).
std::vector<glm::uvec3> GltfReader::assemble(const tg::Primitive& p, const std::string& at,
                                             const std::vector<uint32_t>& v) const {
    std::vector<glm::uvec3> out;
    const size_t n = v.size();
    if (p.mode == TINYGLTF_MODE_TRIANGLES) {
        if (n % 3 != 0)
            fail(at, ": ", count(n, "vertex", "vertices"), " for a triangle list, not a multiple of 3");
        for (size_t i = 0; i < n; i += 3) out.emplace_back(v[i], v[i + 1], v[i + 2]);
    } else if (p.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        for (size_t i = 0; i + 2 < n; ++i)
            out.emplace_back(v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]);
    } else {  // fan
        for (size_t i = 0; i + 2 < n; ++i) out.emplace_back(v[i + 1], v[i + 2], v[0]);
    }
    return out;
}

Piece GltfReader::place(const Primitive& prim, const Mat4& world) const {
    Piece piece;
    piece.primitive = &prim;
    piece.positions.reserve(prim.positions.size());
    for (const Vec3& p : prim.positions) piece.positions.push_back(Vec3(world * Vec4(p, 1.0)));
    const Mat3 linear(world);
    const double det = glm::determinant(linear);
    // Under a singular transform the file's normals mean nothing: computed.
    if (!prim.normals.empty() && det != 0 && std::isfinite(det)) {
        const Mat3 normalMatrix = glm::transpose(glm::inverse(linear));
        for (const Vec3& n : prim.normals) piece.normals.push_back(glm::normalize(normalMatrix * n));
    }
    piece.triangles = prim.triangles;
    if (det < 0)  // a mirror turns counter-clockwise into clockwise
        for (glm::uvec3& t : piece.triangles) std::swap(t.y, t.z);
    return piece;
}

// Materials -------------------------------------------------------------------

void GltfReader::chooseMaterials() {
    std::vector<bool> used(model_.materials.size());
    for (const Piece& p : pieces_)
        if (p.primitive->material >= 0) used[p.primitive->material] = true;
    materials_.resize(model_.materials.size());
    for (size_t m = 0; m < used.size(); ++m)
        if (used[m]) materials_[m] = chooseMaterial(static_cast<int>(m));
}

MaterialChoice GltfReader::chooseMaterial(int index) {
    const tg::Material& m = model_.materials[static_cast<size_t>(index)];
    const std::string at = item("materials", index);
    const std::string named = concat(at, " '", m.name, "'");
    MaterialChoice choice;
    choice.material.name = m.name.empty() ? at : m.name;

    const tg::PbrMetallicRoughness& pbr = m.pbrMetallicRoughness;
    const std::string baseAt = at + ".pbrMetallicRoughness";
    if (pbr.baseColorFactor.size() != 4) fail(baseAt, ".baseColorFactor has ", pbr.baseColorFactor.size(), " values, expected 4");
    if (m.emissiveFactor.size() != 3) fail(at, ".emissiveFactor has ", m.emissiveFactor.size(), " values, expected 3");
    for (double v : pbr.baseColorFactor)
        if (!(v >= 0)) fail(baseAt, ".baseColorFactor has a negative value");
    for (double v : m.emissiveFactor)
        if (!(v >= 0)) fail(at, ".emissiveFactor has a negative value");

    // Alpha: MASK cuts away a whole material whose factor is below its
    // cut-off, and per pixel where the base colour texture's alpha takes it
    // below (Material::alphaMap, for shading and shadows); BLEND is opaque.
    const double alpha = pbr.baseColorFactor[3];
    const std::shared_ptr<const Texture> base = texture(pbr.baseColorTexture, baseAt + ".baseColorTexture");
    const double textureAlpha = base ? alpha * base->minAlpha : alpha;
    if (m.alphaMode == "MASK") {
        if (alpha < m.alphaCutoff) {
            choice.dropped = true;
            size_t triangles = 0;
            for (const Piece& p : pieces_)
                if (p.primitive->material == index) triangles += p.triangles.size();
            warn(named, ": baseColorFactor alpha ", alpha, " is below alphaCutoff ", m.alphaCutoff,
                 " (alphaMode MASK): its ", count(triangles, "triangle is", "triangles are"), " removed");
            return choice;
        }
        if (textureAlpha < m.alphaCutoff) {  // only with a texture: alpha >= the cut-off here
            choice.material.alphaMap.image = base;
            choice.material.alphaMap.factor = Rgb(alpha);
            choice.material.alphaCutoff = m.alphaCutoff;
        }
    } else if (m.alphaMode == "BLEND") {
        if (alpha < 1) warn(named, ": alpha blending (alpha ", alpha, ") ignored, rendered opaque");
        else if (textureAlpha < 1) warn(named, ": alpha texture ignored, rendered opaque");
    } else if (m.alphaMode != "OPAQUE") {
        fail(at, ".alphaMode '", m.alphaMode, "' is not OPAQUE, MASK or BLEND");
    }

    Rgb kd = glm::make_vec3(pbr.baseColorFactor.data());
    if (base) {
        choice.material.kdMap.image = base;
        choice.material.kdMap.factor = kd;
        choice.texCoord = pbr.baseColorTexture.texCoord;
        kd *= textureMean(*base, pbr.baseColorTexture.texCoord, index, baseAt + ".baseColorTexture", true);
    }
    choice.material.kd = glm::clamp(kd, Rgb(0.0), Rgb(1.0));
    if (base) warn(named, ": texture ", base->name, " averaged to Kd ", rgbText(choice.material.kd));

    double strength = 1;
    const auto ext = m.extensions.find("KHR_materials_emissive_strength");
    if (ext != m.extensions.end() && ext->second.Has("emissiveStrength")) {
        const tg::Value& v = ext->second.Get("emissiveStrength");
        strength = v.IsNumber() ? v.GetNumberAsDouble() : -1;
        if (!(strength >= 0 && std::isfinite(strength)))
            fail(at, ".extensions.KHR_materials_emissive_strength.emissiveStrength is not a number >= 0");
    }
    Rgb ke = glm::make_vec3(m.emissiveFactor.data()) * strength * options_.emissionScale;
    if (ke != Rgb(0.0)) {
        const std::string emissiveAt = at + ".emissiveTexture";
        if (const std::shared_ptr<const Texture> emissive = texture(m.emissiveTexture, emissiveAt)) {
            if (choice.texCoord >= 0 && choice.texCoord != m.emissiveTexture.texCoord) {
                // One set of coordinates per mesh: the emission shows its mean.
                warn(named, ": emissiveTexture reads TEXCOORD_", m.emissiveTexture.texCoord,
                     ", baseColorTexture TEXCOORD_", choice.texCoord, "; emission shown as its mean Ke");
            } else {
                choice.material.keMap.image = emissive;
                choice.material.keMap.factor = ke;
                choice.texCoord = m.emissiveTexture.texCoord;
            }
            ke *= textureMean(*emissive, m.emissiveTexture.texCoord, index, emissiveAt);
            warn(named, ": texture ", emissive->name, " averaged to Ke ", rgbText(ke));
        }
    }
    choice.material.ke = ke;
    choice.backToo = m.doubleSided && choice.material.emissive();

    std::string ignored;
    auto ignore = [&](const std::string& what) { ignored += (ignored.empty() ? "" : ", ") + what; };
    const bool mirror = chooseSmoothLayer(m, at, choice.material, ignore);
    if (pbr.metallicFactor >= 0.5 && !mirror)
        ignore(concat("metallic ", pbr.metallicFactor, " (roughness ", pbr.roughnessFactor, ")",
                      pbr.metallicRoughnessTexture.index >= 0 ? " (× metallicRoughnessTexture)" : ""));
    if (m.normalTexture.index >= 0) ignore("normalTexture");
    for (const auto& e : m.extensions)
        if (e.first != "KHR_materials_emissive_strength" && e.first != "KHR_materials_transmission" &&
            e.first != "KHR_materials_ior")
            ignore(e.first);
    if (!ignored.empty())
        warn(named, ": ", ignored, " not rendered; rendered as ",
             choice.material.smooth.kind == SpecularKind::Mirror  ? "a mirror"
             : choice.material.smooth.kind == SpecularKind::Glass ? "glass"
                                                                  : "diffuse");
    return choice;
}

// The smooth layer (core/SmoothSpecular.h) of a glTF material, if it has
// one. A metal (metallicFactor 1) of roughness <= kMirrorRoughness is a
// mirror whose F0 is the base colour, rising to 1 at grazing incidence as
// glTF's metals do (Schlick); it scatters nothing diffusely (Kd 0). A
// material with KHR_materials_transmission is glass of index
// KHR_materials_ior (1.5 by default) whose filter is transmissionFactor ×
// base colour; its diffuse part keeps the fraction the transmission leaves,
// Kd × (1 − transmissionFactor), as glTF's mix of the two lobes does. What
// these models cannot show (textures on their factors, rough metals and
// rough glass, ior without transmission) goes to `ignore`. Returns true for
// a mirror.
bool GltfReader::chooseSmoothLayer(const tg::Material& m, const std::string& at, Material& out,
                                   const std::function<void(const std::string&)>& ignore) {
    const tg::PbrMetallicRoughness& pbr = m.pbrMetallicRoughness;
    SmoothSpecular& s = out.smooth;
    const bool metalMap = pbr.metallicRoughnessTexture.index >= 0;
    if (pbr.metallicFactor == 1 && pbr.roughnessFactor <= kMirrorRoughness && !metalMap) {
        s.kind = SpecularKind::Mirror;
        s.schlick = true;
        s.reflectance = out.kd;  // the base colour factor, × its texture's mean when it has one
        out.kd = Rgb(0.0);
        if (out.kdMap) {
            out.kdMap = TextureMap{};
            ignore("baseColorTexture on a mirror (its mean is the reflectance)");
        }
        return true;
    }
    const auto transmission = m.extensions.find("KHR_materials_transmission");
    if (transmission == m.extensions.end()) {
        if (m.extensions.count("KHR_materials_ior")) ignore("KHR_materials_ior without transmission");
        return false;
    }
    const std::string tAt = at + ".extensions.KHR_materials_transmission";
    double factor = 0;  // the extension's default
    if (transmission->second.Has("transmissionFactor")) {
        const tg::Value& v = transmission->second.Get("transmissionFactor");
        factor = v.IsNumber() ? v.GetNumberAsDouble() : -1;
        if (!(factor >= 0 && factor <= 1)) fail(tAt, ".transmissionFactor is not a number in [0, 1]");
    }
    if (transmission->second.Has("transmissionTexture")) ignore("transmissionTexture");
    if (!(factor > 0)) return false;
    s.kind = SpecularKind::Glass;
    s.transmission = factor * out.kd;
    out.kd *= 1.0 - factor;
    if (out.kdMap) {
        out.kdMap.factor *= 1.0 - factor;
        ignore("baseColorTexture on transmission (its mean filters it)");
    }
    if (pbr.roughnessFactor > kMirrorRoughness || metalMap)
        ignore(concat("roughness ", pbr.roughnessFactor, metalMap ? " (× metallicRoughnessTexture)" : "",
                      " of transmission (smooth glass)"));
    const auto ior = m.extensions.find("KHR_materials_ior");
    if (ior != m.extensions.end() && ior->second.Has("ior")) {
        const tg::Value& v = ior->second.Get("ior");
        s.ior = v.IsNumber() ? v.GetNumberAsDouble() : -1;
        if (!(s.ior > 0 && std::isfinite(s.ior)))
            fail(at, ".extensions.KHR_materials_ior.ior is not a positive number");
    }
    return false;
}

// The texture a material refers to, decoded once; null when there is none.
std::shared_ptr<const Texture> GltfReader::texture(const tg::TextureInfo& info, const std::string& field) {
    if (info.index == -1) return nullptr;
    const tg::Texture& t = element(model_.textures, info.index, "textures", field + ".index");
    auto [it, inserted] = textures_.try_emplace(info.index);
    if (!inserted) return it->second;
    const std::string at = item("textures", info.index);
    if (t.source == -1) {
        warn(at, ": no PNG or JPEG source; ignored");
        return nullptr;
    }
    const tg::Image& image = element(model_.images, t.source, "images", at + ".source");
    const std::string imageAt = item("images", t.source);
    auto tex = std::make_shared<Texture>();
    tex->name = !image.name.empty() ? image.name : !image.uri.empty() && !tg::IsDataURI(image.uri) ? image.uri : imageAt;

    std::vector<unsigned char> file;
    const unsigned char* bytes = nullptr;
    size_t size = 0;
    if (image.bufferView >= 0) {
        const ByteRange range = viewBytes(image.bufferView, imageAt + ".bufferView");
        bytes = range.data, size = range.size;
    } else if (const auto e = encodedImages_.find(t.source); e != encodedImages_.end()) {
        bytes = e->second.data(), size = e->second.size();
    } else {
        const fs::path path = requireFile(imageAt + ".uri", image.uri);
        std::string error;
        if (!tg::ReadWholeFile(&file, &error, path.string(), nullptr))
            fail(imageAt, ".uri: cannot read '", image.uri, "': ", error);
        bytes = file.data(), size = file.size();
    }
    const std::string reason = decodeTexture(bytes, size, *tex);
    if (!reason.empty())
        fail(imageAt, tex->name == imageAt ? "" : " ('" + tex->name + "')", ": cannot decode: ", reason);

    if (t.sampler != -1) {
        const tg::Sampler& s = element(model_.samplers, t.sampler, "samplers", at + ".sampler");
        const std::string samplerAt = item("samplers", t.sampler);
        for (const auto& [mode, name] : {std::pair{s.wrapS, "wrapS"}, std::pair{s.wrapT, "wrapT"}})
            if (mode != TINYGLTF_TEXTURE_WRAP_REPEAT && mode != TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE &&
                mode != TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT)
                fail(samplerAt, ".", name, " ", mode, " is not a glTF wrap mode");
        tex->wrapS = wrapMode(s.wrapS);
        tex->wrapT = wrapMode(s.wrapT);
        tex->nearest = s.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
    }
    it->second = std::move(tex);
    return it->second;
}

// The texture's area-weighted mean over the triangles that use `material`;
// with `perTriangle`, each triangle's own mean is kept in footprints_.
Rgb GltfReader::textureMean(const Texture& tex, int texCoord, int material, const std::string& field,
                            bool perTriangle) {
    TextureMean mean(tex);
    footprints_.resize(pieces_.size());
    for (size_t pi = 0; pi < pieces_.size(); ++pi) {
        const Piece& piece = pieces_[pi];
        if (piece.primitive->material != material) continue;
        const auto set = piece.primitive->texcoords.find(texCoord);
        if (set == piece.primitive->texcoords.end()) {
            warnOnce(concat(field, piece.primitive->at), field, ": ", piece.primitive->at,
                     " has no TEXCOORD_", texCoord, "; its triangles are left out of the texture's mean");
            continue;
        }
        const std::vector<Vec2>& uv = set->second;
        for (const glm::uvec3& t : piece.triangles) {
            const Rgb value = footprintMean(tex, {uv[t.x], uv[t.y], uv[t.z]});
            mean.addValue(0.5 * glm::length(glm::cross(piece.positions[t.y] - piece.positions[t.x],
                                                       piece.positions[t.z] - piece.positions[t.x])),
                          value);
            if (perTriangle) footprints_[pi].push_back(value);
        }
    }
    return mean.mean();
}

uint32_t GltfReader::sceneMaterial(int gltfMaterial) {
    int& index = gltfMaterial < 0 ? defaultMaterial_ : materials_[gltfMaterial].sceneIndex;
    if (index < 0) {
        index = static_cast<int>(scene_.materials.size());
        if (gltfMaterial < 0) {
            Material m;  // Kd 0.8, not emissive
            m.name = "default";
            scene_.materials.push_back(m);
        } else {
            scene_.materials.push_back(materials_[gltfMaterial].material);
        }
    }
    return static_cast<uint32_t>(index);
}

// Meshes ------------------------------------------------------------------------

void GltfReader::buildMeshes() {
    size_t read = 0, masked = 0;
    for (size_t pi = 0; pi < pieces_.size(); ++pi) {
        const Piece& piece = pieces_[pi];
        const Primitive& prim = *piece.primitive;
        read += piece.triangles.size();
        if (prim.material >= 0 && materials_[prim.material].dropped) {
            masked += piece.triangles.size();
            continue;
        }
        Mesh mesh;
        mesh.name = prim.name;
        mesh.positions = piece.positions;
        mesh.normals = piece.normals;
        mesh.triangles = piece.triangles;
        mesh.materials.assign(mesh.triangles.size(), sceneMaterial(prim.material));
        mesh.sourceLines.assign(mesh.triangles.size(), 0);
        if (prim.material >= 0 && materials_[prim.material].texCoord >= 0) {
            const MaterialChoice& choice = materials_[prim.material];
            const auto set = prim.texcoords.find(choice.texCoord);
            if (set != prim.texcoords.end()) mesh.texcoords = set->second;
            if (pi < footprints_.size() && !footprints_[pi].empty())
                for (const Rgb& f : footprints_[pi])
                    mesh.albedo.push_back(glm::clamp(choice.material.kdMap.factor * f, Rgb(0.0), Rgb(1.0)));
        }
        const size_t dropped = removeDegenerateTriangles(mesh, kDegenerateRelTol);
        if (dropped > 0 && degenerate_ == 0) firstDegenerate_ = prim.at;
        degenerate_ += dropped;
        if (mesh.triangles.empty()) continue;
        if (mesh.normals.empty()) computeShadingNormals(mesh, options_.creaseAngleDegrees);
        else compactVertices(mesh);
        scene_.meshes.push_back(std::move(mesh));
        if (prim.material >= 0 && materials_[prim.material].backToo) addBackFaces(scene_.meshes.back());
    }
    if (degenerate_ > 0)
        warn("dropped ", count(degenerate_, "degenerate triangle", "degenerate triangles"), " (first in ",
             firstDegenerate_, ")");
    if (read == 0) fail("no triangles in the scene's nodes");
    if (scene_.meshes.empty())
        fail("none of the scene's ", count(read, "triangle", "triangles"), " is left (", degenerate_,
             " degenerate, ", masked, " removed by alphaMode MASK)");
}

// A doubleSided emitter's triangles reversed, with reversed normals: a mesh
// of their own, so that front and back form separate planar lights.
void GltfReader::addBackFaces(const Mesh& front) {
    // Copied before the push_back, which may move `front`.
    Mesh back;
    back.name = front.name + " (back)";
    back.positions = front.positions;
    for (const Vec3& n : front.normals) back.normals.push_back(-n);
    back.texcoords = front.texcoords;
    back.albedo = front.albedo;
    for (const glm::uvec3& t : front.triangles) back.triangles.emplace_back(t.x, t.z, t.y);
    back.materials = front.materials;
    back.sourceLines = front.sourceLines;
    scene_.meshes.push_back(std::move(back));
}

}  // namespace

Scene loadGltf(const std::string& path, const GltfOptions& options) {
    return GltfReader(path, options).read();
}

Scene loadGltfFromMemory(const std::string& name, const std::vector<unsigned char>& bytes,
                         const GltfOptions& options) {
    return GltfReader(name, options, &bytes).read();
}

}  // namespace ml
