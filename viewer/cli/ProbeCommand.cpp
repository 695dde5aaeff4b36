// meshlight probe: direct irradiance at sensor points (RADIANCE's
// `rtrace -I`), what lighting designers check.
#include "Commands.h"
#include "DirectSetup.h"
#include "Progress.h"
#include "core/Error.h"
#include "core/Random.h"
#include "core/io/AtomicFile.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace ml {

namespace {

struct SensorPoint {
    Vec3 position, normal;
};

std::vector<std::string> splitCsv(const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) {
        const size_t a = cell.find_first_not_of(" \t\r"), b = cell.find_last_not_of(" \t\r");
        cells.push_back(a == std::string::npos ? std::string() : cell.substr(a, b - a + 1));
    }
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    return cells;
}

std::vector<SensorPoint> readPoints(const std::string& path) {
    std::ifstream in(path);
    if (!in) throwInputError(SourceLocation{path}, "cannot open the points file");
    std::string line;
    int lineNo = 0;
    std::vector<SensorPoint> points;
    bool header = false;
    const std::vector<std::string> expected = {"x", "y", "z", "nx", "ny", "nz"};
    while (std::getline(in, line)) {
        ++lineNo;
        if (line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t")] == '#')
            continue;
        const std::vector<std::string> cells = splitCsv(line);
        const SourceLocation at{path, lineNo};
        if (!header) {
            if (cells != expected) throwInputError(at, "the header must be x,y,z,nx,ny,nz");
            header = true;
            continue;
        }
        if (cells.size() != 6) throwInputError(at, "expected 6 values, found ", cells.size());
        double v[6];
        for (int k = 0; k < 6; ++k) {
            char* end = nullptr;
            v[k] = std::strtod(cells[size_t(k)].c_str(), &end);
            if (cells[size_t(k)].empty() || *end != '\0' || !std::isfinite(v[k]))
                throwInputError(at, "column ", expected[size_t(k)], ": '", cells[size_t(k)], "' is not a finite number");
        }
        const Vec3 n(v[3], v[4], v[5]);
        if (!(glm::length(n) > 0)) throwInputError(at, "the normal is zero");
        points.push_back({Vec3(v[0], v[1], v[2]), glm::normalize(n)});
    }
    if (!header) throwInputError(SourceLocation{path}, "empty file: expected the header x,y,z,nx,ny,nz");
    return points;
}

// Light names as CSV column names: letters, digits and '_' only.
std::string columnName(const std::string& name) {
    std::string s;
    for (char c : name) s += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    return s;
}

}  // namespace

int runProbe(const std::vector<std::string>& args) {
    Options o("probe");
    o.positional("scene", "cornell, bench or an OBJ file");
    o.value("points", "IN.csv", "sensor points: columns x,y,z,nx,ny,nz");
    o.value("out", "OUT.csv", "irradiance per light and in total (RGB, W/m²)");
    declareDirectOptions(o);
    if (!o.parseOrPrintHelp(args)) return 0;
    const std::string out = o.str("out");
    checkOutputDirectory(out);
    const DirectChoice choice = readDirectOptions(o);
    const std::vector<SensorPoint> points = readPoints(o.str("points"));
    const Scene scene = loadSceneArgument(o.positionalValue("scene"));
    for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());

    DirectEstimators estimators(scene, choice, false);
    const DirectEstimateFn estimate = estimators.estimate();

    std::ostringstream csv;
    csv.precision(9);
    csv << "x,y,z,nx,ny,nz";
    for (const AreaLight& l : scene.lights) {
        const std::string c = columnName(l.name);
        csv << ",E_" << c << "_r,E_" << c << "_g,E_" << c << "_b";
    }
    csv << ",E_r,E_g,E_b,method,samples,time_s\n";
    const std::string method = choice.exact ? std::string("exact") : directMethodName(choice.sampler.method);

    Progress progress("probe", points.size());
    for (size_t i = 0; i < points.size(); ++i) {
        const SensorPoint& p = points[i];
        const auto t0 = std::chrono::steady_clock::now();
        std::vector<Rgb> perLight(scene.lights.size(), Rgb(0.0));
        for (size_t l = 0; l < scene.lights.size(); ++l) {
            for (int k = 0; k < choice.passes; ++k)
                perLight[l] += estimate(l, p.position, p.normal, seedFor(choice.seed, uint32_t(i), uint32_t(l), uint32_t(k)));
            perLight[l] /= double(choice.passes);
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        Rgb total(0.0);
        csv << p.position.x << "," << p.position.y << "," << p.position.z << "," << p.normal.x << "," << p.normal.y
            << "," << p.normal.z;
        for (const Rgb& e : perLight) {
            csv << "," << e.r << "," << e.g << "," << e.b;
            total += e;
        }
        csv << "," << total.r << "," << total.g << "," << total.b << "," << method << ","
            << choice.passes * int(scene.lights.size()) << "," << seconds << "\n";
        progress.update(i + 1);
    }
    progress.finish();
    writeTextFileAtomically(out, csv.str());
    std::printf("wrote %s (%zu points, %zu lights, %s)\n", out.c_str(), points.size(), scene.lights.size(),
                choice.describe().c_str());
    return 0;
}

}  // namespace ml
