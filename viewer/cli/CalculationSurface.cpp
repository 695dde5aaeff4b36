#include "CalculationSurface.h"

#include "core/Error.h"
#include "core/raytrace/EmbreeScene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <tuple>

namespace ml {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr size_t kMaxPoints = 1000000;

// Equal cells no larger than `spacing` over `length`: at least one.
int cellCount(double length, double spacing) {
    return std::max(1, int(std::ceil(length / spacing - 1e-9)));
}

}  // namespace

UpAxis parseUpAxis(const std::string& name) {
    if (name == "y") return UpAxis::Y;
    if (name == "z") return UpAxis::Z;
    throw InputError(concat("unknown up axis '", name, "' (expected y or z)"));
}

int axisIndex(UpAxis up) { return up == UpAxis::Y ? 1 : 2; }

Vec3 upVector(UpAxis up) { return up == UpAxis::Y ? Vec3(0, 1, 0) : Vec3(0, 0, 1); }

CalculationSurface workPlane(const Bounds3& bounds, const WorkPlaneSettings& s) {
    ML_ASSERT(!bounds.empty(), "a work plane over empty bounds");
    const int up = axisIndex(s.up);
    // Columns along x; rows along z (up = y) or y (up = z).
    const int ua = 0, va = s.up == UpAxis::Y ? 2 : 1;
    const Vec3 extent = bounds.extent();
    if (!(s.height >= 0 && s.height <= extent[up]))
        throw InputError(concat("--plane ", s.height, " is outside the scene: its height along ",
                                s.up == UpAxis::Y ? "y" : "z", " is ", extent[up]));
    const double lengthU = extent[ua] - 2 * s.margin, lengthV = extent[va] - 2 * s.margin;
    if (!(lengthU > 0 && lengthV > 0))
        throw InputError(concat("--margin ", s.margin, " leaves no work plane: the scene is ", extent[ua], " x ",
                                extent[va]));
    PlaneGrid g;
    g.columns = cellCount(lengthU, s.spacing);
    g.rows = cellCount(lengthV, s.spacing);
    if (size_t(g.columns) * size_t(g.rows) > kMaxPoints)
        throw InputError(concat("--spacing ", s.spacing, " makes ", size_t(g.columns) * size_t(g.rows),
                                " points (more than ", kMaxPoints, "): use a larger spacing"));
    g.cellU = lengthU / g.columns;
    g.cellV = lengthV / g.rows;
    g.u = Vec3(0.0);
    g.u[ua] = 1;
    g.v = Vec3(0.0);
    g.v[va] = 1;
    g.corner = bounds.lo;
    g.corner[ua] += s.margin;
    g.corner[va] += s.margin;
    g.corner[up] += s.height;

    CalculationSurface surface;
    surface.name = "workplane";
    const Vec3 normal = upVector(s.up);
    for (int r = 0; r < g.rows; ++r)
        for (int c = 0; c < g.columns; ++c) {
            g.pointAt.push_back(int(surface.points.size()));
            surface.points.push_back({g.corner + (c + 0.5) * g.cellU * g.u + (r + 0.5) * g.cellV * g.v, normal});
        }
    surface.grid = std::move(g);
    return surface;
}

double en12464Spacing(double metres) { return 0.2 * std::pow(5.0, std::log10(std::max(metres, 1e-3))); }

