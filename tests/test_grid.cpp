// Calculation surfaces (`meshlight grid`): the statistics and the grids
// against hand-computed values, a uniformly lit plane's U0 of 1, grid
// points that agree with `probe` at the same points, bad input refused,
// the one-file report; and `probe` and `grid` interrupted by a signal
// write what is done and exit 130.
#include "CsvColumn.h"
#include "ChildProcess.h"
#include "RunCommand.h"
#include "TempDirTest.h"
#include "TestScenes.h"
#include "core/Error.h"
#include "viewer/cli/CalculationSurface.h"

#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace fs = std::filesystem;
using namespace ml;
using test::CommandResult;
using test::csvColumn;
using test::runMeshlight;

namespace {

using Clock = std::chrono::steady_clock;

std::string readFile(const std::string& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// Data rows of a CSV file (lines after the header).
int dataRows(const std::string& path) {
    std::ifstream in(path);
    int n = -1;
    for (std::string line; std::getline(in, line);) n += !line.empty();
    return n;
}

// A scene with two lamps (lamp#0, lamp#1) over a 2 × 2 floor: OBJ and MTL.
const char* kMtl = "newmtl lamp\nKd 0 0 0\nKe 5 5 5\nnewmtl white\nKd 0.5 0.5 0.5\n";
const char* kTwoLampsObj =
    "mtllib scene.mtl\n"
    "o floor\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nusemtl white\nf 1 4 3 2\n"
    "o lamps\nv -0.6 2 -0.2\nv -0.2 2 -0.2\nv -0.2 2 0.2\nv -0.6 2 0.2\n"
    "v 0.2 2 -0.2\nv 0.6 2 -0.2\nv 0.6 2 0.2\nv 0.2 2 0.2\n"
    "usemtl lamp\nf 5 6 7 8\nf 9 10 11 12\n";

}  // namespace

// --- Statistics and surfaces, as pure functions ----------------------------

TEST(GridStatistics, HandComputedValues) {
    // Mean (100 + 200 + 300 + 400) / 4 = 250; U0 = 100 / 250; Emin/Emax = 100 / 400.
    const IlluminanceStatistics s = illuminanceStatistics({300, 100, 400, 200});
    EXPECT_EQ(s.points, 4u);
    EXPECT_DOUBLE_EQ(s.average, 250);
    EXPECT_DOUBLE_EQ(s.minimum, 100);
    EXPECT_DOUBLE_EQ(s.maximum, 400);
    EXPECT_DOUBLE_EQ(s.uniformity(), 0.4);
    EXPECT_DOUBLE_EQ(s.diversity(), 0.25);
}

TEST(GridStatistics, UniformValuesGiveU0One) {
    const IlluminanceStatistics s = illuminanceStatistics(std::vector<double>(12, 500.0));
    EXPECT_DOUBLE_EQ(s.uniformity(), 1.0);
    EXPECT_DOUBLE_EQ(s.diversity(), 1.0);
    EXPECT_DOUBLE_EQ(s.average, 500.0);
}

TEST(GridStatistics, UnlitOrEmptyHasNoUniformity) {
    EXPECT_TRUE(std::isnan(illuminanceStatistics({0, 0}).uniformity()));
    EXPECT_TRUE(std::isnan(illuminanceStatistics({}).uniformity()));
    EXPECT_EQ(illuminanceStatistics({}).points, 0u);
}

TEST(GridSurface, En12464Spacing) {
    EXPECT_NEAR(en12464Spacing(10), 1.0, 1e-12);   // 0.2 × 5^1
    EXPECT_NEAR(en12464Spacing(1), 0.2, 1e-12);    // 0.2 × 5^0
    EXPECT_NEAR(en12464Spacing(100), 5.0, 1e-12);  // 0.2 × 5^2
}

TEST(GridSurface, WorkPlaneCellsAndCentres) {
    Bounds3 room;
    room.extend(Vec3(0, 0, 0));
    room.extend(Vec3(4, 3, 2));
    WorkPlaneSettings s;
    s.height = 0.75;
    s.margin = 0.5;
    s.spacing = 1;
    // 3 × 1 free area: 3 cells of 1 × 1, centres at x = 1, 2, 3, z = 1.
    CalculationSurface plane = workPlane(room, s);
    ASSERT_TRUE(plane.grid);
    EXPECT_EQ(plane.grid->columns, 3);
    EXPECT_EQ(plane.grid->rows, 1);
    ASSERT_EQ(plane.points.size(), 3u);
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(plane.points[size_t(k)].position.x, 1.0 + k, 1e-12);
        EXPECT_NEAR(plane.points[size_t(k)].position.y, 0.75, 1e-12);
        EXPECT_NEAR(plane.points[size_t(k)].position.z, 1.0, 1e-12);
        EXPECT_EQ(plane.points[size_t(k)].normal, Vec3(0, 1, 0));
    }
    // Spacing 0.4: ceil(3 / 0.4) = 8 cells of 0.375 along x, ceil(1 / 0.4) = 3 of 1/3 along z.
    s.spacing = 0.4;
    plane = workPlane(room, s);
    EXPECT_EQ(plane.grid->columns, 8);
    EXPECT_EQ(plane.grid->rows, 3);
    EXPECT_NEAR(plane.grid->cellU, 0.375, 1e-12);
    EXPECT_NEAR(plane.points.front().position.x, 0.5 + 0.1875, 1e-12);
    EXPECT_NEAR(plane.points.front().position.z, 0.5 + 1.0 / 6, 1e-12);
    // z up: columns along x, rows along y, the plane at z = 0.75.
    s.up = UpAxis::Z;
    s.spacing = 1;
    s.margin = 0;
    plane = workPlane(room, s);
    EXPECT_EQ(plane.grid->columns, 4);
    EXPECT_EQ(plane.grid->rows, 3);
    EXPECT_NEAR(plane.points.front().position.z, 0.75, 1e-12);
    EXPECT_EQ(plane.points.front().normal, Vec3(0, 0, 1));
    // Refused: above the scene, a margin that leaves nothing.
    s.up = UpAxis::Y;
    s.height = 3.5;
    EXPECT_THROW(workPlane(room, s), InputError);
    s.height = 1;
    s.margin = 1;
    EXPECT_THROW(workPlane(room, s), InputError);
}

