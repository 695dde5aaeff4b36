#include "LuminaireLayout.h"

#include "PhotometricFile.h"
#include "core/CandelaTable.h"
#include "core/Error.h"
#include "core/image/Photometry.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace ml {

Light luminaireLight(std::shared_ptr<const CandelaTable> table, const LuminairePlacement& p, std::string name,
                     std::string group) {
    Light l;
    l.name = std::move(name);
    l.group = std::move(group);
    l.kind = LightKind::Point;
    PunctualEmission& e = l.emission;
    e.position = p.position;
    const double aimLength = glm::length(p.aim);
    e.axis = aimLength > 0 ? p.aim / aimLength : p.aim;  // Scene::finalize refuses a zero aim, naming the light
    // The C0 direction: the reference made perpendicular to the aim (+z
    // when it lies along the aim), then turned about the aim.
    Vec3 r = p.reference - glm::dot(p.reference, e.axis) * e.axis;
    if (glm::length(r) < 1e-6) r = Vec3(0, 0, 1) - glm::dot(Vec3(0, 0, 1), e.axis) * e.axis;
    if (glm::length(r) > 0) {
        r = glm::normalize(r);
        const double a = p.rotationDegrees * kPi / 180;
        r = std::cos(a) * r + std::sin(a) * glm::cross(e.axis, r);  // Rodrigues, r ⟂ axis
    }
    e.reference = r;
    e.intensity = Rgb(table->maxIntensity() * p.multiplier / kRadianceEfficacy);
    e.profile.shape = IntensityProfile::Shape::Table;
    e.profile.table = std::move(table);
    return l;
}

namespace {

std::string trim(const std::string& s) {
    const size_t a = s.find_first_not_of(" \t\r"), b = s.find_last_not_of(" \t\r");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

std::vector<std::string> cells(const std::string& line) {
    std::vector<std::string> out;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) out.push_back(trim(cell));
    if (!line.empty() && line.back() == ',') out.emplace_back();
    return out;
}

const char* const kColumns[] = {"file", "x", "y", "z", "aim_x", "aim_y", "aim_z", "rotation", "multiplier", "group", "name"};

}  // namespace

void addLuminaireLayout(Scene& scene, const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(SourceLocation{path, 0}, "cannot open the luminaire layout");
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    std::map<std::string, int> column;  // name -> index
    std::map<std::string, std::shared_ptr<const CandelaTable>> tables;  // by resolved path: read once
    std::map<std::string, int> stems;   // default names
    std::string line;
    int lineNo = 0, luminaires = 0;
    while (std::getline(in, line)) {
        ++lineNo;
        const SourceLocation at{path, lineNo};
        const std::string t = trim(line);
        if (t.empty() || t[0] == '#') continue;
        const std::vector<std::string> c = cells(t);
        if (column.empty()) {
            for (size_t i = 0; i < c.size(); ++i) {
                bool known = false;
                for (const char* k : kColumns) known |= c[i] == k;
                if (!known)
                    throwInputError(at, "unknown column '", c[i], "' (columns: file, x, y, z, aim_x, aim_y, aim_z, "
                                    "rotation, multiplier, group, name)");
                if (!column.emplace(c[i], int(i)).second) throwInputError(at, "column '", c[i], "' appears twice");
            }
            for (const char* k : {"file", "x", "y", "z"})
                if (!column.count(k)) throwInputError(at, "the header has no column '", k, "'");
            const int aims = int(column.count("aim_x") + column.count("aim_y") + column.count("aim_z"));
            if (aims != 0 && aims != 3) throwInputError(at, "aim_x, aim_y and aim_z come together");
            continue;
        }
        if (c.size() != column.size())
            throwInputError(at, c.size(), " values, the header names ", column.size(), " columns");
        const auto text = [&](const char* name, const std::string& fallback) {
            const auto it = column.find(name);
            return it == column.end() ? fallback : c[size_t(it->second)];
        };
        const auto number = [&](const char* name, double fallback) {
            const auto it = column.find(name);
            if (it == column.end()) return fallback;
            double v = 0;
            if (!photometric::parseNumber(c[size_t(it->second)], v))
                throwInputError(at, "column '", name, "': '", c[size_t(it->second)], "' is not a finite number");
            return v;
        };
        const std::string file = text("file", "");
        if (file.empty()) throwInputError(at, "column 'file' is empty");
        const std::string resolved = (folder / file).lexically_normal().string();
        auto& table = tables[resolved];
        if (!table) table = std::make_shared<const CandelaTable>(loadPhotometricFile(resolved));
        LuminairePlacement p;
        p.position = Vec3(number("x", 0), number("y", 0), number("z", 0));
        p.aim = Vec3(number("aim_x", 0), number("aim_y", -1), number("aim_z", 0));
        if (!(glm::length(p.aim) > 0)) throwInputError(at, "the aim is the zero vector");
        p.rotationDegrees = number("rotation", 0);
        p.multiplier = number("multiplier", 1);
        if (p.multiplier < 0) throwInputError(at, "column 'multiplier': ", p.multiplier, " is negative");
        std::string name = text("name", "");
        if (name.empty()) {
            const std::string stem = std::filesystem::path(file).stem().string();
            name = concat(stem, "#", stems[stem]++);
        }
        for (const Light& l : scene.lights)
            if (l.name == name) throwInputError(at, "a light named '", name, "' is already in the scene");
        std::string group = text("group", "");
        if (group.empty()) group = lightGroupOf(name);
        scene.lights.push_back(luminaireLight(table, p, name, group));
        ++luminaires;
    }
    if (column.empty()) throw InputError(SourceLocation{path, lineNo}, "no header line (file,x,y,z,...)");
    if (luminaires == 0) scene.warnings.push_back(concat(path, ": no luminaire in the layout"));
    scene.finalize();
}

}  // namespace ml
