// The scene's lights as the viewer shows and switches them: each light's
// emitted power and luminous flux (the panel, the status line), and the
// groups of lights that switch and dim as one (the panel, a script's
// `group NAME on|off|dim F`).
//
// Power. Light::power() is W·(scene unit)²/m² for every kind; watts are
// that × s², s the metres per unit of what has a length in it. A punctual
// light's power is its intensity × the solid angle of its profile (W·sr⁻¹ ×
// sr), which has no length: s is the scene's own (Scene::metresPerUnit, the
// one its inverse-square law uses), and the product is unit-free. An area
// light's is π Ke A: A in m² takes the unit the viewer was told (--units).
//
// Groups. A group is a set of lights a lighting designer switches together
// (Light::group: a glTF node's name without its numbered suffix, a luminaire
// layout's group column); a light without one is a group of its own, named
// as the light. Switching or dimming a group sets each of its lights'
// controls (LightControl::on, ::intensity), so the weights a group gives are
// those its lights would have if each were set alike: exact where each
// light has its own cache mesh (DisplayState.h).
#pragma once

#include "DisplayState.h"
#include "core/Scene.h"
#include "core/image/Photometry.h"

#include <string>
#include <vector>

namespace ml {

// What the viewer shows of one light.
struct ViewLight {
    std::string name;
    std::string kind;     // "area", "point", "spot", "luminaire" (a candela table) or "directional"
    std::string details;  // the panel's tooltip: "Ke (...) W/sr/m2, area A m2" or "peak I cd, ... at (x, y, z)"
    Rgb powerW{0.0};      // emitted power, W per channel (a directional light's: what reaches the scene)
    double lumens = 0;    // Photometry::luminous(powerW), lm
    // A point light (point, spot, luminaire) has no faces to draw: the
    // wireframe marks it at its position instead.
    bool point = false;
    Vec3 position{0.0};
};

// `areaMetresPerUnit`: metres per scene unit for an area light's area (the
// viewer's --units); punctual lights use the scene's own (see above).
ViewLight viewLight(const Light& light, const Scene& scene, double areaMetresPerUnit, const Photometry& photometry);

struct LightGroup {
    std::string name;            // Light::group, or the light's name when it has none
    std::vector<size_t> lights;  // indices into Scene::lights, ascending; never empty
};

// The scene's groups, in the order of their first lights.
std::vector<LightGroup> lightGroups(const std::vector<Light>& lights);

// A group is on when any of its lights is.
bool groupOn(const std::vector<LightControl>& controls, const LightGroup& group);
// Every light of the group on or off (its intensity and colour kept).
void switchGroup(std::vector<LightControl>& controls, const LightGroup& group, bool on);
// Every light of the group at `intensity` (≥ 0, × the scene's emission).
void dimGroup(std::vector<LightControl>& controls, const LightGroup& group, double intensity);

// "'Spot' (2 lights), 'Bulb'": the groups as an error message lists them.
std::string describeGroups(const std::vector<LightGroup>& groups);

}  // namespace ml