TEST(GridSurface, ObjectQuadGetsOneRegularLattice) {
    // A 1 × 1 quad of two triangles facing up: a 0.25 lattice puts 4 × 4
    // points on it, each once (none on the diagonal twice), facing up.
    const Mesh quad = test::quadMesh("desk", 0, Vec3(0, 0.7, 0), test::kZ, test::kX);
    const CalculationSurface s = objectSurface(quad, 0.25, std::nullopt);
    ASSERT_EQ(s.points.size(), 16u);
    std::set<std::pair<long, long>> cells;
    for (const SensorPoint& p : s.points) {
        EXPECT_NEAR(p.position.y, 0.7, 1e-12);
        EXPECT_NEAR(p.normal.y, 1.0, 1e-12);
        EXPECT_GT(p.position.x, 0);
        EXPECT_LT(p.position.x, 1);
        cells.insert({std::lround(p.position.x * 8), std::lround(p.position.z * 8)});
    }
    EXPECT_EQ(cells.size(), 16u);
    // A wall facing +x has no face within 60° of up.
    const Mesh wall = test::quadMesh("wall", 0, Vec3(0, 0, 0), test::kY, test::kZ);
    EXPECT_EQ(objectSurface(wall, 0.25, std::nullopt).points.size(), 16u);
    EXPECT_THROW(objectSurface(wall, 0.25, Vec3(0, 1, 0)), InputError);
}

// --- The command ------------------------------------------------------------

using Grid = test::TempDirTest;

