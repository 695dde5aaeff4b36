// A small OBJ/MTL parser of our own. OpenMesh's OBJ reader (already a
// dependency) was not used: it cannot say at which file:line a face or number
// is wrong, and it does not keep a material per face, both of which the
// renderer needs (errors users can act on; one material per triangle).
#include "ObjLoader.h"

#include "core/Error.h"
#include "core/MeshUtil.h"
#include "TextureMean.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string_view>
#include <unordered_map>

namespace ml {

namespace {

namespace fs = std::filesystem;
using std::string_view;

// Triangles with an area <= (1e-6 · mesh diagonal)² are dropped as degenerate.
constexpr double kDegenerateRelTol = 1e-6;

// One statement: its keyword, the arguments split at blanks, and the raw text
// after the keyword (names may contain blanks). Comments are removed.
struct Statement {
    string_view keyword;
    std::vector<string_view> args;
    string_view rest;
};

bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

string_view trim(string_view s) {
    while (!s.empty() && isBlank(s.front())) s.remove_prefix(1);
    while (!s.empty() && isBlank(s.back())) s.remove_suffix(1);
    return s;
}

// Splits a line into `out`; returns false for a blank or comment-only line.
bool splitStatement(string_view line, Statement& out) {
    line = trim(line.substr(0, line.find('#')));
    if (line.empty()) return false;
    out.args.clear();
    size_t i = 0;
    while (i < line.size() && !isBlank(line[i])) ++i;
    out.keyword = line.substr(0, i);
    out.rest = trim(line.substr(i));
    while (i < line.size()) {
        while (i < line.size() && isBlank(line[i])) ++i;
        const size_t start = i;
        while (i < line.size() && !isBlank(line[i])) ++i;
        if (i > start) out.args.push_back(line.substr(start, i - start));
    }
    return true;
}

// The file's lines with their 1-based numbers; LF or CRLF endings, and a
// UTF-8 byte order mark (written by some Windows exporters) skipped.
class LineReader {
public:
    explicit LineReader(std::string text) : text_(std::move(text)) {
        if (text_.compare(0, 3, "\xEF\xBB\xBF") == 0) pos_ = 3;
    }
    bool next(string_view& line) {
        if (pos_ >= text_.size()) return false;
        size_t end = text_.find('\n', pos_);
        if (end == std::string::npos) end = text_.size();
        line = string_view(text_).substr(pos_, end - pos_);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        pos_ = end + 1;
        ++line_;
        return true;
    }
    int line() const { return line_; }

private:
    std::string text_;
    size_t pos_ = 0;
    int line_ = 0;
};

// Reads a whole file; returns false when it cannot be opened.
bool readFile(const fs::path& path, std::string& text) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return false;
    std::ifstream in(path, std::ios::binary);
    if (!in) return false;
    std::ostringstream ss;
    ss << in.rdbuf();
    text = ss.str();
    return true;
}

// Parses a whole token as a finite number; `what` names it in errors
// ("coordinate 'nan' is not a finite number").
double parseNumber(string_view token, const SourceLocation& at, const char* what) {
    const char* first = token.data();
    const char* last = first + token.size();
    if (first != last && *first == '+') ++first;  // from_chars rejects '+'; some exporters write it
    double value = 0;
    const auto [end, ec] = std::from_chars(first, last, value);
    if (ec == std::errc::result_out_of_range)
        throwInputError(at, what, " '", token, "' is out of the range of a double");
    if (ec != std::errc() || end != last || first == last)
        throwInputError(at, what, " '", token, "' is not a number");
    if (!std::isfinite(value)) throwInputError(at, what, " '", token, "' is not a finite number");
    return value;
}

// Returns false unless the whole token is an integer.
bool parseInteger(string_view token, long long& value) {
    const char* last = token.data() + token.size();
    const auto [end, ec] = std::from_chars(token.data(), last, value);
    return ec == std::errc() && end == last && !token.empty();
}

// "1 vertex", "3 vertices"
std::string count(size_t n, const char* singular, const char* plural) {
    return concat(n, " ", n == 1 ? singular : plural);
}

// "the only triangle is degenerate", "all its 3 triangles are degenerate"
std::string allDegenerate(size_t n, const char* determiner) {
    return n == 1 ? concat(determiner, " only triangle is degenerate")
                  : concat("all ", determiner, " ", n, " triangles are degenerate");
}

// The textures whose means multiply a constant (map_Kd, map_Ke) or cut
// triangles out (map_d).
bool isAveragedTexture(string_view kw) { return kw == "map_Kd" || kw == "map_Ke" || kw == "map_d"; }

// Statements whose value could come from an image; those that are not
// isAveragedTexture are warned about and their constant is used.
bool isTextureStatement(string_view kw) {
    return kw.substr(0, 4) == "map_" || kw == "bump" || kw == "disp" || kw == "decal" ||
           kw == "refl" || kw == "norm";
}

bool isMaterialStatement(string_view kw) {
    return isTextureStatement(kw) || kw == "Kd" || kw == "Ks" || kw == "Ke" || kw == "Ns" ||
           kw == "Ka" || kw == "Ni" || kw == "Tf" || kw == "d" || kw == "Tr" || kw == "illum";
}

// MTL texture options (the MTL specification's), with how many values each
// takes: numbers for the numeric ones, else one word ("on", "m").
struct TextureOption {
    string_view name;
    size_t maxValues;
    bool numeric;
};
constexpr TextureOption kTextureOptions[] = {
    {"-blendu", 1, false}, {"-blendv", 1, false}, {"-bm", 1, true},    {"-boost", 1, true},
    {"-cc", 1, false},     {"-clamp", 1, false},  {"-imfchan", 1, false}, {"-mm", 2, true},
    {"-o", 3, true},       {"-s", 3, true},       {"-t", 3, true},     {"-texres", 1, true},
    {"-type", 1, false},
};

// map_d: the surface is cut out where its coverage is below this (per pixel
// on faces with vt; a face without vt by the image's mean coverage).
constexpr double kCutOutCoverage = 0.5;

// Returns false unless the whole token is a finite number.
bool isNumber(string_view token) {
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);
    double value = 0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    return ec == std::errc() && end == token.data() + token.size() && !token.empty() && std::isfinite(value);
}

