// The meshlight binary: bad input gets file:line, a non-zero exit and no
// output file; good input writes what it says.
#include "CsvColumn.h"
#include "RunCommand.h"
#include "TempDirTest.h"
#include "core/image/Image.h"
#include "viewer/cli/UntilErrorSchedule.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;
using ml::test::CommandResult;
using ml::test::csvColumn;
using ml::test::runMeshlight;
using namespace ml;

namespace {

using Cli = ml::test::TempDirTest;

const char* kQuadMtl = "newmtl lamp\nKd 0 0 0\nKe 5 5 5\nnewmtl white\nKd 0.5 0.5 0.5\n";
const char* kQuadObj =
    "mtllib scene.mtl\n"
    "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
    "v -0.2 2 -0.2\nv 0.2 2 -0.2\nv 0.2 2 0.2\nv -0.2 2 0.2\n"
    "usemtl white\nf 1 4 3 2\n"
    "usemtl lamp\nf 5 6 7 8\n";

}  // namespace

TEST_F(Cli, UnknownOptionIsAnErrorWithNoOutput) {
    const CommandResult r = runMeshlight("render cornell --out " + path("x.png") + " --frobnicate 3");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("unknown option '--frobnicate'"), std::string::npos) << r.output;
    EXPECT_EQ(files(), 0u);
}

TEST_F(Cli, UnknownCommandAndBadValues) {
    EXPECT_EQ(runMeshlight("paint cornell").status, 2);
    const CommandResult bits = runMeshlight("render cornell --bits 3 --out " + path("x.png"));
    EXPECT_EQ(bits.status, 2);
    EXPECT_NE(bits.output.find("bits per pixel 3"), std::string::npos) << bits.output;
    const CommandResult ext = runMeshlight("render cornell --out " + path("x.jpg"));
    EXPECT_EQ(ext.status, 2);
    EXPECT_NE(ext.output.find("unsupported output format"), std::string::npos) << ext.output;
    const CommandResult width = runMeshlight("render cornell --width abc --out " + path("x.png"));
    EXPECT_EQ(width.status, 2);
    const CommandResult outlines = runMeshlight("render cornell --outline-passes -1 --out " + path("x.png"));
    EXPECT_EQ(outlines.status, 2);
    EXPECT_NE(outlines.output.find("option --outline-passes: '-1' is not an integer in [0, 1024]"), std::string::npos)
        << outlines.output;
    const CommandResult rays = runMeshlight("render cornell --shared-rays 2.5 --out " + path("x.png"));
    EXPECT_EQ(rays.status, 2);
    EXPECT_NE(rays.output.find("--shared-rays: '2.5' is not a whole number"), std::string::npos) << rays.output;
    const CommandResult negative = runMeshlight("render cornell --shared-rays -1 --out " + path("x.png"));
    EXPECT_EQ(negative.status, 2);
    EXPECT_NE(negative.output.find("option --shared-rays: -1 is not in [0, 65536]"), std::string::npos)
        << negative.output;
    EXPECT_EQ(files(), 0u);
}