// A plane 1 unit over the floor, 2 × 2 in the middle of a 200 × 200 room
// whose whole ceiling glows: the illuminance varies by (1/99)² at most
// over it, so U0 is 1 to well within 0.1%.
TEST_F(Grid, UniformlyLitPlaneHasU0One) {
    write("scene.mtl", kMtl);
    write("scene.obj",
          "mtllib scene.mtl\n"
          "v -100 0 -100\nv 100 0 -100\nv 100 0 100\nv -100 0 100\n"
          "v -100 100 -100\nv 100 100 -100\nv 100 100 100\nv -100 100 100\n"
          "usemtl white\nf 1 4 3 2\nusemtl lamp\nf 5 6 7 8\n");
    const CommandResult r = runMeshlight("grid " + path("scene.obj") + " --plane 1 --margin 99 --spacing 0.5 "
                                         "--method exact --direct-only --summary " + path("s.csv"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(csvColumn(path("s.csv"), 0, "points"), 16);
    EXPECT_NEAR(csvColumn(path("s.csv"), 0, "U0"), 1.0, 1e-3);
    EXPECT_NEAR(csvColumn(path("s.csv"), 0, "Emin_Emax"), 1.0, 1e-3);
    EXPECT_GT(csvColumn(path("s.csv"), 0, "E_avg"), 0);
}

// Light off a mirror: a lamp 0.5 over a grey floor faces up, under a mirror
// ceiling at 1 (reflectance 0.9); a second lamp in a corner faces down.
// Where the points are, most of the floor's light is the first lamp's image
// in the mirror (a caustic: the photons) and that light reflected again by
// the floor and the mirror (bounce 1 reflects the caustic mesh). probe's
// cache method adds both, as render does; the path tracer finds the same
// light by sampling directions. Before the caustics were added, probe read
// 9.8, 4.5 and 2.7 lux where the path tracer reads 33, 27 and 22.
// Tolerance: 4 of the path tracer's standard errors (it reaches the small
// image by chance: about 1.2% at 10⁶ paths) and 6% for the photons' kernel
// and noise and the cache's gathers (measured: −0.8%, +1.2%, −1.6%).
TEST_F(Grid, ProbeCountsLightOffAMirror) {
    write("scene.mtl", "newmtl lamp\nKd 0 0 0\nKe 10 10 10\nnewmtl white\nKd 0.5 0.5 0.5\n"
                       "newmtl mirror\nKd 0 0 0\nKs 0.9 0.9 0.9\nillum 5\n");
    write("scene.obj",
          "mtllib scene.mtl\n"
          "o floor\nv -1.5 0 -1.5\nv -1.5 0 1.5\nv 1.5 0 1.5\nv 1.5 0 -1.5\nusemtl white\nf 1 2 3 4\n"
          "o lamp\nv -0.1 0.5 -0.1\nv -0.1 0.5 0.1\nv 0.1 0.5 0.1\nv 0.1 0.5 -0.1\nusemtl lamp\nf 5 6 7 8\n"
          "o mirror\nv -1.5 1 -1.5\nv 1.5 1 -1.5\nv 1.5 1 1.5\nv -1.5 1 1.5\nusemtl mirror\nf 9 10 11 12\n"
          "o down\nv 1 0.5 1\nv 1.2 0.5 1\nv 1.2 0.5 1.2\nv 1 0.5 1.2\nusemtl lamp\nf 13 14 15 16\n");
    write("points.csv", "x,y,z,nx,ny,nz\n0.6,0,0,0,1,0\n-0.5,0,0.4,0,1,0\n0.2,0,-0.8,0,1,0\n");
    CommandResult r = runMeshlight("probe " + path("scene.obj") + " --method exact --time 6 --points " +
                                   path("points.csv") + " --out " + path("c.csv"));
    ASSERT_EQ(r.status, 0) << r.output;
    r = runMeshlight("probe " + path("scene.obj") + " --method path --spp 1000000 --points " + path("points.csv") +
                     " --out " + path("p.csv"));
    ASSERT_EQ(r.status, 0) << r.output;
    for (int i = 0; i < 3; ++i) {
        const double cache = csvColumn(path("c.csv"), i, "lux"), traced = csvColumn(path("p.csv"), i, "lux");
        const double se = traced *
                          std::hypot(csvColumn(path("p.csv"), i, "E_se_g"), csvColumn(path("p.csv"), i, "E_indirect_se_g")) /
                          (csvColumn(path("p.csv"), i, "E_g") + csvColumn(path("p.csv"), i, "E_indirect_g"));
        std::printf("point %d: cache %.2f lux, path tracer %.2f ± %.2f lux (%+.2f%%)\n", i, cache, traced, se,
                    100 * (cache / traced - 1));
        EXPECT_NEAR(cache, traced, 4 * se + 0.06 * traced) << "point " << i;
    }
}

// The Cornell floor as an object: grid's lux at its points is probe's at
// the same points (same method, same numbers); the points under the two
// blocks are inside them and left out.
TEST_F(Grid, CornellFloorAgreesWithProbe) {
    CommandResult r = runMeshlight("grid cornell --object floor --spacing 100 --method exact --direct-only --out " +
                                   path("g.csv"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("inside solid objects left out"), std::string::npos) << r.output;
    const int n = dataRows(path("g.csv"));
    ASSERT_GE(n, 20);
    std::ostringstream points;
    points << "x,y,z,nx,ny,nz\n";
    points.precision(17);
    for (int i = 0; i < n; ++i) {
        for (const char* c : {"x", "y", "z", "nx", "ny"}) points << csvColumn(path("g.csv"), i, c) << ",";
        points << csvColumn(path("g.csv"), i, "nz") << "\n";
    }
    write("points.csv", points.str());
    r = runMeshlight("probe cornell --method exact --direct-only --points " + path("points.csv") + " --out " +
                     path("p.csv"));
    ASSERT_EQ(r.status, 0) << r.output;
    ASSERT_EQ(dataRows(path("p.csv")), n);
    int lit = 0;
    for (int i = 0; i < n; ++i) {
        const double probe = csvColumn(path("p.csv"), i, "lux");
        EXPECT_NEAR(csvColumn(path("g.csv"), i, "lux"), probe, 1e-6 * probe + 1e-9) << "point " << i;
        EXPECT_EQ(csvColumn(path("g.csv"), i, "lux_indirect"), 0);
        lit += probe > 1;
    }
    EXPECT_GT(lit, n / 2);
}

TEST_F(Grid, BadInputIsRefusedWithNoOutput) {
    write("scene.mtl", kMtl);
    write("scene.obj", kTwoLampsObj);
    write("bad.csv", "x,y,z,nx,ny,nz\n0,0.5,0,0,1,0\n0,abc,0,0,1,0\n");
    write("header.csv", "x,y,z,nx,ny\n0,0.5,0,0,1\n");
    const std::string outputs =
        " --out " + path("o.csv") + " --summary " + path("s.csv") + " --report " + path("r.html");
    const std::string scene = "grid " + path("scene.obj") + " --method exact --direct-only";
    struct Case {
        std::string args, expected;
    };
    const std::vector<Case> cases = {
        {" --grid-file " + path("bad.csv"), "bad.csv:3: column y: 'abc' is not a finite number"},
        {" --grid-file " + path("header.csv"), "header.csv:1: the header must be"},
        {" --grid-file " + path("missing.csv"), "missing.csv: cannot open"},
        {" --object table", "no mesh named 'table'"},
        {"", "grid needs a surface"},
        {" --plane 5", "--plane 5 is outside the scene"},
        {" --plane 0.5 --margin 3", "leaves no work plane"},
        {" --plane 0.5 --up x", "unknown up axis 'x'"},
        {" --plane 0.5 --spacing 0", "spacing"},
        {" --plane 0.5 --spp 10", "does not apply to --method exact"},
    };
    for (const Case& c : cases) {
        const CommandResult r = runMeshlight(scene + c.args + outputs);
        EXPECT_EQ(r.status, 2) << c.args << "\n" << r.output;
        EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << "\n" << r.output;
    }
    EXPECT_EQ(files(), 4u);  // obj, mtl and the two bad grid files
}

TEST_F(Grid, ReportIsOneHtmlFileNamingEveryLight) {
    write("scene.mtl", kMtl);
    write("scene.obj", kTwoLampsObj);
    write("pts.csv", "x,y,z,nx,ny,nz,surface\n0,1,0,0,1,0,middle\n0.5,1,0.5,0,1,0,middle\n0,0.5,0,0,1,0,low\n");
    const CommandResult r =
        runMeshlight("grid " + path("scene.obj") + " --plane 0.5 --spacing 0.25 --object floor --grid-file " +
                     path("pts.csv") + " --method exact --direct-only --out " + path("o.csv") + " --summary " +
                     path("s.csv") + " --report " + path("r.html"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(files(), 6u);  // obj, mtl, pts and the three outputs: the report is one file
    const std::string html = readFile(path("r.html"));
    EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_NE(html.find("</html>"), std::string::npos);
    EXPECT_NE(html.find("src=\"data:image/png;base64,iVBORw0KGgo"), std::string::npos);  // the PNG signature
    for (const char* light : {"lamp#0", "lamp#1"}) EXPECT_NE(html.find(light), std::string::npos) << light;
    for (const char* surface : {"workplane", "floor", "middle", "low"})
        EXPECT_NE(html.find(surface), std::string::npos) << surface;
    // The summary: one row per surface, in order; the grid 2 x 2 floor less nothing: 8 x 8 cells.
    EXPECT_EQ(dataRows(path("s.csv")), 4);
    EXPECT_EQ(csvColumn(path("s.csv"), 0, "points"), 64);
    EXPECT_EQ(csvColumn(path("s.csv"), 2, "points"), 2);
    EXPECT_EQ(dataRows(path("o.csv")), 64 + int(csvColumn(path("s.csv"), 1, "points")) + 3);
    // Lux in o.csv is its direct and indirect parts.
    EXPECT_NEAR(csvColumn(path("o.csv"), 0, "lux"), csvColumn(path("o.csv"), 0, "lux_direct"), 1e-9);
}

// --- Interrupts (the pattern of test_interrupt.cpp) -------------------------

namespace {

using Child = test::ChildProcess;
using test::sleepFor;

class GridInterrupt : public test::TempDirTest {
protected:
    // 40 points on the Cornell floor: a CSV for probe.
    std::string floorPoints() const {
        std::ostringstream csv;
        csv << "x,y,z,nx,ny,nz\n";
        for (int i = 0; i < 40; ++i) csv << 100 + 10 * i << ",0," << 400 << ",0,1,0\n";
        return write("points.csv", csv.str());
    }
    std::vector<std::string> temporaries() const {
        std::vector<std::string> found;
        for (const auto& e : fs::directory_iterator(path("")))
            if (e.path().filename().string().find(".tmp-") != std::string::npos)
                found.push_back(e.path().filename().string());
        return found;
    }
};

}  // namespace

// The path tracer at 2 million samples a point takes seconds a point: a
// signal ends the run after the point under way, and the rows done are written.
TEST_F(GridInterrupt, ProbeWritesThePointsDone) {
    Child probe({"probe", "cornell", "--method", "path", "--spp", "2000000", "--threads", "2", "--points",
                 floorPoints(), "--out", path("o.csv")},
                path("log.txt"));
    sleepFor(2);
    probe.signal(SIGINT);
    ASSERT_EQ(probe.wait(30), 130) << probe.output();
    EXPECT_NE(probe.output().find("interrupted (the points): wrote " + path("o.csv")), std::string::npos)
        << probe.output();
    const int rows = dataRows(path("o.csv"));
    EXPECT_GE(rows, 1);
    EXPECT_LT(rows, 40);
    EXPECT_GT(csvColumn(path("o.csv"), 0, "lux"), 0);
    EXPECT_TRUE(temporaries().empty());
}

// With the caches' methods, a signal during refinement ends it and every
// point is evaluated from what is cached.
TEST_F(GridInterrupt, ProbeEndsRefinementAndEvaluatesEveryPoint) {
    Child probe({"probe", "cornell", "--points", floorPoints(), "--out", path("o.csv")}, path("log.txt"));
    sleepFor(3);
    probe.signal(SIGTERM);
    ASSERT_EQ(probe.wait(60), 130) << probe.output();
    EXPECT_NE(probe.output().find("interrupted (refinement after"), std::string::npos) << probe.output();
    EXPECT_EQ(dataRows(path("o.csv")), 40);
    EXPECT_GT(csvColumn(path("o.csv"), 0, "lux_indirect"), 0);
}

TEST_F(GridInterrupt, GridWritesThePointsDoneAndTheirSummary) {
    Child grid({"grid", "cornell", "--object", "floor", "--spacing", "50", "--method", "path", "--spp", "2000000",
                "--threads", "2", "--out", path("o.csv"), "--summary", path("s.csv"), "--report", path("r.html")},
               path("log.txt"));
    sleepFor(2);
    grid.signal(SIGINT);
    ASSERT_EQ(grid.wait(30), 130) << grid.output();
    const int rows = dataRows(path("o.csv"));
    EXPECT_GE(rows, 1);
    EXPECT_EQ(csvColumn(path("s.csv"), 0, "points"), rows);
    EXPECT_NE(readFile(path("r.html")).find("cut short"), std::string::npos);
    EXPECT_TRUE(temporaries().empty());
}

TEST_F(GridInterrupt, SecondSignalExitsAtOnceAndLeavesNoPartialFile) {
    Child probe({"probe", "cornell", "--method", "path", "--spp", "16000000", "--threads", "2", "--points",
                 floorPoints(), "--out", path("o.csv")},
                path("log.txt"));
    sleepFor(1.5);
    probe.signal(SIGINT);
    sleepFor(0.4);  // later than InterruptGuard::kSecondSignalSeconds: a second request
    const auto second = Clock::now();
    probe.signal(SIGINT);
    ASSERT_EQ(probe.wait(30), 130) << probe.output();
    EXPECT_LT(std::chrono::duration<double>(Clock::now() - second).count(), 1.0) << probe.output();
    EXPECT_TRUE(temporaries().empty());
    EXPECT_EQ(probe.output().find("interrupted (the points): wrote"), std::string::npos) << probe.output();
    EXPECT_FALSE(fs::exists(path("o.csv")));  // the point under way takes seconds: nothing was written
}