// Names an index kind in errors: "vertex index 9 is out of range (4 vertices ...)".
struct IndexKind {
    const char* singular;
    const char* plural;
};
constexpr IndexKind kVertexIndex{"vertex", "vertices"};
constexpr IndexKind kTexcoordIndex{"texture coordinate", "texture coordinates"};
constexpr IndexKind kNormalIndex{"normal", "normals"};

// Warnings that would repeat on many lines (an unknown statement, vertex
// colours) become one per file and kind: the first line and a count.
class RepeatedWarnings {
public:
    void add(const std::string& message, int line) {
        ++seen_.try_emplace(message, Seen{line, 0}).first->second.count;
    }
    void flushInto(const std::string& file, std::vector<std::string>& warnings) {
        std::vector<std::pair<int, std::string>> ordered;
        for (const auto& [message, s] : seen_)
            ordered.emplace_back(s.firstLine,
                                 s.count > 1 ? concat(message, " (", s.count, " lines)") : message);
        std::sort(ordered.begin(), ordered.end());
        for (const auto& [line, text] : ordered)
            warnings.push_back(SourceLocation{file, line}.str() + ": " + text);
        seen_.clear();
    }

private:
    struct Seen {
        int firstLine;
        size_t count;
    };
    std::map<std::string, Seen> seen_;
};

// A triangle as read: global OBJ indices (0-based), -1 for a missing normal
// or texture coordinate.
struct RawTriangle {
    std::array<uint32_t, 3> position;
    std::array<int32_t, 3> normal;
    std::array<int32_t, 3> texcoord;
    uint32_t material;  // index into Scene::materials
    int line;
    bool cutOut = false;  // removed by its material's map_d
    std::optional<Rgb> albedo;  // map_Kd's mean over its footprint × Kd, when textured with vt

    bool hasTexcoords() const { return texcoord[0] >= 0 && texcoord[1] >= 0 && texcoord[2] >= 0; }
};

struct Group {
    std::string name;
    std::vector<RawTriangle> triangles;
};

// A map_Kd, map_Ke or map_d statement: the image and the options honoured.
struct TextureStatement {
    std::string keyword;  // "map_Kd"
    std::string file;     // as written
    std::string path;     // relative to the MTL's folder, lexically normalised
    SourceLocation at;
    Vec2 scale{1.0};      // -s u v
    Vec2 offset{0.0};     // -o u v
    bool clamp = false;   // -clamp on

    // "map_Kd 'wood.png'", for messages.
    std::string named() const { return concat(keyword, " '", file, "'"); }
    // Where an OBJ texture coordinate reads the image: scaled, offset, and
    // with v turned down (an OBJ vt has v up; images are stored top row first).
    Vec2 lookup(const Vec2& vt) const {
        const Vec2 p = vt * scale + offset;
        return {p.x, 1 - p.y};
    }
    // The same as a TextureMap of Mesh::texcoords, which hold (u, 1 − v):
    // lookup(vt) = texcoord·(sx, sy) + (ox, 1 − sy − oy).
    TextureMap map(std::shared_ptr<const Texture> image, const Rgb& factor) const {
        TextureMap m;
        m.image = std::move(image);
        m.factor = factor;
        m.scale = scale;
        m.offset = Vec2(offset.x, 1 - scale.y - offset.y);
        return m;
    }
};

struct LibraryMaterial {
    Material material;
    SourceLocation definedAt;
    // The illum model and where it was given: resolved once the whole
    // material is read (finishMaterial), since Ks, Ni and Tf may follow it.
    long long illum = 2;
    SourceLocation illumAt;
    int sceneIndex = -1;  // set when a face first uses it
    std::optional<TextureStatement> mapKd, mapKe, mapD;
};

class ObjParser {
public:
    ObjParser(const std::string& path, const ObjOptions& options, const ObjFileReader& read)
        : path_(path), options_(options), read_(read) {}

    Scene parse();

private:
    void readStatements();
    void assembleMeshes();

    // OBJ statements
    void parseVertex(const Statement& st, const SourceLocation& at);
    void parseNormal(const Statement& st, const SourceLocation& at);
    void parseTexcoord(const Statement& st, const SourceLocation& at);
    void parseFace(const Statement& st, const SourceLocation& at);
    uint32_t resolveIndex(string_view token, size_t defined, const IndexKind& kind,
                          const SourceLocation& at) const;
    void startGroup(string_view name);
    void useMaterial(string_view name, const SourceLocation& at);
    uint32_t currentMaterial();

    // MTL
    void loadMaterialLibrary(string_view name, const SourceLocation& at);
    void parseMaterialStatement(const Statement& st, const SourceLocation& at, LibraryMaterial& lm);
    void finishMaterial(LibraryMaterial& lm);
    void parseAveragedTexture(const Statement& st, const SourceLocation& at, LibraryMaterial& m,
                              RepeatedWarnings& repeated);

    // Textures
    void applyTextures();
    std::shared_ptr<const Texture> loadTexture(const TextureStatement& statement);
    void cutOut(const TextureStatement& statement, const std::vector<RawTriangle*>& triangles);
    Rgb textureMean(const TextureStatement& statement, const std::vector<RawTriangle*>& triangles,
                    const Rgb* albedoFactor = nullptr);
    double worldArea(const RawTriangle& t) const;
    std::array<Vec2, 3> lookups(const TextureStatement& statement, const RawTriangle& t) const;
    void warnWithoutUv(const TextureStatement& statement, size_t triangles);

    // Assembly
    Mesh buildMesh(const Group& group);

    std::string path_;
    ObjOptions options_;
    const ObjFileReader& read_;
    Scene scene_;
    RepeatedWarnings repeated_;

    std::vector<Vec3> positions_;
    std::vector<Vec3> normals_;   // unit, or zero when the file's vn has zero length
    std::vector<int> normalLines_;
    std::vector<Vec2> texcoords_;  // u, v (v up, as the file gives it)