TEST_F(Cli, MalformedObjNamesFileAndLine) {
    write("scene.mtl", kQuadMtl);
    write("bad.obj", "mtllib scene.mtl\nv 0 0 0\nv 1 nan 0\nv 0 0 1\nf 1 2 3\n");
    const CommandResult r = runMeshlight("render " + path("bad.obj") + " --out " + path("out.png"));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("bad.obj:3:"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(path("out.png")));

    write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 7\n");
    const CommandResult r2 = runMeshlight("render " + path("range.obj") + " --out " + path("out.png"));
    EXPECT_EQ(r2.status, 2);
    EXPECT_NE(r2.output.find("range.obj:4:"), std::string::npos) << r2.output;

    write("nomtl.obj", "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
    const CommandResult r3 = runMeshlight("render " + path("nomtl.obj") + " --out " + path("out.png"));
    EXPECT_EQ(r3.status, 2);
    EXPECT_NE(r3.output.find("nomtl.obj:1:"), std::string::npos) << r3.output;
    EXPECT_FALSE(fs::exists(path("out.png")));
}

TEST_F(Cli, RenderWritesTheImage) {
    write("scene.mtl", kQuadMtl);
    write("scene.obj", kQuadObj);
    const CommandResult r =
        runMeshlight("render " + path("scene.obj") + " --width 32 --height 24 --cache-edge 0.1 --out " + path("a.exr"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(fs::exists(path("a.exr")));
    EXPECT_NE(r.output.find("plan:"), std::string::npos);
    EXPECT_EQ(files(), 3u);  // obj, mtl, exr: no temporary left behind
}

TEST_F(Cli, ProbeAgreesWithExactAndRejectsBadPoints) {
    write("scene.mtl", kQuadMtl);
    write("scene.obj", kQuadObj);
    write("points.csv", "x,y,z,nx,ny,nz\n0,0,0,0,1,0\n0.5,0,0.3,0,1,0\n");
    const CommandResult exact = runMeshlight("probe " + path("scene.obj") + " --points " + path("points.csv") +
                                             " --method exact --out " + path("exact.csv"));
    ASSERT_EQ(exact.status, 0) << exact.output;
    const CommandResult jit =
        runMeshlight("probe " + path("scene.obj") + " --points " + path("points.csv") + " --out " + path("jit.csv"));
    ASSERT_EQ(jit.status, 0) << jit.output;
    for (int row = 0; row < 2; ++row) {
        const double e = csvColumn(path("exact.csv"), row, "E_r");
        ASSERT_GT(e, 0);
        // Nothing occludes this lamp: the cv estimator is Lambert's value.
        EXPECT_NEAR(csvColumn(path("jit.csv"), row, "E_r"), e, 1e-6 * e);
    }

    write("bad.csv", "x,y,z,nx,ny,nz\n0,0,0,0,1,0\n1,2,inf,0,1,0\n");
    const CommandResult bad =
        runMeshlight("probe " + path("scene.obj") + " --points " + path("bad.csv") + " --out " + path("o.csv"));
    EXPECT_EQ(bad.status, 2);
    EXPECT_NE(bad.output.find("bad.csv:3:"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(path("o.csv")));
}

TEST_F(Cli, ProgressiveRenderLogsSnapshotsAndResumesFromItsCache) {
    write("scene.mtl", kQuadMtl);
    write("scene.obj", kQuadObj);
    const std::string common = path("scene.obj") + " --width 24 --height 24 --supersample 1 --cache-edge 0.25";
    // A sample budget: the run repeats exactly whatever the machine's speed.
    CommandResult r =
        runMeshlight("render " + common + " --samples 400 --every 0.01 --log " + path("log.csv") + " --snapshots " +
                     path("snaps") + " --cache " + path("scene.mlc") + " --out " + path("a.exr"));
    ASSERT_EQ(0, r.status) << r.output;
    EXPECT_TRUE(fs::exists(path("a.exr")));
    EXPECT_TRUE(fs::exists(path("scene.mlc")));
    std::ifstream log(path("log.csv"));
    std::string header, row;
    std::getline(log, header);
    EXPECT_EQ(0u, header.find("seconds,frame,rounds,vertices,samples,estimated_error")) << header;
    size_t rows = 0;
    while (std::getline(log, row)) ++rows;
    EXPECT_GE(rows, 1u);  // at least the final row
    // Resuming: the cache file is read back and refined further.
    r = runMeshlight("render " + common + " --samples 800 --cache " + path("scene.mlc") + " --out " + path("b.exr"));
    ASSERT_EQ(0, r.status) << r.output;
    EXPECT_NE(r.output.find("resumed from"), std::string::npos) << r.output;
    // A corrupt cache file is refused before any output is written, and kept.
    write("bad.mlc", "MESHLIGHT-CACHE\nnot really");
    r = runMeshlight("render " + common + " --samples 400 --cache " + path("bad.mlc") + " --out " + path("c.exr"));
    EXPECT_EQ(2, r.status) << r.output;
    EXPECT_NE(r.output.find("bad.mlc"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(path("c.exr")));
    EXPECT_TRUE(fs::exists(path("bad.mlc")));
}

TEST_F(Cli, WalkthroughWritesOneImagePerCameraAndRejectsBadPaths) {
    write("scene.mtl", kQuadMtl);
    write("scene.obj", kQuadObj);
    write("path.csv", "# px,py,pz,tx,ty,tz,ux,uy,uz,fov\n0,1,4,0,0,0,0,1,0,40\n1,1,4,0,0,0,0,1,0,40\n");
    const std::string common = path("scene.obj") + " --width 16 --height 16 --supersample 1 --cache-edge 0.25";
    CommandResult r = runMeshlight("render " + common + " --samples 300 --camera-path " + path("path.csv") + " --out " +
                                   path("view_##.png"));
    ASSERT_EQ(0, r.status) << r.output;
    EXPECT_TRUE(fs::exists(path("view_00.png")));
    EXPECT_TRUE(fs::exists(path("view_01.png")));
    // A pattern without #### would overwrite one file.
    r = runMeshlight("render " + common + " --camera-path " + path("path.csv") + " --out " + path("view.png"));
    EXPECT_EQ(2, r.status) << r.output;
    // A bad line is named with its file and line.
    write("bad.csv", "0,1,4,0,0,0,0,1,0,40\n0,1,4,0,0,0,0,1,0\n");
    r = runMeshlight("render " + common + " --camera-path " + path("bad.csv") + " --out " + path("v_#.png"));
    EXPECT_EQ(2, r.status) << r.output;
    EXPECT_NE(r.output.find("bad.csv:2"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(path("v_0.png")));
}

TEST_F(Cli, PlanPrintsWhatWouldBeSimulated) {
    const CommandResult r = runMeshlight("plan cornell");
    ASSERT_EQ(0, r.status) << r.output;
    EXPECT_NE(r.output.find("light 'light'"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("specular: no pass"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("grid cache"), std::string::npos) << r.output;
}

// --indirect-edge sets the bounce meshes' base and refuses what is not a
// fraction, with no output. Without it the ray gather's base is the mean
// free path over 7.5: the Cornell box's 4V/S is 0.367 of its diagonal
// (5 blocks' worth of faces inside a 555 mm room), so 1/20.4, printed 1/20,
// with 40 x 16/20.4 = 31 -> 31²/4 = 240 rays; the office's (0.231) gives
// less than 1/32, so 1/32 and the least 100 rays.
TEST_F(Cli, IndirectEdgeSetsTheBounceMeshesBase) {
    const CommandResult plain = runMeshlight("plan cornell");
    ASSERT_EQ(0, plain.status) << plain.output;
    EXPECT_NE(plain.output.find("indirect caches: one mesh per bounce, edges at most 1/20 of the scene (the mean "
                                "free path 4V/S over 7.5, 4V/S being 0.367 of the diagonal"),
              std::string::npos) << plain.output;
    EXPECT_NE(plain.output.find("raytrace: 240 stratified"), std::string::npos) << plain.output;
    const CommandResult office = runMeshlight("plan office");
    ASSERT_EQ(0, office.status) << office.output;
    EXPECT_NE(office.output.find("edges at most 1/32 of the scene (the mean free path"), std::string::npos)
        << office.output;
    EXPECT_NE(office.output.find("raytrace: 100 stratified"), std::string::npos) << office.output;
    // Once gathered, each base is split down to half its edge (the
    // office's 1/32 to 1/64; the Cornell box's 1/20.4 to 1/40.8).
    EXPECT_NE(office.output.find("then split down to 1/64 once gathered"), std::string::npos) << office.output;
    EXPECT_NE(plain.output.find("then split down to 1/41 once gathered"), std::string::npos) << plain.output;
    // --gather-size keeps its rays whatever base is chosen.
    const CommandResult asked = runMeshlight("plan office --gather-size 40");
    ASSERT_EQ(0, asked.status) << asked.output;
    EXPECT_NE(asked.output.find("raytrace: 400 stratified"), std::string::npos) << asked.output;
    const CommandResult fine = runMeshlight("plan cornell --indirect-edge 0.03125");
    ASSERT_EQ(0, fine.status) << fine.output;
    EXPECT_NE(fine.output.find("indirect caches: one mesh per bounce, edges at most 1/32 of the scene"),
              std::string::npos) << fine.output;
    for (const char* bad : {"0", "2", "x"}) {
        const CommandResult r = runMeshlight(concat("render cornell --indirect-edge ", bad, " --out ", path("e.png")));
        EXPECT_EQ(2, r.status) << r.output;
        EXPECT_NE(r.output.find("--indirect-edge"), std::string::npos) << r.output;
        EXPECT_FALSE(fs::exists(path("e.png")));
    }
}

// --- Lux: probe's RADIANCE-style input and lux columns, render --quantity lux ---

namespace {

// lux from a probe CSV's E_r, E_g, E_b (direct light) with the weights of a photometry.
double luxOf(const std::string& csv, int row, const Rgb& weights) {
    return 179 * (weights.r * csvColumn(csv, row, "E_r") + weights.g * csvColumn(csv, row, "E_g") +
                  weights.b * csvColumn(csv, row, "E_b"));
}

}  // namespace

TEST_F(Cli, ProbeReadsRadiancePointsFromStandardInputAndWritesLux) {
    write("scene.mtl", kQuadMtl);
    write("scene.obj", kQuadObj);
    // rtrace's input: x y z dx dy dz, any white space, '#' comments, blank lines.
    write("points.txt", "# two sensors\n\n0 0 0 0 1 0\n  0.5\t0 0.3   0 2 0  # on the desk\n");
    write("points.csv", "x,y,z,nx,ny,nz\n0,0,0,0,1,0\n0.5,0,0.3,0,1,0\n");
    const std::string probe = "probe " + path("scene.obj") + " --method exact --direct-only";
    CommandResult r = runMeshlight(probe + " --points - --out " + path("stdin.csv") + " < " + path("points.txt"));
    ASSERT_EQ(r.status, 0) << r.output;
    r = runMeshlight(probe + " --points " + path("points.csv") + " --out " + path("file.csv"));
    ASSERT_EQ(r.status, 0) << r.output;
    r = runMeshlight(probe + " --photometry rec709 --points - --out " + path("rec709.csv") + " < " +
                     path("points.txt"));
    ASSERT_EQ(r.status, 0) << r.output;
    for (int row = 0; row < 2; ++row) {
        EXPECT_EQ(csvColumn(path("stdin.csv"), row, "E_g"), csvColumn(path("file.csv"), row, "E_g"));
        EXPECT_EQ(csvColumn(path("stdin.csv"), row, "ny"), 1.0);  // the direction is normalised
        const double radiance = luxOf(path("stdin.csv"), row, Rgb(0.265, 0.670, 0.065));
        ASSERT_GT(radiance, 0);
        EXPECT_NEAR(csvColumn(path("stdin.csv"), row, "lux"), radiance, 1e-8 * radiance);  // 9 digits in the CSV
        const double rec709 = luxOf(path("rec709.csv"), row, Rgb(0.2126, 0.7152, 0.0722));
        EXPECT_NEAR(csvColumn(path("rec709.csv"), row, "lux"), rec709, 1e-8 * rec709);
    }
    // Direct light only: no lux_indirect column.
    std::ifstream in(path("stdin.csv"));
    std::string header;
    std::getline(in, header);
    EXPECT_NE(header.find(",lux,"), std::string::npos) << header;
    EXPECT_EQ(header.find("lux_indirect"), std::string::npos) << header;
}

TEST_F(Cli, ProbeStandardInputErrorsNameTheLine) {
    write("scene.mtl", kQuadMtl);
    write("scene.obj", kQuadObj);
    const std::string probe = "probe " + path("scene.obj") + " --method exact --direct-only --points - --out " +
                              path("o.csv") + " < ";
    write("short.txt", "0 0 0 0 1 0\n\n# a comment\n1 2 3 0 1\n");
    CommandResult r = runMeshlight(probe + path("short.txt"));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("<stdin>:4: expected 6 numbers (x y z dx dy dz), found 5"), std::string::npos) << r.output;
    write("word.txt", "0 0 zero 0 1 0\n");
    r = runMeshlight(probe + path("word.txt"));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("<stdin>:1: column z: 'zero' is not a finite number"), std::string::npos) << r.output;
    write("zero.txt", "\n\n0 0 0 0 0 0\n");
    r = runMeshlight(probe + path("zero.txt"));
    EXPECT_NE(r.output.find("<stdin>:3: the normal is zero"), std::string::npos) << r.output;
    write("empty.txt", "# nothing\n");
    r = runMeshlight(probe + path("empty.txt"));
    EXPECT_EQ(r.status, 2);
    EXPECT_FALSE(fs::exists(path("o.csv")));
    r = runMeshlight("probe " + path("scene.obj") + " --photometry cie --points - --out " + path("o.csv") + " < " +
                     path("zero.txt"));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("radiance|rec709"), std::string::npos) << r.output;
}

TEST_F(Cli, RenderLuxImages) {
    write("scene.mtl", kQuadMtl);
    write("scene.obj", kQuadObj);
    const std::string render = "render " + path("scene.obj") + " --width 48 --height 32 --samples 300 --quantity lux";
    CommandResult r = runMeshlight(render + " --out " + path("lux.png"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(fs::exists(path("lux.png")));
    r = runMeshlight(render + " --photometry rec709 --out " + path("lux.exr"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(readImageAttribute(path("lux.exr"), "meshlight:unit"), std::optional<std::string>("lx"));
    EXPECT_EQ(readImageChannel(path("lux.exr"), "Y").width, 48);
    for (const std::string& bad : {render + " --quantity candela --out " + path("x.png"),
                                   render + " --photometry cie --out " + path("x.png"),
                                   render + " --log " + path("l.csv") + " --reference " + path("lux.exr") +
                                       " --out " + path("x.png")}) {
        r = runMeshlight(bad);
        EXPECT_EQ(r.status, 2) << bad << "\n" << r.output;
    }
    EXPECT_EQ(files(), 4u);  // obj, mtl, png, exr
}

// The lux image holds irradiance from the cache, not radiance: at the floor's
// centre of the Cornell box it is what probe computes there.
TEST_F(Cli, RenderLuxAtTheCornellFloorCentreAgreesWithProbe) {
    // Straight down on the floor's centre from 300 mm, 10° across: 1.6 mm a
    // pixel. The point is in the tall block's penumbra (about 1 % a mm), and
    // the view makes the cache refine there first.
    const std::string view = "--direct-only --camera-pos 276.4,300,279.6 --camera-target 276.4,0,279.6 "
                             "--camera-up 0,0,1 --fov 10 --width 33 --height 33";
    // Refined for a time rather than --until-error, which stops on the
    // image's estimate: this test judges the cache's own (direct_error).
    CommandResult r = runMeshlight("render cornell --quantity lux --time 8 --every 0.5 " + view +
                                   " --log " +
                                   path("log.csv") + " --out " + path("lux.exr"));
    ASSERT_EQ(r.status, 0) << r.output;
    write("point.txt", "276.4 0 279.6 0 1 0\n");
    r = runMeshlight("probe cornell --method exact --direct-only --points - --out " + path("p.csv") + " < " +
                     path("point.txt"));
    ASSERT_EQ(r.status, 0) << r.output;
    const ImageChannel lux = readImageChannel(path("lux.exr"), "Y");
    ASSERT_EQ(lux.width, 33);
    const double rendered = lux.values[16 * 33 + 16];  // the centre pixel sees the centre
    const double exact = csvColumn(path("p.csv"), 0, "lux");
    // The tolerance is three times the cache's own estimate of its error
    // (its last log row's direct_error, a relative RMS over the vertices
    // that matter for the view): interpolation between vertices and their
    // sampling noise are what separate a pixel from the exact value, and a
    // single point may stray beyond the RMS. The pixel's own width adds
    // nothing to first order (the gradient is linear across 1.6 mm).
    std::ifstream log(path("log.csv"));
    int rows = -1;  // not counting the header
    for (std::string line; std::getline(log, line);) ++rows;
    const double estimated = csvColumn(path("log.csv"), rows - 1, "direct_error");
    ASSERT_GT(exact, 50);  // about 76 lx
    ASSERT_LT(estimated, 0.05) << "the cache did not get near enough in 8 s:\n" << r.output;
    EXPECT_NEAR(rendered, exact, 3 * estimated * exact) << "estimated error " << estimated;
}

// --until-error waits for a bounce: the caustics' mesh, which a scene with
// a mirror or glass shows from the first snapshot, is not indirect light.
// The McGuire box with a mirror and a glass sphere, until 2%, stopped on
// its first snapshot with no bounce gathered (its estimate 1.81%, the
// ceiling lit only by caustics). Skipped without ../shared/scenes.
TEST_F(Cli, UntilErrorWaitsForABounceBesideTheCaustics) {
    const std::string scene = std::string(MESHLIGHT_SHARED_SCENES) + "/mcguire-cornellbox/CornellBox-Sphere.obj";
    if (!fs::exists(scene)) GTEST_SKIP() << scene << " is absent";
    const CommandResult r = runMeshlight("render " + scene + " --width 128 --height 128 --until-error 0.02 --out " +
                                         path("x.png"));
    ASSERT_EQ(r.status, 0) << r.output;
    const size_t at = r.output.find("\nrefined ");
    ASSERT_NE(at, std::string::npos) << r.output;
    const std::string line = r.output.substr(at + 1, r.output.find('\n', at + 1) - at - 1);
    EXPECT_NE(line.find("caustic photons"), std::string::npos) << line;
    EXPECT_EQ(line.find("(0 gathers)"), std::string::npos) << line;
}

// When --until-error asks its estimate next (UntilErrorSchedule), on exact
// power laws: after one estimate the error is taken to fall as 1/t² (0.08
// at 0.4 s reaches 0.02 at 0.8 s); after two, through both (0.16 at 1 s and
// 0.04 at 2 s: α = 2, so 0.01 at 4 s); a stalled error takes α = 0.25
// (0.04 twice: 0.02 at 2 · 2⁴ = 32 s); at or below the target, now; before
// any estimate, never. Exact up to rounding.
TEST(UntilError, TheNextAskIsWhenTheEstimatesSayTheErrorReachesTheTarget) {
    UntilErrorSchedule s;
    EXPECT_EQ(s.crossing(0.02), kInf);
    s.add(0.4, 0.08);
    EXPECT_NEAR(s.crossing(0.02), 0.8, 1e-12);
    UntilErrorSchedule fast;
    fast.add(1, 0.16);
    fast.add(2, 0.04);
    EXPECT_NEAR(fast.crossing(0.01), 4.0, 1e-12);
    EXPECT_NEAR(fast.crossing(0.04), 2.0, 1e-12);
    UntilErrorSchedule stalled;
    stalled.add(1, 0.04);
    stalled.add(2, 0.04);
    EXPECT_NEAR(stalled.crossing(0.02), 32.0, 1e-9);
    // Only the last two count: a third estimate replaces the first.
    stalled.add(4, 0.01);
    EXPECT_NEAR(stalled.crossing(0.0025), 4 * std::pow(4.0, 1 / 2.0), 1e-12);
}

// Which fresh snapshots --until-error asks about (UntilErrorSchedule::
// shouldAsk): the first; then one due by the crossing (within half the
// snapshots' spacing of it), or one a regular interval (0.5 s, or three
// asks' cost) after the last ask began. Times exact in binary fractions.
TEST(UntilError, ItAsksTheFirstSnapshotThoseNearTheCrossingAndRegularlyElse) {
    UntilErrorSchedule s;
    EXPECT_TRUE(s.shouldAsk(0.25, 0.25, 0.02));
    s.asked(0.25, 0.375, 0.25, 0.08);  // 8% at 0.25 s, α = 2: 2% at 0.5 s
    EXPECT_EQ(s.askCost, 0.125);
    EXPECT_NEAR(s.crossing(0.02), 0.5, 1e-12);
    // A snapshot at 0.3125 (spacing 0.0625): 0.34375 is short of 0.5, and
    // 0.1875 s since the ask began; the next at 0.5625 (spacing 0.25):
    // 0.6875 reaches it.
    EXPECT_FALSE(s.shouldAsk(0.4375, 0.3125, 0.02));
    UntilErrorSchedule due = s;
    EXPECT_TRUE(due.shouldAsk(0.5625, 0.5625, 0.02));
    // Far from the crossing only the regular interval asks: 2% is due at
    // 0.5 s but 0.1% at 0.25·√80 = 2.24 s.
    UntilErrorSchedule far = s;
    EXPECT_FALSE(far.shouldAsk(0.5625, 0.5625, 0.001));
    EXPECT_FALSE(far.shouldAsk(0.6875, 0.6875, 0.001));  // 0.4375 s since the ask began
    EXPECT_TRUE(far.shouldAsk(0.75, 0.75, 0.001));       // 0.5 s
    // An ask that cost 0.25 s makes the regular interval 0.75 s.
    UntilErrorSchedule slow;
    EXPECT_TRUE(slow.shouldAsk(1, 1, 0.001));
    slow.asked(1, 1.25, 1, 0.05);
    EXPECT_FALSE(slow.shouldAsk(1.625, 1.625, 0.001));
    EXPECT_TRUE(slow.shouldAsk(1.75, 1.75, 0.001));
}
