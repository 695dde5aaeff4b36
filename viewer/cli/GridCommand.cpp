// meshlight grid: illuminance on calculation surfaces, as lighting designers
// report it (EN 12464-1): a work plane over the floor, the faces of named
// objects, or points from a file; the lux at every point (CSV), and per
// surface the average, minimum, maximum and uniformity (printed, CSV), and a
// one-page HTML report with the work plane's false-colour plan view. The
// irradiance comes from probe's machinery (SensorIrradiance.h), with its
// methods, options and interrupt rules.
#include "CalculationSurface.h"
#include "Commands.h"
#include "GridReport.h"
#include "PhotometryOptions.h"
#include "SensorIrradiance.h"
#include "core/Error.h"
#include "core/image/Illuminance.h"
#include "core/io/AtomicFile.h"
#include "core/io/InterruptGuard.h"
#include "core/raytrace/EmbreeScene.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>
#include <sstream>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;

// Every value of an option the user may repeat (--object A --object B);
// Options keeps only the last.
std::vector<std::string> repeatedValues(const std::vector<std::string>& args, const std::string& name) {
    std::vector<std::string> values;
    for (size_t i = 0; i < args.size(); ++i) {
        if (args[i] == "--" + name && i + 1 < args.size())
            values.push_back(args[++i]);
        else if (args[i].rfind("--" + name + "=", 0) == 0)
            values.push_back(args[i].substr(name.size() + 3));
    }
    return values;
}

// The scene's length unit: --units, else the scene's own (Scene::metresPerUnit:
// millimetres for the built-in Cornell box, metres for the office, the bench,
// OBJ and glTF files), as its name ("mm") and metres per unit.
std::pair<std::string, double> sceneUnit(const std::optional<LengthUnit>& given, const Scene& scene) {
    if (given) return {lengthUnitName(*given), metresPerUnit(*given)};
    for (LengthUnit u : {LengthUnit::Millimetre, LengthUnit::Centimetre, LengthUnit::Metre})
        if (std::abs(scene.metresPerUnit - metresPerUnit(u)) <= 1e-9 * metresPerUnit(u))
            return {lengthUnitName(u), metresPerUnit(u)};
    return {concat("units of ", scene.metresPerUnit, " m"), scene.metresPerUnit};
}

// The surfaces of a grid file: one per name in its `surface` column, in
// order of first appearance, or one named after the file.
std::vector<CalculationSurface> fileSurfaces(const std::string& path) {
    std::vector<std::string> names;
    const std::vector<SensorPoint> points = readSensorCsv(path, &names);
    std::vector<CalculationSurface> surfaces;
    std::map<std::string, size_t> index;
    const std::string fallback = std::filesystem::path(path).stem().string();
    for (size_t i = 0; i < points.size(); ++i) {
        const std::string& name = names[i].empty() ? fallback : names[i];
        auto [it, added] = index.emplace(name, surfaces.size());
        if (added) {
            surfaces.emplace_back();
            surfaces.back().name = name;
        }
        surfaces[it->second].points.push_back(points[i]);
    }
    if (surfaces.empty()) throwInputError(SourceLocation{path}, "no points");
    return surfaces;
}

// The meshes named `name`, as one surface.
CalculationSurface namedObject(const Scene& scene, const std::string& name, double spacing,
                               const std::optional<Vec3>& facingUp) {
    Mesh merged;
    merged.name = name;
    for (const Mesh& m : scene.meshes) {
        if (m.name != name) continue;
        const uint32_t base = uint32_t(merged.positions.size());
        merged.positions.insert(merged.positions.end(), m.positions.begin(), m.positions.end());
        for (const glm::uvec3& t : m.triangles) merged.triangles.push_back(t + glm::uvec3(base));
    }
    if (merged.triangles.empty()) {
        std::string known;
        for (size_t i = 0; i < scene.meshes.size() && i < 40; ++i)
            known += (i ? ", " : "") + scene.meshes[i].name;
        if (scene.meshes.size() > 40) known += ", ...";
        throw InputError(concat("--object: no mesh named '", name, "' in scene '", scene.name, "' (meshes: ", known,
                                ")"));
    }
    return objectSurface(merged, spacing, facingUp);
}

std::string fixed(double v, int digits) {
    if (!std::isfinite(v)) return "-";
    char text[32];
    std::snprintf(text, sizeof text, "%.*f", digits, v);
    return text;
}