    std::vector<Group> groups_;
    std::unordered_map<std::string, size_t> groupIndex_;
    size_t currentGroup_ = 0;

    std::map<std::string, LibraryMaterial> library_;
    std::vector<std::string> libraryFiles_;
    std::map<std::string, std::shared_ptr<const Texture>> textures_;  // by path, and "(clamp)" when clamped
    std::vector<bool> drawsTexture_;  // per scene material: a map_Kd or map_Ke drawn per pixel
    LibraryMaterial* currentLibraryMaterial_ = nullptr;  // null: no usemtl yet
    int defaultMaterial_ = -1;

    size_t nonConvexPolygons_ = 0;
    int firstNonConvexLine_ = 0;
    size_t degenerateTriangles_ = 0;
    size_t cutOutTriangles_ = 0;
    int firstDegenerateLine_ = 0;

    // Reused across faces to avoid an allocation per line.
    std::vector<uint32_t> facePositions_;
    std::vector<int32_t> faceNormals_;
    std::vector<int32_t> faceTexcoords_;
    std::vector<Vec3> fanNormals_;
};

Scene ObjParser::parse() {
    if (!(options_.creaseAngleDegrees >= 0 && options_.creaseAngleDegrees <= 180))
        throw InputError(concat("crease angle ", options_.creaseAngleDegrees,
                                " degrees is not in [0, 180]"));
    scene_.name = path_;
    readStatements();
    applyTextures();
    assembleMeshes();
    scene_.finalize();
    return std::move(scene_);
}

void ObjParser::readStatements() {
    std::string text;
    if (!read_(path_, text)) throwInputError(SourceLocation{path_}, "cannot open OBJ file");
    startGroup(fs::path(path_).stem().string());
    LineReader reader(std::move(text));
    string_view line;
    Statement st;
    while (reader.next(line)) {
        if (!splitStatement(line, st)) continue;
        const SourceLocation at{path_, reader.line()};
        const string_view kw = st.keyword;
        if (kw == "v") parseVertex(st, at);
        else if (kw == "vn") parseNormal(st, at);
        else if (kw == "vt") parseTexcoord(st, at);
        else if (kw == "f") parseFace(st, at);
        else if (kw == "o" || kw == "g") startGroup(st.rest);
        else if (kw == "usemtl") useMaterial(st.rest, at);
        else if (kw == "mtllib")
            for (string_view file : st.args) loadMaterialLibrary(file, at);
        else if (kw == "s") continue;  // smoothing groups: the crease angle decides instead
        else repeated_.add(concat("unknown statement '", kw, "' ignored"), at.line);
    }
    repeated_.flushInto(path_, scene_.warnings);
    if (nonConvexPolygons_ > 0)
        scene_.warnings.push_back(concat(
            path_, ": ", count(nonConvexPolygons_, "polygon is", "polygons are"),
            " not convex as seen from the first corner, so the fan triangulation overlaps",
            " (first at line ", firstNonConvexLine_, ")"));
}

// Meshes from the groups: degenerate triangles dropped, normals completed.
void ObjParser::assembleMeshes() {
    size_t faceTriangles = 0;
    for (const Group& g : groups_) faceTriangles += g.triangles.size();
    if (faceTriangles == 0)
        throwInputError(SourceLocation{path_}, cutOutTriangles_ > 0
                                                   ? concat("map_d cuts out every triangle (",
                                                            cutOutTriangles_, ")")
                                                   : std::string("no faces (f statements) found"));

    std::vector<size_t> trianglesPerMaterial(scene_.materials.size(), 0);
    std::vector<int> firstLinePerMaterial(scene_.materials.size(), 0);
    for (const Group& g : groups_)
        for (const RawTriangle& t : g.triangles)
            if (trianglesPerMaterial[t.material]++ == 0) firstLinePerMaterial[t.material] = t.line;

    for (const Group& g : groups_) {
        if (g.triangles.empty()) continue;
        Mesh mesh = buildMesh(g);
        if (!mesh.triangles.empty()) scene_.meshes.push_back(std::move(mesh));
    }
    if (degenerateTriangles_ > 0)
        scene_.warnings.push_back(concat(path_, ": dropped ",
                                         count(degenerateTriangles_, "degenerate triangle",
                                               "degenerate triangles"),
                                         " (first at line ", firstDegenerateLine_, ")"));

    // A light whose every triangle was dropped would vanish without a word.
    std::vector<size_t> keptPerMaterial(scene_.materials.size(), 0);
    for (const Mesh& m : scene_.meshes)
        for (uint32_t mat : m.materials) ++keptPerMaterial[mat];
    for (size_t mat = 0; mat < scene_.materials.size(); ++mat)
        if (scene_.materials[mat].emissive() && trianglesPerMaterial[mat] > 0 &&
            keptPerMaterial[mat] == 0)
            throwInputError(SourceLocation{path_, firstLinePerMaterial[mat]}, "light '",
                            scene_.materials[mat].name, "' has zero area: ",
                            allDegenerate(trianglesPerMaterial[mat], "its"));
    if (scene_.meshes.empty())
        throwInputError(SourceLocation{path_}, allDegenerate(faceTriangles, "the"));
}

// OBJ statements ------------------------------------------------------------

void ObjParser::parseVertex(const Statement& st, const SourceLocation& at) {
    const size_t n = st.args.size();
    if (n != 3 && n != 4 && n != 6)
        throwInputError(at, "v has ", count(n, "value", "values"),
                        ", expected 3 or 4 (x y z [w]) or 6 (x y z r g b)");
    double xyz[3];
    for (size_t k = 0; k < n; ++k) {
        const double value = parseNumber(st.args[k], at, "coordinate");
        if (k < 3) xyz[k] = value;
    }
    if (n == 6) repeated_.add("vertex colours are not supported; ignored", at.line);
    positions_.emplace_back(xyz[0], xyz[1], xyz[2]);
}

