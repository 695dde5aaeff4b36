// Calculation surfaces as lighting designers use them (EN 12464-1, DIAL,
// Relux): the points where `meshlight grid` computes illuminance, and the
// statistics it reports for each surface. A surface is a horizontal work
// plane over the scene's floor, the faces of a named object, or points from
// a file. The geometry and the statistics are pure functions (no GPU, no
// rays) except skipPointsInsideSolids, which casts one ray a point.
#pragma once

#include "SensorIrradiance.h"
#include "core/Math.h"
#include "core/Scene.h"

#include <optional>
#include <string>
#include <vector>

namespace ml {

class EmbreeScene;

// A work plane's regular grid: the plan view's cells, `columns` × `rows`,
// each holding at most one point (at its centre).
struct PlaneGrid {
    int columns = 0, rows = 0;
    Vec3 corner{0.0};          // the grid's corner at u = v = 0, on the plane
    Vec3 u{1, 0, 0}, v{0, 0, 1};  // unit axes of the columns and the rows
    double cellU = 0, cellV = 0;  // cell sides along u and v (scene units), at most the spacing asked for
    // Per cell (row-major, row 0 at v = 0): the index of its point in
    // CalculationSurface::points, or -1 where the point was left out.
    std::vector<int> pointAt;
};

struct CalculationSurface {
    std::string name;                  // "workplane", a mesh's name, a grid file's surface name
    std::vector<SensorPoint> points;
    std::optional<PlaneGrid> grid;     // a work plane's grid; none for objects and files
    size_t skipped = 0;                // points left out (inside solid objects)
};

// Which axis is up: the floor is the scene bounds' minimum along it.
enum class UpAxis { Y, Z };
UpAxis parseUpAxis(const std::string& name);  // "y" or "z"; InputError otherwise
int axisIndex(UpAxis up);                     // 1 or 2
Vec3 upVector(UpAxis up);                     // (0,1,0) or (0,0,1)

struct WorkPlaneSettings {
    double height = 0.75;   // above the floor, scene units; typical 0.75 m (desks), 0.85 m, 0 (floor)
    double margin = 0;      // left out along the walls (the scene bounds), scene units; typical 0.5 m
    double spacing = 0.25;  // the largest cell side, scene units; EN 12464-1 asks ≤ en12464Spacing()
    UpAxis up = UpAxis::Y;
};

// A horizontal plane at `height` above bounds.lo along up, over the bounds
// less `margin` on every side, divided into equal cells no larger than
// `spacing` with a point at each cell's centre, facing up: EN 12464-1's
// grid (cells, not edge points, so the average is the area's mean). Axes:
// for up = y, columns along x and rows along z; for up = z, x and y.
// InputError when the height is outside the bounds, the margin leaves no
// area or the grid would exceed 10⁶ points.
CalculationSurface workPlane(const Bounds3& bounds, const WorkPlaneSettings& settings);

// EN 12464-1 (2021, 5.2.3): the largest grid spacing for an area whose
// longer side is `metres` long: 0.2 × 5^log10(d) m (1 m for d = 10 m).
double en12464Spacing(double metres);

// Points on `mesh`'s triangles, on their front (counter-clockwise, outward
// for a closed object) side, with the face's normal: a square lattice of
// `spacing` in each face's plane, shared by coplanar faces of one normal
// (so a quad of two triangles gets one regular grid) and kept where it falls
// inside a triangle, a point on a shared edge once. With `facingUp`, only
// faces whose normal is within 60° of it (n · up > 0.5): a desk's top, not
// its sides. InputError naming the mesh when no point falls on it.
CalculationSurface objectSurface(const Mesh& mesh, double spacing, const std::optional<Vec3>& facingUp);

// Leaves out the points inside solid objects: those whose ray straight up
// first meets the back of a face (a cabinet's top seen from inside), since
// no light reaches them and EN 12464-1 evaluates the free area. Points
// with nothing above, or a face's front (a ceiling, a light), are kept.
// Updates `skipped` and the grid's cells.
void skipPointsInsideSolids(CalculationSurface& surface, const EmbreeScene& rays, const Vec3& up);

// --- Statistics ----------------------------------------------------------------

// What EN 12464-1 reports for a calculation surface, from the illuminance
// at its points (lx): equal cells, so the average is the plain mean.
struct IlluminanceStatistics {
    size_t points = 0;
    double average = 0;  // Ē, lx
    double minimum = 0;  // Emin, lx
    double maximum = 0;  // Emax, lx
    // U0 = Emin / Ē (EN 12464-1's uniformity); NaN when Ē = 0 or no point.
    double uniformity() const;
    // Emin / Emax (the "diversity" Ud); NaN when Emax = 0 or no point.
    double diversity() const;
};
IlluminanceStatistics illuminanceStatistics(const std::vector<double>& lux);

}  // namespace ml
