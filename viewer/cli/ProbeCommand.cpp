// meshlight probe: irradiance at sensor points (RADIANCE's `rtrace -I`),
// what lighting designers check: direct light per light, indirect light,
// and the illuminance in lux. Points come from a CSV file, or, with
// `--points -`, as RADIANCE's rtrace reads them: "x y z dx dy dz" lines on
// standard input. The irradiance itself comes from SensorIrradiance.h,
// shared with `grid`; this file writes probe's CSV.
#include "Commands.h"
#include "PhotometryOptions.h"
#include "SensorIrradiance.h"
#include "core/Error.h"
#include "core/io/AtomicFile.h"
#include "core/io/InterruptGuard.h"

#include <cctype>
#include <cstdio>
#include <iostream>
#include <sstream>

namespace ml {

namespace {

// `--points -`: RADIANCE's format on standard input; else a CSV file.
std::vector<SensorPoint> readPoints(const std::string& path) {
    return path == "-" ? readRadiancePoints(std::cin, "<stdin>") : readSensorCsv(path);
}

// Light names as CSV column names: letters, digits and '_' only.
std::string columnName(const std::string& name) {
    std::string s;
    for (char c : name) s += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    return s;
}

std::string csvHeader(const Scene& scene) {
    std::string h = "x,y,z,nx,ny,nz";
    for (const auto& l : scene.lights) {
        const std::string c = columnName(l.name);
        h += ",E_" + c + "_r,E_" + c + "_g,E_" + c + "_b";
    }
    return h + ",E_r,E_g,E_b";
}

void csvRgb(std::ostringstream& csv, const Rgb& c) { csv << "," << c.r << "," << c.g << "," << c.b; }

// The lux columns: "lux", the illuminance of all the light computed, and
// with indirect light "lux_indirect", its indirect part.
const char* luxHeader(bool indirect) { return indirect ? ",lux,lux_indirect" : ",lux"; }
void csvLux(std::ostringstream& csv, const Photometry& photometry, const Rgb& direct, const Rgb* indirect) {
    csv << "," << photometry.luminous(indirect ? direct + *indirect : direct);
    if (indirect) csv << "," << photometry.luminous(*indirect);
}

void csvPoint(std::ostringstream& csv, const SensorPoint& p) {
    csv << p.position.x << "," << p.position.y << "," << p.position.z << "," << p.normal.x << "," << p.normal.y << ","
        << p.normal.z;
}

// The CSV of every method: the point, direct irradiance per light and in
// all; with --method path the standard errors and the indirect irradiance
// with its own, else the indirect irradiance when computed; lux; how.
std::string probeCsv(const Scene& scene, const SensorSettings& s, const SensorReadings& r,
                     const std::vector<SensorPoint>& points, const Photometry& photometry) {
    const bool path = s.kind == SensorMethod::Path;
    std::ostringstream csv;
    csv.precision(9);
    csv << csvHeader(scene);
    if (path)
        csv << ",E_se_r,E_se_g,E_se_b,E_indirect_r,E_indirect_g,E_indirect_b,"
            << "E_indirect_se_r,E_indirect_se_g,E_indirect_se_b";
    else if (r.indirect)
        csv << ",E_indirect_r,E_indirect_g,E_indirect_b";
    csv << luxHeader(r.indirect) << (path ? ",method,samples,max_depth,time_s\n" : ",method,samples,time_s\n");
    for (size_t i = 0; i < r.values.size(); ++i) {
        const SensorValue& v = r.values[i];
        csvPoint(csv, points[i]);
        for (const Rgb& e : v.directPerLight) csvRgb(csv, e);
        csvRgb(csv, v.direct);
        if (path) csvRgb(csv, v.directError);
        if (r.indirect) csvRgb(csv, v.indirect);
        if (path) csvRgb(csv, v.indirectError);
        csvLux(csv, photometry, v.direct, r.indirect ? &v.indirect : nullptr);
        csv << "," << s.method << "," << r.samples;
        if (path) csv << "," << s.path.maxDepth;
        csv << "," << v.seconds << "\n";
    }
    return csv.str();
}

// --method path: the mean relative standard error of the total irradiance.
void printPathError(const SensorReadings& r) {
    double relative = 0;
    size_t lit = 0;
    for (const SensorValue& v : r.values) {
        const Rgb total = v.direct + v.indirect;
        if (luminance(total) > 0) {
            relative += luminance(glm::sqrt(v.directError * v.directError + v.indirectError * v.indirectError)) /
                        luminance(total);
            ++lit;
        }
    }
    if (lit) std::printf("mean relative standard error of the total irradiance: %.3g %% over %zu lit points\n",
                         100 * relative / double(lit), lit);
}

}  // namespace

int runProbe(const std::vector<std::string>& args) {
    Options o("probe");
    declareSceneOptions(o);
    o.value("points", "IN.csv|-", "sensor points: a CSV file with columns x,y,z,nx,ny,nz, or - for RADIANCE's rtrace "
                                  "input on standard input: lines of x y z dx dy dz ('#' comments)");
    o.value("out", "OUT.csv", "irradiance per light and in total (RGB, W/m²), and illuminance: lux (all the light "
                              "computed) and lux_indirect (its indirect part, when indirect light is computed)");
    declarePhotometryOption(o);
    declareSensorOptions(o);
    if (!o.parseOrPrintHelp(args)) return 0;
    const std::string out = o.str("out");
    checkOutputDirectory(out);
    SensorSettings settings = readSensorSettings(o, args);
    const Photometry photometry = readPhotometryOption(o);
    const std::vector<SensorPoint> points = readPoints(o.str("points"));
    const Scene scene = loadScene(o);
    for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());

    // From here on, the first Ctrl-C ends the work under way and writes what is done.
    const InterruptGuard interrupt;
    const SensorReadings readings = measureSensors(scene, settings, points, "probe", &interrupt);
    writeTextFileAtomically(out, probeCsv(scene, settings, readings, points, photometry));
    std::printf("wrote %s (%zu points, %zu lights, %s)\n", out.c_str(), readings.values.size(), scene.lights.size(),
                settings.describe().c_str());
    if (settings.kind == SensorMethod::Path) printPathError(readings);
    if (readings.interrupted) {
        std::fprintf(stderr, "meshlight: interrupted (%s): wrote %s (%zu of %zu points)\n", readings.cut.c_str(),
                     out.c_str(), readings.values.size(), points.size());
        return 130;
    }
    return 0;
}

}  // namespace ml