void ObjParser::parseNormal(const Statement& st, const SourceLocation& at) {
    if (st.args.size() != 3)
        throwInputError(at, "vn has ", count(st.args.size(), "value", "values"), ", expected 3");
    const Vec3 n(parseNumber(st.args[0], at, "normal coordinate"),
                 parseNumber(st.args[1], at, "normal coordinate"),
                 parseNumber(st.args[2], at, "normal coordinate"));
    // Scaled by its largest component first: that neither overflows for huge
    // components nor loses digits for subnormal ones (whose length has only
    // a few significant bits), so only a true zero fails.
    const double largest = std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
    normals_.push_back(largest > 0 ? glm::normalize(n / largest) : Vec3(0.0));
    normalLines_.push_back(at.line);
}

void ObjParser::parseTexcoord(const Statement& st, const SourceLocation& at) {
    if (st.args.empty() || st.args.size() > 3)
        throwInputError(at, "vt has ", count(st.args.size(), "value", "values"),
                        ", expected 1 to 3");
    Vec2 uv(0.0);  // w, the third value, is for 3D textures
    for (size_t k = 0; k < st.args.size(); ++k) {
        const double value = parseNumber(st.args[k], at, "texture coordinate");
        if (k < 2) uv[static_cast<int>(k)] = value;
    }
    texcoords_.push_back(uv);
}

uint32_t ObjParser::resolveIndex(string_view token, size_t defined, const IndexKind& kind,
                                 const SourceLocation& at) const {
    long long i = 0;
    if (!parseInteger(token, i))
        throwInputError(at, kind.singular, " index '", token, "' is not an integer");
    if (i == 0) throwInputError(at, kind.singular, " index 0 is invalid (OBJ indices start at 1)");
    // Negative indices count back from the last one defined so far (-1 = last).
    const long long resolved = i > 0 ? i - 1 : static_cast<long long>(defined) + i;
    if (resolved < 0 || resolved >= static_cast<long long>(defined))
        throwInputError(at, kind.singular, " index ", i, " is out of range (",
                        count(defined, kind.singular, kind.plural), " defined so far)");
    return static_cast<uint32_t>(resolved);
}

void ObjParser::parseFace(const Statement& st, const SourceLocation& at) {
    if (st.args.size() < 3)
        throwInputError(at, "face has ", count(st.args.size(), "vertex", "vertices"),
                        ", expected at least 3");
    facePositions_.clear();
    faceNormals_.clear();
    faceTexcoords_.clear();
    for (string_view corner : st.args) {
        // v, v/vt, v//vn or v/vt/vn
        std::array<string_view, 3> parts;
        size_t partCount = 0;
        for (size_t start = 0;;) {
            const size_t slash = corner.find('/', start);
            if (partCount == parts.size())
                throwInputError(at, "face vertex '", corner,
                                "' is malformed (expected v, v/vt, v//vn or v/vt/vn)");
            parts[partCount++] =
                corner.substr(start, slash == string_view::npos ? slash : slash - start);
            if (slash == string_view::npos) break;
            start = slash + 1;
        }
        if (parts[0].empty() || (partCount == 3 && parts[2].empty()))
            throwInputError(at, "face vertex '", corner,
                            "' is malformed (expected v, v/vt, v//vn or v/vt/vn)");
        facePositions_.push_back(resolveIndex(parts[0], positions_.size(), kVertexIndex, at));
        faceTexcoords_.push_back(
            partCount >= 2 && !parts[1].empty()
                ? static_cast<int32_t>(resolveIndex(parts[1], texcoords_.size(), kTexcoordIndex, at))
                : -1);
        int32_t normal = -1;
        if (partCount == 3) {
            normal =
                static_cast<int32_t>(resolveIndex(parts[2], normals_.size(), kNormalIndex, at));
            if (normals_[normal] == Vec3(0.0))
                throwInputError(at, "normal ", normal + 1, " (line ", normalLines_[normal],
                                ") has zero length");
        }
        faceNormals_.push_back(normal);
    }

    // A fan from corner 0 is right for convex polygons (and any polygon whose
    // corners all see corner 0); otherwise some fan triangle faces against
    // the polygon's vector area, which is the sum of the fan triangles' (taken
    // relative to corner 0 for precision far from the origin).
    const size_t n = facePositions_.size();
    const Vec3& p0 = positions_[facePositions_[0]];
    fanNormals_.clear();
    Vec3 polygonNormal(0.0);
    for (size_t k = 1; k + 1 < n; ++k) {
        fanNormals_.push_back(glm::cross(positions_[facePositions_[k]] - p0,
                                         positions_[facePositions_[k + 1]] - p0));
        polygonNormal += fanNormals_.back();
    }
    bool overlaps = false;
    const uint32_t material = currentMaterial();
    Group& group = groups_[currentGroup_];
    for (size_t k = 1; k + 1 < n; ++k) {
        RawTriangle t;
        t.position = {facePositions_[0], facePositions_[k], facePositions_[k + 1]};
        t.normal = {faceNormals_[0], faceNormals_[k], faceNormals_[k + 1]};
        t.texcoord = {faceTexcoords_[0], faceTexcoords_[k], faceTexcoords_[k + 1]};
        t.material = material;
        t.line = at.line;
        group.triangles.push_back(t);
        // Rounding may tip a collinear (degenerate) fan triangle either way.
        if (glm::dot(fanNormals_[k - 1], polygonNormal) <
            -1e-12 * glm::dot(polygonNormal, polygonNormal))
            overlaps = true;
    }
    if (overlaps && nonConvexPolygons_++ == 0) firstNonConvexLine_ = at.line;
}

void ObjParser::startGroup(string_view name) {
    std::string key(name.empty() ? fs::path(path_).stem().string() : std::string(name));
    auto [it, inserted] = groupIndex_.try_emplace(key, groups_.size());
    if (inserted) groups_.push_back(Group{key, {}});
    currentGroup_ = it->second;
}

void ObjParser::useMaterial(string_view name, const SourceLocation& at) {
    if (name.empty()) throwInputError(at, "usemtl without a material name");
    const auto it = library_.find(std::string(name));
    if (it == library_.end()) {
        std::string read;
        for (const std::string& f : libraryFiles_) read += (read.empty() ? "" : ", ") + f;
        throwInputError(at, "usemtl '", name, "': unknown material (",
                        read.empty() ? "no mtllib before this line"
                                     : "material libraries read: " + read,
                        ")");
    }
    currentLibraryMaterial_ = &it->second;
}

