#include "ViewLights.h"

#include "core/Error.h"

#include <algorithm>
#include <cstdio>
#include <unordered_map>

namespace ml {

namespace {

std::string format(const char* fmt, double a, double b = 0, double c = 0, double d = 0) {
    char buf[160];
    std::snprintf(buf, sizeof buf, fmt, a, b, c, d);
    return buf;
}

std::string position(const Vec3& p) { return format("(%.4g, %.4g, %.4g)", p.x, p.y, p.z); }

const char* kindName(const Light& l) {
    if (l.kind == LightKind::Directional) return "directional";
    if (l.kind == LightKind::Area) return "area";
    switch (l.emission.profile.shape) {
        case IntensityProfile::Shape::Isotropic: return "point";
        case IntensityProfile::Shape::Spot: return "spot";
        case IntensityProfile::Shape::Table: return "luminaire";
    }
    return "point";
}

}  // namespace

ViewLight viewLight(const Light& light, const Scene& scene, double areaMetresPerUnit, const Photometry& photometry) {
    ViewLight v;
    v.name = light.name;
    v.kind = kindName(light);
    const double s = light.punctual() ? scene.metresPerUnit : areaMetresPerUnit;
    v.powerW = light.power() * (s * s);
    v.lumens = photometry.luminous(v.powerW);
    const PunctualEmission& e = light.emission;
    switch (light.kind) {
        case LightKind::Area:
            v.details = format("Ke (%.3g, %.3g, %.3g) W/sr/m2, area %.4g m2", light.radiance.r, light.radiance.g,
                               light.radiance.b, light.area * areaMetresPerUnit * areaMetresPerUnit);
            break;
        case LightKind::Point:
            v.point = true;
            v.position = e.position;
            v.details = concat(format("peak %.4g cd, ", photometry.luminous(e.intensity)), e.profile.describe(),
                               ", at ", position(e.position),
                               e.profile.shape == IntensityProfile::Shape::Isotropic
                                   ? std::string()
                                   : ", aimed along " + position(e.axis));
            break;
        case LightKind::Directional:
            v.details = concat(format("%.4g lx on a surface facing it, travelling along ", photometry.luminous(e.intensity)),
                               position(e.axis), "; its flux is what reaches the scene's bounding sphere");
            break;
    }
    return v;
}

std::vector<LightGroup> lightGroups(const std::vector<Light>& lights) {
    std::vector<LightGroup> groups;
    std::unordered_map<std::string, size_t> index;  // name → position in groups
    for (size_t l = 0; l < lights.size(); ++l) {
        const std::string& name = lights[l].group.empty() ? lights[l].name : lights[l].group;
        const auto [at, added] = index.emplace(name, groups.size());
        if (added) groups.push_back({name, {}});
        groups[at->second].lights.push_back(l);
    }
    return groups;
}

bool groupOn(const std::vector<LightControl>& controls, const LightGroup& group) {
    return std::any_of(group.lights.begin(), group.lights.end(), [&](size_t l) { return controls.at(l).on; });
}

void switchGroup(std::vector<LightControl>& controls, const LightGroup& group, bool on) {
    for (size_t l : group.lights) controls.at(l).on = on;
}

void dimGroup(std::vector<LightControl>& controls, const LightGroup& group, double intensity) {
    ML_ASSERT(intensity >= 0, "group '", group.name, "' dimmed to ", intensity);
    for (size_t l : group.lights) controls.at(l).intensity = intensity;
}

std::string describeGroups(const std::vector<LightGroup>& groups) {
    std::string s;
    for (const LightGroup& g : groups)
        s += concat(s.empty() ? "" : ", ", "'", g.name, "'",
                    g.lights.size() > 1 ? concat(" (", g.lights.size(), " lights)") : std::string());
    return s;
}

}  // namespace ml