CalculationSurface objectSurface(const Mesh& mesh, double spacing, const std::optional<Vec3>& facingUp) {
    CalculationSurface surface;
    surface.name = mesh.name;
    // A lattice point once, whichever of the triangles sharing it finds it:
    // keyed by the face normal, the plane's offset and the lattice indices.
    std::set<std::tuple<long long, long long, long long, long long, long long, long long>> seen;
    const auto quantise = [](double x) { return (long long)std::llround(x * 1e6); };
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Vec3 an = mesh.areaNormal(t);
        if (!(glm::length(an) > 0)) continue;
        const Vec3 n = glm::normalize(an);
        if (facingUp && glm::dot(n, *facingUp) <= 0.5) continue;
        Vec3 tu, tv;
        orthonormalBasis(n, tu, tv);
        const Triangle3 p = mesh.triangle(t);
        const double d = glm::dot(p[0], n);
        double u[3], v[3];
        for (int k = 0; k < 3; ++k) {
            u[k] = glm::dot(p[k], tu);
            v[k] = glm::dot(p[k], tv);
        }
        const double area2 = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
        if (area2 == 0) continue;
        const double eps = 1e-9 * std::abs(area2);
        const long long i0 = (long long)std::ceil(std::min({u[0], u[1], u[2]}) / spacing - 0.5);
        const long long i1 = (long long)std::floor(std::max({u[0], u[1], u[2]}) / spacing - 0.5);
        const long long j0 = (long long)std::ceil(std::min({v[0], v[1], v[2]}) / spacing - 0.5);
        const long long j1 = (long long)std::floor(std::max({v[0], v[1], v[2]}) / spacing - 0.5);
        if ((i1 - i0 + 1) * (j1 - j0 + 1) > (long long)kMaxPoints)
            throw InputError(concat("--spacing ", spacing, " puts more than ", kMaxPoints, " points on object '",
                                    mesh.name, "': use a larger spacing"));
        for (long long i = i0; i <= i1; ++i)
            for (long long j = j0; j <= j1; ++j) {
                const double x = (double(i) + 0.5) * spacing, y = (double(j) + 0.5) * spacing;
                // Edge functions, signed like the triangle: all ≥ 0 inside.
                bool inside = true;
                for (int k = 0; k < 3 && inside; ++k) {
                    const int a = k, b = (k + 1) % 3;
                    const double e = ((u[b] - u[a]) * (y - v[a]) - (x - u[a]) * (v[b] - v[a])) * (area2 > 0 ? 1 : -1);
                    inside = e >= -eps;
                }
                if (!inside) continue;
                if (!seen.insert({quantise(n.x), quantise(n.y), quantise(n.z), quantise(d / spacing), i, j}).second)
                    continue;
                surface.points.push_back({x * tu + y * tv + d * n, n});
            }
        if (surface.points.size() > kMaxPoints)
            throw InputError(concat("--spacing ", spacing, " puts more than ", kMaxPoints, " points on object '",
                                    mesh.name, "': use a larger spacing"));
    }
    if (surface.points.empty())
        throw InputError(concat("object '", mesh.name, "' has no point at --spacing ", spacing,
                                facingUp ? " facing up" : "", ": its faces are smaller than the spacing"));
    return surface;
}

void skipPointsInsideSolids(CalculationSurface& surface, const EmbreeScene& rays, const Vec3& up) {
    std::vector<SensorPoint> kept;
    std::vector<int> newIndex(surface.points.size(), -1);
    for (size_t i = 0; i < surface.points.size(); ++i) {
        const SensorPoint& p = surface.points[i];
        RayHit hit;
        const bool inside = rays.intersect(p.position, up, rays.rayOffset(p.position), kInf, hit) &&
                            glm::dot(rays.surface(hit).geometricNormal, up) > 0;
        if (inside) continue;
        newIndex[i] = int(kept.size());
        kept.push_back(p);
    }
    surface.skipped += surface.points.size() - kept.size();
    surface.points = std::move(kept);
    if (surface.grid)
        for (int& k : surface.grid->pointAt)
            if (k >= 0) k = newIndex[size_t(k)];
}

double IlluminanceStatistics::uniformity() const { return points && average > 0 ? minimum / average : kNaN; }

double IlluminanceStatistics::diversity() const { return points && maximum > 0 ? minimum / maximum : kNaN; }

IlluminanceStatistics illuminanceStatistics(const std::vector<double>& lux) {
    IlluminanceStatistics s;
    s.points = lux.size();
    if (lux.empty()) return s;
    double sum = 0;
    s.minimum = s.maximum = lux.front();
    for (double e : lux) {
        sum += e;
        s.minimum = std::min(s.minimum, e);
        s.maximum = std::max(s.maximum, e);
    }
    s.average = sum / double(lux.size());
    return s;
}

}  // namespace ml