uint32_t ObjParser::currentMaterial() {
    if (!currentLibraryMaterial_) {
        if (defaultMaterial_ < 0) {
            defaultMaterial_ = static_cast<int>(scene_.materials.size());
            Material m;  // Kd 0.8, not emissive
            m.name = "default";
            scene_.materials.push_back(m);
        }
        return static_cast<uint32_t>(defaultMaterial_);
    }
    // Only materials that faces use enter the scene. library_ is a std::map,
    // so the pointer stays valid while later libraries are added.
    LibraryMaterial& lm = *currentLibraryMaterial_;
    if (lm.sceneIndex < 0) {
        lm.sceneIndex = static_cast<int>(scene_.materials.size());
        scene_.materials.push_back(lm.material);
    }
    return static_cast<uint32_t>(lm.sceneIndex);
}

// MTL -------------------------------------------------------------------------

void ObjParser::loadMaterialLibrary(string_view name, const SourceLocation& at) {
    fs::path file{std::string(name)};
    if (file.is_relative()) file = fs::path(path_).parent_path() / file;
    const std::string mtlPath = file.lexically_normal().string();
    if (std::find(libraryFiles_.begin(), libraryFiles_.end(), mtlPath) != libraryFiles_.end())
        return;
    std::string text;
    if (!read_(mtlPath, text))
        throwInputError(at, "cannot open material library '", name, "' (", mtlPath, ")");
    libraryFiles_.push_back(mtlPath);

    RepeatedWarnings repeated;
    LibraryMaterial* current = nullptr;
    LibraryMaterial redefinition;  // parsed (so it is checked) but not used
    LineReader reader(std::move(text));
    string_view line;
    Statement st;
    while (reader.next(line)) {
        if (!splitStatement(line, st)) continue;
        const SourceLocation where{mtlPath, reader.line()};
        const string_view kw = st.keyword;
        if (kw == "newmtl") {
            if (st.rest.empty()) throwInputError(where, "newmtl without a name");
            if (current) finishMaterial(*current);
            const std::string matName(st.rest);
            auto [it, inserted] = library_.try_emplace(matName);
            if (inserted) {
                current = &it->second;
            } else {
                scene_.warnings.push_back(concat(where.str(), ": material '", matName,
                                                 "' is defined again; the definition at ",
                                                 it->second.definedAt.str(), " is used"));
                redefinition = LibraryMaterial{};
                current = &redefinition;
            }
            current->material.name = matName;
            current->definedAt = where;
        } else if (!isMaterialStatement(kw)) {
            repeated.add(concat("unknown statement '", kw, "' ignored"), where.line);
        } else if (!current) {
            throwInputError(where, kw, " before any newmtl");
        } else if (isAveragedTexture(kw)) {
            parseAveragedTexture(st, where, *current, repeated);
        } else {
            parseMaterialStatement(st, where, *current);
        }
    }
    if (current) finishMaterial(*current);
    repeated.flushInto(mtlPath, scene_.warnings);
}

void ObjParser::parseMaterialStatement(const Statement& st, const SourceLocation& at, LibraryMaterial& lm) {
    Material& m = lm.material;
    const string_view kw = st.keyword;
    const std::string valueName = concat(kw, " value");
    if (isTextureStatement(kw)) {
        // Options such as "-s 1 1 1" come first; the file name is last.
        const string_view file = st.args.empty() ? string_view() : st.args.back();
        static const char* const constants[] = {"Kd", "Ks", "Ke", "Ka", "Ns", "d"};
        const string_view suffix = kw.substr(0, 4) == "map_" ? kw.substr(4) : string_view();
        const bool hasConstant = std::any_of(std::begin(constants), std::end(constants),
                                             [&](const char* c) { return suffix == c; });
        scene_.warnings.push_back(concat(at.str(), ": texture ", kw, " '", file,
                                         "' is not supported yet; ",
                                         hasConstant ? concat("using ", suffix) : "ignored"));
        return;
    }
    if (kw == "Tf" && !st.args.empty() && (st.args[0] == "xyz" || st.args[0] == "spectral")) {
        scene_.warnings.push_back(concat(at.str(), ": Tf ", st.args[0],
                                         " is not supported (only RGB); transmission filter 1 1 1 used"));
        return;
    }
    if (kw == "Kd" || kw == "Ks" || kw == "Ke" || kw == "Ka" || kw == "Tf") {
        const size_t n = st.args.size();
        if (n != 1 && n != 3)
            throwInputError(at, kw, " has ", count(n, "value", "values"), ", expected 1 or 3");
        Rgb c;
        for (int k = 0; k < 3; ++k)
            c[k] = parseNumber(st.args[n == 1 ? 0 : k], at, valueName.c_str());
        if (kw == "Ka") return;  // ambient: global illumination computes it
        if (c.r < 0 || c.g < 0 || c.b < 0)
            throwInputError(at, kw, " ", c.r, " ", c.g, " ", c.b, " has a negative value");
        if (kw != "Ke" && (c.r > 1 || c.g > 1 || c.b > 1)) {
            scene_.warnings.push_back(concat(at.str(), ": ", kw, " ", c.r, " ", c.g, " ", c.b,
                                             kw == "Tf" ? " exceeds 1 (transmits more than it receives); "
                                                        : " exceeds 1 (reflects more than it receives); ",
                                             "clamped to 1"));
            c = glm::min(c, Rgb(1.0));
        }
        if (kw == "Kd") m.kd = c;
        else if (kw == "Ks") m.ks = c;
        else if (kw == "Tf") m.smooth.transmission = c;  // used by glass only (finishMaterial)
        else m.ke = c;
        return;
    }
    // The remaining statements take one value.
    if (st.args.size() != 1)
        throwInputError(at, kw, " has ", count(st.args.size(), "value", "values"), ", expected 1");
    if (kw == "illum") {
        if (!parseInteger(st.args[0], lm.illum))
            throwInputError(at, "illum value '", st.args[0], "' is not an integer");
        lm.illumAt = at;
        return;
    }
    const double v = parseNumber(st.args[0], at, valueName.c_str());
    if (kw == "Ns") {
        if (v < 0) throwInputError(at, "Ns ", v, " is negative");
        m.ns = v;
    } else if (kw == "Ni") {
        // Kept whatever the illum model; only glass uses it (finishMaterial).
        if (!(v > 0)) throwInputError(at, "Ni ", v, " is not positive (an index of refraction)");
        m.smooth.ior = v;
    } else if ((kw == "d" && v < 1) || (kw == "Tr" && v > 0)) {
        scene_.warnings.push_back(concat(at.str(), ": ", kw, " ", v,
                                         " (transparency) is not supported; rendered opaque"));
    }
}