std::string localTime() {
    const std::time_t now = std::time(nullptr);
    char text[64];
    std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S %Z", std::localtime(&now));
    return text;
}

}  // namespace

int runGrid(const std::vector<std::string>& args) {
    const auto t0 = Clock::now();
    Options o("grid");
    declareSceneOptions(o);
    o.value("plane", "H", "a work plane H scene units above the floor (the scene bounds' minimum along --up), e.g. "
                          "0.75 (m) for desks");
    o.value("spacing", "S", "grid spacing, scene units: the work plane's cells are at most S on a side, objects get "
                            "a lattice of S; default EN 12464-1's 0.2 x 5^log10(d) m (d: the plane's longer side)");
    o.value("margin", "M", "the work plane leaves out M scene units along the walls (the scene bounds)",
            std::string("0"));
    o.value("up", "y|z", "the scene's up axis (Meshlight's scenes and glTF: y)", std::string("y"));
    o.value("object", "NAME", "points on the faces of the mesh(es) named NAME, with their normals; repeatable");
    o.value("facing", "all|up", "--object: all faces, or only those within 60 degrees of up (a desk's top)",
            std::string("all"));
    o.value("grid-file", "FILE.csv", "points from a CSV file: x,y,z,nx,ny,nz and an optional surface column");
    o.value("inside", "skip|keep", "work plane and object points inside solid objects (a ray straight up meets the "
                                   "back of a face first): left out of the grid and the statistics, or kept",
            std::string("skip"));
    o.value("units", "mm|cm|m", "the scene's length unit, for the default spacing, the report and the lights' flux "
                                "(lux does not depend on it); default the scene's own: mm for cornell, m otherwise");
    o.value("out", "FILE.csv", "lux at every point: surface,x,y,z,nx,ny,nz,lux,lux_direct,lux_indirect");
    o.value("summary", "FILE.csv", "per surface: points, average, minimum, maximum, U0 = Emin/Eavg, Emin/Emax");
    o.value("report", "FILE.html", "a one-page HTML report: plan view, statistics, luminaires, settings");
    declarePhotometryOption(o);
    // A designer's run ends in seconds by default (probe refines until converged).
    declareSensorOptions(o, std::string("20"));
    if (!o.parseOrPrintHelp(args)) return 0;

    // Every option and input is checked before any work.
    const std::vector<std::string> objects = repeatedValues(args, "object");
    if (!o.has("plane") && objects.empty() && !o.has("grid-file"))
        throw InputError("grid needs a surface: --plane H, --object NAME or --grid-file FILE.csv");
    std::vector<std::string> outputs;
    for (const char* name : {"out", "summary", "report"})
        if (o.has(name)) {
            const std::string path = o.str(name);
            checkOutputDirectory(path);
            for (const std::string& other : outputs)
                if (std::filesystem::weakly_canonical(other) == std::filesystem::weakly_canonical(path))
                    throw InputError(concat("--", name, " ", path, " is already another output"));
            outputs.push_back(path);
        }
    const std::string facing = o.str("facing"), inside = o.str("inside");
    if (facing != "all" && facing != "up") throw InputError(concat("--facing '", facing, "': expected all or up"));
    if (inside != "skip" && inside != "keep") throw InputError(concat("--inside '", inside, "': expected skip or keep"));
    const UpAxis up = parseUpAxis(o.str("up"));
    const std::string sceneArg = o.positionalValue("scene");
    std::optional<LengthUnit> givenUnit;
    if (o.has("units")) givenUnit = parseLengthUnit(o.str("units"));
    WorkPlaneSettings plane;
    plane.up = up;
    plane.margin = o.number("margin", 0, 1e12);
    if (o.has("plane")) plane.height = o.number("plane", 0, 1e12);
    std::optional<double> spacing;
    if (o.has("spacing")) spacing = o.number("spacing", 1e-9, 1e12);
    SensorSettings settings = readSensorSettings(o, args);
    const Photometry photometry = readPhotometryOption(o);
    std::vector<CalculationSurface> surfaces;
    if (o.has("grid-file")) surfaces = fileSurfaces(o.str("grid-file"));
    const Scene scene = loadScene(o);
    for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    if (scene.bounds.empty()) throw InputError(concat("scene '", scene.name, "' has no triangles"));
    const auto [unitLabel, metres] = sceneUnit(givenUnit, scene);
    const char* unitName = unitLabel.c_str();

    // The surfaces: the work plane first, then the objects, then the file's.
    std::vector<CalculationSurface> made;
    if (o.has("plane")) {
        const Vec3 extent = scene.bounds.extent();
        const double longer = std::max(extent.x, up == UpAxis::Y ? extent.z : extent.y) - 2 * plane.margin;
        plane.spacing = spacing ? *spacing : en12464Spacing(longer * metres) / metres;
        made.push_back(workPlane(scene.bounds, plane));
    }
    const double objectSpacing = spacing ? *spacing : en12464Spacing(1.0) / metres;  // 0.2 m
    for (const std::string& name : objects)
        made.push_back(namedObject(scene, name, objectSpacing,
                                   facing == "up" ? std::optional<Vec3>(upVector(up)) : std::nullopt));
    if (inside == "skip" && !made.empty()) {
        const EmbreeScene rays(scene);
        for (CalculationSurface& s : made) skipPointsInsideSolids(s, rays, upVector(up));
    }
    surfaces.insert(surfaces.begin(), std::make_move_iterator(made.begin()), std::make_move_iterator(made.end()));
    std::vector<SensorPoint> points;
    std::vector<size_t> surfaceOf;
    for (size_t k = 0; k < surfaces.size(); ++k) {
        if (surfaces[k].points.empty())
            throw InputError(concat("surface '", surfaces[k].name, "' has no point outside solid objects (",
                                    surfaces[k].skipped, " inside; --inside keep keeps them)"));
        points.insert(points.end(), surfaces[k].points.begin(), surfaces[k].points.end());
        surfaceOf.insert(surfaceOf.end(), surfaces[k].points.size(), k);
    }
    for (const CalculationSurface& s : surfaces) {
        std::printf("surface %s: %zu points", s.name.c_str(), s.points.size());
        if (s.grid)
            std::printf(" (%d x %d cells of %.4g x %.4g %s at %.4g %s above the floor)", s.grid->columns,
                        s.grid->rows, s.grid->cellU, s.grid->cellV, unitName, plane.height, unitName);
        if (s.skipped) std::printf(", %zu more inside solid objects left out", s.skipped);
        std::printf("\n");
    }

    // From here on, the first Ctrl-C ends the work under way and writes what is done.
    const InterruptGuard interrupt;
    const SensorReadings readings = measureSensors(scene, settings, points, "grid", &interrupt);
    const size_t done = readings.values.size();

    // Lux at every point evaluated; NaN where the run was cut short.
    std::vector<double> lux(points.size(), std::nan("")), luxDirect(points.size()), luxIndirect(points.size());
    for (size_t i = 0; i < done; ++i) {
        const SensorValue& v = readings.values[i];
        luxDirect[i] = photometry.luminous(v.direct);
        luxIndirect[i] = readings.indirect ? photometry.luminous(v.indirect) : 0.0;
        lux[i] = luxDirect[i] + luxIndirect[i];
    }
    std::vector<GridReportSurface> table;
    std::ostringstream summary;
    summary.precision(9);
    summary << "surface,points,skipped,E_avg,E_min,E_max,U0,Emin_Emax\n";
    std::printf("%-16s %8s %12s %12s %12s %7s %9s\n", "surface", "points", "Eavg (lx)", "Emin (lx)", "Emax (lx)",
                "U0", "Emin/Emax");
    for (size_t k = 0, first = 0; k < surfaces.size(); first += surfaces[k].points.size(), ++k) {
        std::vector<double> values;
        for (size_t i = first; i < first + surfaces[k].points.size() && i < done; ++i) values.push_back(lux[i]);
        const IlluminanceStatistics st = illuminanceStatistics(values);
        table.push_back({surfaces[k].name, st, surfaces[k].skipped});
        std::printf("%-16s %8zu %12.4g %12.4g %12.4g %7s %9s\n", surfaces[k].name.c_str(), st.points, st.average,
                    st.minimum, st.maximum, fixed(st.uniformity(), 3).c_str(), fixed(st.diversity(), 3).c_str());
        summary << surfaces[k].name << "," << st.points << "," << surfaces[k].skipped << "," << st.average << ","
                << st.minimum << "," << st.maximum << "," << st.uniformity() << "," << st.diversity() << "\n";
    }

    if (o.has("out")) {
        std::ostringstream csv;
        csv.precision(9);
        csv << "surface,x,y,z,nx,ny,nz,lux,lux_direct,lux_indirect\n";
        for (size_t i = 0; i < done; ++i) {
            const SensorPoint& p = points[i];
            csv << surfaces[surfaceOf[i]].name << "," << p.position.x << "," << p.position.y << "," << p.position.z
                << "," << p.normal.x << "," << p.normal.y << "," << p.normal.z << "," << lux[i] << ","
                << luxDirect[i] << "," << luxIndirect[i] << "\n";
        }
        writeTextFileAtomically(o.str("out"), csv.str());
    }
    if (o.has("summary")) writeTextFileAtomically(o.str("summary"), summary.str());
    const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    if (o.has("report")) {
        GridReport report;
        report.title = concat("Illuminance: ", scene.name,
                              o.has("plane") ? concat(", work plane at ", plane.height, " ", unitName) : std::string());
        report.facts = {
            {"scene", concat(sceneArg, " (", scene.meshes.size(), " meshes, ", scene.triangleCount(), " triangles, ",
                             scene.lights.size(), scene.lights.size() == 1 ? " light)" : " lights)")},
            {"unit", concat(unitName, "; up is +", up == UpAxis::Y ? "y" : "z", "; the floor at ",
                            up == UpAxis::Y ? "y" : "z", " = ", scene.bounds.lo[axisIndex(up)])},
            {"method", settings.describe()},
            {"light computed", readings.indirect ? "direct and indirect" : "direct only"},
            {"refinement", settings.kind == SensorMethod::Cache && readings.indirect
                               ? (settings.seconds ? concat("at most ", *settings.seconds, " s") : "until converged")
                               : std::string("none (not needed by this method)")},
            {"photometry", photometry.describe()},
            {"points", concat(done, " evaluated", done < points.size() ? concat(" of ", points.size()) : "")},
            {"run", concat(localTime(), ", ", fixed(seconds, 1), " s")},
        };
        if (readings.interrupted)
            report.facts.push_back({"interrupted", concat("yes: ", readings.cut, " cut short")});
        report.surfaces = table;
        for (const auto& l : scene.lights)
            report.luminaires.emplace_back(l.name, photometry.luminous(l.power()) * metres * metres);
        if (o.has("plane")) {
            const CalculationSurface& wp = surfaces.front();
            const PlaneGrid& g = *wp.grid;
            const std::vector<double> wpLux(lux.begin(), lux.begin() + std::ptrdiff_t(wp.points.size()));
            report.planPngBase64 = pngBase64(planViewImage(g, wpLux, up == UpAxis::Z));
            const char* vName = up == UpAxis::Y ? "z" : "y";
            const double u0 = g.corner.x, u1 = u0 + g.cellU * g.columns;
            const double v0 = glm::dot(g.corner, g.v), v1 = v0 + g.cellV * g.rows;
            report.planCaption = concat(
                "Seen from above: x from ", u0, " to ", u1, " ", unitName, " left to right, ", vName, " from ",
                up == UpAxis::Y ? v0 : v1, " to ", up == UpAxis::Y ? v1 : v0, " ", unitName, " top to bottom (",
                g.columns, " x ", g.rows, " cells of ", fixed(g.cellU, 3), " x ", fixed(g.cellV, 3), " ", unitName,
                ", margin ", plane.margin, " ", unitName, "). Lux interpolated between the cells' centres on a log "
                "scale; black lines at the 1-2-5 iso-lux levels; dark grey: outside the plane",
                wp.skipped ? " or inside solid objects." : ".");
        }
        report.notes.push_back(
            "EN 12464-1 quantities: Ē the mean illuminance over the points (equal cells), Emin and Emax the "
            "extremes, U0 = Emin/Ē the uniformity. Illuminance on each surface's front side, lux from W/m² by the "
            "photometry above; luminous flux from each light's emitted power.");
        if (inside == "skip")
            report.notes.push_back("Points inside solid objects (a ray straight up meets the back of a face first, "
                                   "e.g. inside a cabinet) are left out of the grid and the statistics.");
        writeTextFileAtomically(o.str("report"), gridReportHtml(report));
    }
    std::string wrote;
    for (const std::string& f : outputs) wrote += (wrote.empty() ? "" : ", ") + f;
    std::printf("%zu points, %zu lights, %s; %.1f s%s%s\n", done, scene.lights.size(), settings.describe().c_str(),
                seconds, wrote.empty() ? "" : "; wrote ", wrote.c_str());
    if (readings.interrupted) {
        std::fprintf(stderr, "meshlight: interrupted (%s): wrote %s (%zu of %zu points)\n", readings.cut.c_str(),
                     wrote.empty() ? "nothing" : wrote.c_str(), done, points.size());
        return 130;
    }
    return 0;
}

}  // namespace ml
