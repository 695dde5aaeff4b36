// Photometric luminaires placed in a scene: a luminaire layout file, or a
// glTF node's extras, each pointing at an IES LM-63 or EULUMDAT file
// (PhotometricFile.h). A luminaire becomes a point light (Light, kind Point)
// whose intensity follows the file's candela table: it is treated as a point
// at its photometric centre, as the far-field photometry of the file
// assumes (its luminous opening is not sampled as an area light: say so in
// a scene where receivers come within about five times the opening's size).
//
// The layout file: CSV, '#' starts a comment line, blank lines are skipped,
// the first other line names the columns (any order, each at most once):
//   file        the IES (.ies) or EULUMDAT (.ldt) file, relative to the layout's folder (required)
//   x, y, z     the photometric centre, scene units (required)
//   aim_x, aim_y, aim_z
//               where the luminaire points (its nadir, γ = 0); default 0,-1,0 (down in a y-up scene)
//   rotation    degrees about the aim, right-handed, turning the C0 half-plane away from its default:
//               the scene's +x made perpendicular to the aim (+z when the aim is along x); default 0
//   multiplier  scales the file's candela values (dimming, a lamp of other lumens); default 1
//   group       lights that switch together in the viewer (default: the name's group, Scene.h)
//   name        the light's name (default: the file's stem, "#k" added where names repeat)
// Every error names the layout file, its line and the column.
#pragma once

#include "core/Scene.h"

#include <memory>
#include <string>

namespace ml {

struct CandelaTable;

// Where a luminaire is and how it points.
struct LuminairePlacement {
    Vec3 position{0.0};         // photometric centre, scene units
    Vec3 aim{0.0, -1.0, 0.0};   // nadir direction (need not be unit)
    Vec3 reference{1.0, 0.0, 0.0};  // the C0 half-plane's direction before `rotation` (made ⟂ aim)
    double rotationDegrees = 0;  // about the aim, right-handed
    double multiplier = 1;       // on the candela values, >= 0
};

// A point light of `table`'s distribution: white, peak intensity max cd ×
// multiplier / 179 (K of Photometry.h) W·sr⁻¹ per channel.
Light luminaireLight(std::shared_ptr<const CandelaTable> table, const LuminairePlacement& placement,
                     std::string name, std::string group);

// Reads a layout file and appends its luminaires to scene.lights, then
// finalizes the scene again (its area lights stay as they were). Throws
// InputError naming the file and line.
void addLuminaireLayout(Scene& scene, const std::string& path);

}  // namespace ml