// The illum model, once Ks, Ni and Tf are all known (statements of a newmtl
// come in any order). 3 and 5 are mirrors of reflectance Ks (5 with
// Fresnel's rise towards grazing incidence, by Schlick), 7 is glass of index
// Ni (1.5 when absent) and filter Tf (1 1 1 when absent); the others that
// ray trace are drawn as the nearest of these (core/SmoothSpecular.h).
void ObjParser::finishMaterial(LibraryMaterial& lm) {
    Material& m = lm.material;
    SmoothSpecular& s = m.smooth;
    const long long model = lm.illum;
    const char* nearest = nullptr;
    switch (model) {
    case 3: s.kind = SpecularKind::Mirror; break;
    case 5: s.kind = SpecularKind::Mirror; s.schlick = true; break;
    case 7: s.kind = SpecularKind::Glass; break;
    // 8: reflection without ray tracing, drawn as illum 3's mirror.
    case 8: s.kind = SpecularKind::Mirror; nearest = "a mirror of reflectance Ks (as illum 3)"; break;
    // 4, 6, 9: glass without Fresnel, or refraction without it, drawn as illum 7's glass.
    case 4: case 6: case 9:
        s.kind = SpecularKind::Glass;
        nearest = "glass of index Ni and filter Tf (as illum 7)";
        break;
    default:
        s.kind = SpecularKind::None;
        if (model > 2)
            scene_.warnings.push_back(concat(lm.illumAt.str(), ": illum ", model,
                                             " is not supported; rendered as Lambert + Phong"));
        break;
    }
    if (nearest)
        scene_.warnings.push_back(concat(lm.illumAt.str(), ": illum ", model, " is rendered as ", nearest));
    if (s.kind == SpecularKind::Mirror) s.reflectance = m.ks;
}

// Options come first, each with its values; the file name is the rest of
// the line, blanks included. -o, -s and -clamp are honoured (see
// TextureStatement), the others warned about once per MTL file.
void ObjParser::parseAveragedTexture(const Statement& st, const SourceLocation& at, LibraryMaterial& m,
                                     RepeatedWarnings& repeated) {
    TextureStatement texture;
    texture.keyword = std::string(st.keyword);
    texture.at = at;
    size_t i = 0;
    // The last argument is never an option's value: it is (the end of) the file name.
    while (i + 1 < st.args.size() && st.args[i].size() > 1 && st.args[i].front() == '-') {
        const string_view name = st.args[i++];
        const auto option = std::find_if(std::begin(kTextureOptions), std::end(kTextureOptions),
                                         [&](const TextureOption& o) { return o.name == name; });
        if (option == std::end(kTextureOptions))
            throwInputError(at, st.keyword, ": unknown texture option '", name, "'");
        std::vector<double> values;
        string_view word;
        if (option->numeric) {
            while (values.size() < option->maxValues && i + 1 < st.args.size() && isNumber(st.args[i]))
                values.push_back(parseNumber(st.args[i++], at, "texture option value"));
            if (values.empty())
                throwInputError(at, st.keyword, ": texture option ", name, " has no value before the file name");
        } else {
            if (i + 1 >= st.args.size())
                throwInputError(at, st.keyword, ": texture option ", name, " has no value before the file name");
            word = st.args[i++];
        }
        if (name == "-o") {
            texture.offset = Vec2(values[0], values.size() > 1 ? values[1] : 0.0);
        } else if (name == "-s") {
            texture.scale = Vec2(values[0], values.size() > 1 ? values[1] : 1.0);
        } else if (name == "-clamp") {
            if (word != "on" && word != "off")
                throwInputError(at, st.keyword, ": -clamp takes on or off, not '", word, "'");
            texture.clamp = word == "on";
        } else {
            repeated.add(concat("texture option ", name, " is not supported; ignored"), at.line);
        }
    }
    if (i >= st.args.size()) throwInputError(at, st.keyword, " without a file name");
    const string_view file(st.args[i].data(), static_cast<size_t>(st.rest.data() + st.rest.size() - st.args[i].data()));
    texture.file = std::string(file);
    // Windows exporters write folders with backslashes.
    std::string portable = texture.file;
    std::replace(portable.begin(), portable.end(), '\\', '/');
    fs::path path{portable};
    if (path.is_relative()) path = fs::path(at.file).parent_path() / path;
    texture.path = path.lexically_normal().string();
    std::optional<TextureStatement>& slot =
        st.keyword == "map_Kd" ? m.mapKd : st.keyword == "map_Ke" ? m.mapKe : m.mapD;
    slot = std::move(texture);
}

// Textures --------------------------------------------------------------------

// Per material that faces use: map_d cuts triangles out first, then map_Kd
// and map_Ke are averaged over the triangles left.
void ObjParser::applyTextures() {
    std::vector<const LibraryMaterial*> textured(scene_.materials.size(), nullptr);
    bool any = false;
    for (const auto& [name, lm] : library_)
        if (lm.sceneIndex >= 0 && (lm.mapKd || lm.mapKe || lm.mapD)) {
            textured[lm.sceneIndex] = &lm;
            any = true;
        }
    if (!any) return;
    drawsTexture_.assign(scene_.materials.size(), false);
    for (size_t mi = 0; mi < textured.size(); ++mi)
        drawsTexture_[mi] = textured[mi] && (textured[mi]->mapKd || textured[mi]->mapKe || textured[mi]->mapD);
    std::vector<std::vector<RawTriangle*>> trianglesOf(scene_.materials.size());
    for (Group& g : groups_)
        for (RawTriangle& t : g.triangles)
            if (textured[t.material]) trianglesOf[t.material].push_back(&t);

    for (size_t mi = 0; mi < textured.size(); ++mi) {
        const LibraryMaterial* lm = textured[mi];
        if (!lm) continue;
        std::vector<RawTriangle*>& triangles = trianglesOf[mi];
        Material& m = scene_.materials[mi];
        if (lm->mapD) {
            // Per pixel where faces have vt (Material::alphaMap, for shading
            // and shadows); a face without vt is kept or cut out whole.
            m.alphaMap = lm->mapD->map(loadTexture(*lm->mapD), Rgb(1.0));
            m.alphaCutoff = kCutOutCoverage;
            cutOut(*lm->mapD, triangles);
            triangles.erase(std::remove_if(triangles.begin(), triangles.end(),
                                           [](const RawTriangle* t) { return t->cutOut; }),
                            triangles.end());
        }
        if (lm->mapKd) {
            m.kdMap = lm->mapKd->map(loadTexture(*lm->mapKd), m.kd);
            m.kd = glm::clamp(m.kd * textureMean(*lm->mapKd, triangles, &m.kd), Rgb(0.0), Rgb(1.0));
            scene_.warnings.push_back(concat(lm->mapKd->at.str(), ": texture ", lm->mapKd->named(),
                                             " averaged to Kd ", rgbText(m.kd)));
        }
        if (lm->mapKe) {
            // Exporters often write Ke 0 with an emission map: the map is the emission.
            const bool unset = m.ke == Rgb(0.0);
            if (unset) m.ke = Rgb(1.0);
            m.keMap = lm->mapKe->map(loadTexture(*lm->mapKe), m.ke);
            m.ke *= textureMean(*lm->mapKe, triangles);
            scene_.warnings.push_back(concat(lm->mapKe->at.str(), ": texture ", lm->mapKe->named(),
                                             " averaged to Ke ", rgbText(m.ke),
                                             unset ? " (no Ke or Ke 0: taken as 1 1 1 under map_Ke)" : ""));
        }
    }
    for (Group& g : groups_)
        g.triangles.erase(std::remove_if(g.triangles.begin(), g.triangles.end(),
                                         [](const RawTriangle& t) { return t.cutOut; }),
                          g.triangles.end());
}

// The texture a statement names, read (through read_) and decoded once.
std::shared_ptr<const Texture> ObjParser::loadTexture(const TextureStatement& statement) {
    const std::string key = statement.clamp ? statement.path + " (clamp)" : statement.path;
    auto found = textures_.find(key);
    if (found != textures_.end()) return found->second;
    std::string bytes;
    if (!read_(statement.path, bytes))
        throwInputError(statement.at, statement.named(), ": cannot read: no such file or not readable (",
                        statement.path, ")");
    auto texture = std::make_shared<Texture>();
    texture->name = statement.file;
    const std::string reason =
        decodeTexture(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), *texture);
    if (!reason.empty())
        throwInputError(statement.at, statement.named(),
                        ": cannot read: not a PNG, JPEG or TGA image that stb_image can decode (", reason, ")");
    // The nearest texel: a footprint of whole texels averages exactly those.
    texture->nearest = true;
    texture->wrapS = texture->wrapT = statement.clamp ? TextureWrap::ClampToEdge : TextureWrap::Repeat;
    return textures_.emplace(key, std::move(texture)).first->second;
}

void ObjParser::cutOut(const TextureStatement& statement, const std::vector<RawTriangle*>& triangles) {
    const Texture& texture = *loadTexture(statement);
    std::optional<double> imageCoverage;  // computed once, when a triangle has no vt
    size_t removed = 0, withoutUv = 0;
    for (RawTriangle* t : triangles) {
        if (t->hasTexcoords()) continue;  // cut out per pixel (Material::alphaMap)
        if (!imageCoverage) imageCoverage = texture.imageCoverage();
        ++withoutUv;
        t->cutOut = *imageCoverage < kCutOutCoverage;
        removed += t->cutOut;
    }
    cutOutTriangles_ += removed;
    if (withoutUv > 0) {
        scene_.warnings.push_back(concat(statement.at.str(), ": texture ", statement.named(), " cuts out ", removed,
                                         " of the ", count(withoutUv, "triangle", "triangles"),
                                         " without vt (the image's mean coverage is below ", kCutOutCoverage,
                                         "); faces with vt are cut out per pixel"));
        warnWithoutUv(statement, withoutUv);
    }
}

// With `albedoFactor`, each triangle with vt keeps factor × its own mean
// (RawTriangle::albedo).
Rgb ObjParser::textureMean(const TextureStatement& statement, const std::vector<RawTriangle*>& triangles,
                           const Rgb* albedoFactor) {
    const std::shared_ptr<const Texture> texture = loadTexture(statement);
    TextureMean mean(*texture);
    size_t withoutUv = 0;
    for (RawTriangle* t : triangles) {
        if (t->hasTexcoords()) {
            const Rgb value = footprintMean(*texture, lookups(statement, *t));
            mean.addValue(worldArea(*t), value);
            if (albedoFactor) t->albedo = glm::clamp(*albedoFactor * value, Rgb(0.0), Rgb(1.0));
        } else {
            mean.addWithoutUv(worldArea(*t));
            ++withoutUv;
        }
    }
    if (withoutUv > 0) warnWithoutUv(statement, withoutUv);
    return mean.mean();
}

void ObjParser::warnWithoutUv(const TextureStatement& statement, size_t triangles) {
    scene_.warnings.push_back(concat(statement.at.str(), ": texture ", statement.named(), ": ",
                                     count(triangles, "triangle has", "triangles have"),
                                     " no vt (texture coordinates); the mean over the whole image is used for ",
                                     triangles == 1 ? "it" : "them"));
}

double ObjParser::worldArea(const RawTriangle& t) const {
    const Vec3& p0 = positions_[t.position[0]];
    return 0.5 * glm::length(glm::cross(positions_[t.position[1]] - p0, positions_[t.position[2]] - p0));
}

std::array<Vec2, 3> ObjParser::lookups(const TextureStatement& statement, const RawTriangle& t) const {
    return {statement.lookup(texcoords_[t.texcoord[0]]), statement.lookup(texcoords_[t.texcoord[1]]),
            statement.lookup(texcoords_[t.texcoord[2]])};
}

// Assembly --------------------------------------------------------------------

Mesh ObjParser::buildMesh(const Group& group) {
    // The group's triangles over its own vertices, one per OBJ position.
    // Faces that draw a texture keep their vt: their vertices are split by
    // texture coordinate as well (Mesh::texcoords, v turned down).
    auto drawsTexture = [&](const RawTriangle& t) {
        return t.hasTexcoords() && t.material < drawsTexture_.size() && drawsTexture_[t.material];
    };
    const bool textured = std::any_of(group.triangles.begin(), group.triangles.end(), drawsTexture);
    const bool anyAlbedo = std::any_of(group.triangles.begin(), group.triangles.end(),
                                       [](const RawTriangle& t) { return t.albedo.has_value(); });
    Mesh raw;
    raw.name = group.name;
    std::vector<std::array<int32_t, 3>> cornerNormals;
    std::unordered_map<uint64_t, uint32_t> localOf;  // (position, vt + 1 or 0) → vertex
    for (const RawTriangle& t : group.triangles) {
        glm::uvec3 tri;
        const bool keepUv = textured && drawsTexture(t);
        for (int k = 0; k < 3; ++k) {
            const int32_t vt = keepUv ? t.texcoord[k] : -1;
            const auto [it, inserted] =
                localOf.try_emplace(uint64_t(t.position[k]) << 32 | uint32_t(vt + 1),
                                    static_cast<uint32_t>(raw.positions.size()));
            if (inserted) {
                raw.positions.push_back(positions_[t.position[k]]);
                if (textured) {
                    const Vec2 uv = vt >= 0 ? texcoords_[vt] : Vec2(0.0, 1.0);
                    raw.texcoords.emplace_back(uv.x, 1 - uv.y);
                }
            }
            tri[k] = it->second;
        }
        raw.triangles.push_back(tri);
        raw.materials.push_back(t.material);
        raw.sourceLines.push_back(t.line);
        if (anyAlbedo) raw.albedo.push_back(t.albedo ? *t.albedo : scene_.materials[t.material].kd);
        cornerNormals.push_back(t.normal);
    }

    std::vector<size_t> removed;
    removeDegenerateTriangles(raw, kDegenerateRelTol, &removed);
    for (size_t r : removed) {
        const int line = group.triangles[r].line;
        if (degenerateTriangles_++ == 0 || line < firstDegenerateLine_) firstDegenerateLine_ = line;
    }
    if (!removed.empty()) {
        size_t kept = 0, nextRemoved = 0;
        for (size_t t = 0; t < cornerNormals.size(); ++t) {
            if (nextRemoved < removed.size() && removed[nextRemoved] == t) ++nextRemoved;
            else cornerNormals[kept++] = cornerNormals[t];
        }
        cornerNormals.resize(kept);
    }

    // Faces whose corners all have vn keep them (a vertex per position and
    // normal); the others get computed normals. Triangle order is kept.
    Mesh out;
    out.name = group.name;
    Mesh computed;
    computed.name = group.name;
    computed.positions = raw.positions;
    std::map<std::pair<uint32_t, int32_t>, uint32_t> givenVertex;
    std::vector<bool> isGiven(raw.triangles.size());
    for (size_t t = 0; t < raw.triangles.size(); ++t) {
        const std::array<int32_t, 3>& cn = cornerNormals[t];
        isGiven[t] = cn[0] >= 0 && cn[1] >= 0 && cn[2] >= 0;
        if (!isGiven[t]) {
            computed.triangles.push_back(raw.triangles[t]);
            continue;
        }
        glm::uvec3 tri;
        for (int k = 0; k < 3; ++k) {
            const auto [it, inserted] =
                givenVertex.try_emplace(std::make_pair(raw.triangles[t][k], cn[k]),
                                        static_cast<uint32_t>(out.positions.size()));
            if (inserted) {
                out.positions.push_back(raw.positions[raw.triangles[t][k]]);
                out.normals.push_back(normals_[cn[k]]);
                if (textured) out.texcoords.push_back(raw.texcoords[raw.triangles[t][k]]);
            }
            tri[k] = it->second;
        }
        out.triangles.push_back(tri);
    }
    if (computed.triangles.empty()) {
        out.materials = std::move(raw.materials);
        out.sourceLines = std::move(raw.sourceLines);
        out.albedo = std::move(raw.albedo);
        return out;
    }
    computed.texcoords = raw.texcoords;
    computeShadingNormals(computed, options_.creaseAngleDegrees);

    const uint32_t offset = static_cast<uint32_t>(out.positions.size());
    out.positions.insert(out.positions.end(), computed.positions.begin(), computed.positions.end());
    out.normals.insert(out.normals.end(), computed.normals.begin(), computed.normals.end());
    out.texcoords.insert(out.texcoords.end(), computed.texcoords.begin(), computed.texcoords.end());
    std::vector<glm::uvec3> given = std::move(out.triangles);
    out.triangles.clear();
    size_t nextGiven = 0, nextComputed = 0;
    for (size_t t = 0; t < raw.triangles.size(); ++t)
        out.triangles.push_back(isGiven[t] ? given[nextGiven++]
                                           : computed.triangles[nextComputed++] + offset);
    out.materials = std::move(raw.materials);
    out.sourceLines = std::move(raw.sourceLines);
    out.albedo = std::move(raw.albedo);
    return out;
}

}  // namespace

Scene loadObj(const std::string& path, const ObjOptions& options) {
    return loadObj(path, options, [](const std::string& file, std::string& text) { return readFile(file, text); });
}

Scene loadObj(const std::string& path, const ObjOptions& options, const ObjFileReader& read) {
    return ObjParser(path, options, read).parse();
}

}  // namespace ml
