// The bench report's building blocks, on values known exactly: the power-law
// fit, the bench table and its number formats, HTML escaping, CSV and
// Markdown to HTML, the scaling scenes, and the page of a report whose
// sections are test fixtures; the error against a noisy reference and the
// switch that turns Blender Cycles off.
#include "core/Error.h"
#include "core/ParallelFor.h"
#include "core/scenes/BenchScene.h"
#include "core/scenes/CornellBox.h"
#include "core/scenes/OfficeScene.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/scenes/ScalingScene.h"
#include "viewer/bench/BenchReport.h"
#include "viewer/bench/BenchStatistics.h"
#include "viewer/bench/BenchTable.h"
#include "viewer/bench/CyclesRunner.h"
#include "viewer/bench/EstimateAgreement.h"
#include "viewer/bench/NoisyReference.h"
#include "viewer/bench/OfficeWalkthrough.h"
#include "viewer/bench/WalkthroughViews.h"
#include "viewer/bench/PowerLawFit.h"
#include "viewer/bench/ReportHtml.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

using namespace ml;
namespace fs = std::filesystem;

// --- Work on threads ----------------------------------------------------------------

TEST(ParallelFor, EveryItemOnceAndTheFirstFailureRethrown) {
    for (const int threads : {1, 3, 8}) {
        std::vector<std::atomic<int>> hits(100);
        parallelFor(hits.size(), threads, [&](size_t i) { ++hits[i]; });
        for (size_t i = 0; i < hits.size(); ++i) ASSERT_EQ(hits[i].load(), 1) << threads << " threads, item " << i;
    }
    // One thread: in order, on the caller's own (no thread started).
    std::vector<size_t> order;
    std::vector<std::thread::id> on;
    parallelFor(5, 1, [&](size_t i) { order.push_back(i), on.push_back(std::this_thread::get_id()); });
    EXPECT_EQ(order, (std::vector<size_t>{0, 1, 2, 3, 4}));
    for (const std::thread::id& id : on) EXPECT_EQ(id, std::this_thread::get_id());
    // A failing item's exception reaches the caller, on threads or not.
    for (const int threads : {1, 3}) {
        try {
            parallelFor(1000, threads, [&](size_t i) {
                if (i == 7) throw std::runtime_error("item seven");
            });
            ADD_FAILURE() << "no exception on " << threads << " threads";
        } catch (const std::runtime_error& e) {
            EXPECT_STREQ(e.what(), "item seven");
        }
    }
}

// --- Power-law fit ------------------------------------------------------------------

TEST(PowerLawFit, ExactOnAPowerLaw) {
    const std::vector<double> x = {1, 2, 10, 1000, 1e6};
    std::vector<double> y;
    for (double v : x) y.push_back(3.0 * std::pow(v, 1.5));
    const PowerLawFit fit = fitPowerLaw(x, y);
    EXPECT_NEAR(fit.exponent, 1.5, 1e-12);
    EXPECT_NEAR(fit.coefficient, 3.0, 3e-12);
    EXPECT_NEAR(fit.r2, 1.0, 1e-12);
    EXPECT_EQ(fit.points, 5u);
    EXPECT_NEAR(fit.at(4.0), 24.0, 1e-10);
}

TEST(PowerLawFit, ExactOnDecreasingAndConstantLaws) {
    const std::vector<double> x = {0.5, 3, 7, 64};
    std::vector<double> falling, flat;
    for (double v : x) {
        falling.push_back(0.25 / v);
        flat.push_back(42.0);
    }
    const PowerLawFit f = fitPowerLaw(x, falling);
    EXPECT_NEAR(f.exponent, -1.0, 1e-12);
    EXPECT_NEAR(f.coefficient, 0.25, 1e-12);
    const PowerLawFit c = fitPowerLaw(x, flat);
    EXPECT_NEAR(c.exponent, 0.0, 1e-12);
    EXPECT_NEAR(c.coefficient, 42.0, 1e-10);
    EXPECT_EQ(c.r2, 1.0);  // nothing to explain: every point is on the line
}

// Off the line, the least-squares answer in closed form: ln x = 0, 1, 2 and
// ln y = 0, 2, 3 give slope 3/2, intercept 1/6 and r² = 1 − (1/6)/(14/3) = 27/28.
TEST(PowerLawFit, LeastSquaresOffTheLine) {
    const double e = std::exp(1.0);
    const PowerLawFit fit = fitPowerLaw({1, e, e * e}, {1, e * e, e * e * e});
    EXPECT_NEAR(fit.exponent, 1.5, 1e-12);
    EXPECT_NEAR(fit.coefficient, std::exp(1.0 / 6.0), 1e-12);
    EXPECT_NEAR(fit.r2, 27.0 / 28.0, 1e-12);
}

TEST(PowerLawFit, RefusesWhatHasNoSlope) {
    EXPECT_THROW(fitPowerLaw({1, 2}, {1}), std::invalid_argument);
    EXPECT_THROW(fitPowerLaw({1}, {1}), std::invalid_argument);
    EXPECT_THROW(fitPowerLaw({3, 3, 3}, {1, 2, 3}), std::invalid_argument);
    EXPECT_THROW(fitPowerLaw({1, 2}, {0, 1}), std::invalid_argument);
    EXPECT_THROW(fitPowerLaw({-1, 2}, {1, 1}), std::invalid_argument);
    EXPECT_THROW(fitPowerLaw({1, NAN}, {1, 1}), std::invalid_argument);
}

// --- Bench tables and statistics --------------------------------------------------------

TEST(BenchTable, AlignedCsvAndMarkdownFromTheSameCells) {
    BenchTable t({"config", "ms"});
    t.addRow({"jittered 64x4", benchMs(0.0123456)});
    t.addRow({"query", ""});
    EXPECT_EQ(t.aligned(),
              "config            ms\n"
              "jittered 64x4  12.35\n"
              "query               \n");
    EXPECT_EQ(t.csv(), "config,ms\njittered 64x4,12.35\nquery,\n");
    EXPECT_EQ(t.markdown(), "| config | ms |\n|---|---|\n| jittered 64x4 | 12.35 |\n| query |  |\n");
    // The summaries' tables read back as HTML tables.
    EXPECT_NE(markdownToHtml(t.markdown()).find("<td>jittered 64x4</td>"), std::string::npos);
}

TEST(BenchTable, NumberFormats) {
    EXPECT_EQ(benchNumber(0.097123), "0.09712");
    EXPECT_EQ(benchNumber(123456), "1.235e+05");
    EXPECT_EQ(benchPct(0.01234), "1.234");
    EXPECT_EQ(benchMs(2.5), "2500");
    EXPECT_EQ(benchYesNo(true), "yes");
    EXPECT_EQ(benchYesNo(false), "no");
}

// The image's estimate against the measured error: only images measured
// within the range count, and only those with an estimate (not made, or 1
// while no bounce is shown); the worst factor either way decides.
TEST(EstimateAgreement, TheWorstFactorEitherWayOverTheRange) {
    const std::vector<EstimatePoint> points = {
        {0.5, 0.20, 0.05},   // measured above the range: left out
        {1.0, 0.08, 1.0},    // no estimate yet: left out
        {2.0, 0.05, 0.06},   // 1.2
        {3.0, 0.02, 0.012},  // 1/0.6 = 1.667 (under-estimated)
        {4.0, 0.01, 0.013},  // 1.3, on the range's edge: counted
        {5.0, 0.005, 0.05},  // measured below the range: left out
        {6.0, 0.03, -1},     // not made: left out
    };
    const EstimateAgreement a = estimateAgreement(points, 0.10, 0.01);
    EXPECT_EQ(a.images, 3);
    EXPECT_NEAR(a.worst, 0.02 / 0.012, 1e-12);
    EXPECT_EQ(a.worstAt, 3.0);
    EXPECT_EQ(estimateTarget("t", a, 1.5).status, "not met");
    EXPECT_EQ(estimateTarget("t", a, 1.7).status, "met");
    EXPECT_EQ(estimateTarget("t", estimateAgreement(points, 0.10, 0.09), 1.5).status, "not measured");
}

TEST(BenchStatistics, MedianAndSpread) {
    EXPECT_EQ(median({}), 0.0);
    EXPECT_EQ(median({3, 1, 2}), 2.0);
    EXPECT_EQ(median({4, 1, 3, 2}), 2.5);
    const std::vector<int> items = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
    EXPECT_EQ(spread(items, 4), (std::vector<int>{0, 2, 5, 7}));
    EXPECT_EQ(spread(items, 20), items);
}

// --- HTML ------------------------------------------------------------------------------

TEST(ReportHtml, EscapesTheFiveSpecialCharacters) {
    EXPECT_EQ(htmlEscape("<a href=\"x\">Tom & Jerry's</a>"),
              "&lt;a href=&quot;x&quot;&gt;Tom &amp; Jerry&#39;s&lt;/a&gt;");
    EXPECT_EQ(htmlEscape("&amp;"), "&amp;amp;");  // text, not markup: escaped again
    EXPECT_EQ(htmlEscape("64×64, ≤ 0.2 %"), "64×64, ≤ 0.2 %");  // UTF-8 passes through
    EXPECT_EQ(htmlEscape(""), "");
}

TEST(ReportHtml, ParsesCsvWithQuotesAndCrLf) {
    const CsvTable t = parseCsv("name,value\r\n\"a, \"\"b\"\"\",1.5\r\nplain,-2e-3\r\n", "t.csv");
    ASSERT_EQ(t.header, (std::vector<std::string>{"name", "value"}));
    ASSERT_EQ(t.rows.size(), 2u);
    EXPECT_EQ(t.rows[0][0], "a, \"b\"");
    EXPECT_EQ(t.rows[1][1], "-2e-3");
    EXPECT_EQ(t.column("value"), 1u);
    EXPECT_THROW(t.column("missing"), InputError);
}

TEST(ReportHtml, CsvErrorsNameFileAndLine) {
    try {
        parseCsv("a,b\n1,2\n3\n", "bad.csv");
        FAIL() << "a short row was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.csv:3"), std::string::npos) << e.what();
    }
    EXPECT_THROW(parseCsv("a,b\n\"1,2\n", "open.csv"), InputError);
    EXPECT_THROW(parseCsv("", "empty.csv"), InputError);
}

TEST(ReportHtml, TableEscapesCellsAndPicksColumns) {
    const CsvTable t = parseCsv("config,ms,note\nq<32>,0.25,a&b\n", "t.csv");
    const std::string all = htmlTable(t);
    EXPECT_NE(all.find("<td>q&lt;32&gt;</td>"), std::string::npos) << all;
    EXPECT_NE(all.find("<td class=\"num\">0.25</td>"), std::string::npos) << all;
    EXPECT_NE(all.find("<td>a&amp;b</td>"), std::string::npos) << all;
    const std::string picked = htmlTable(t, {"ms", "config"});
    EXPECT_LT(picked.find("<th>ms</th>"), picked.find("<th>config</th>"));
    EXPECT_EQ(picked.find("note"), std::string::npos);
    EXPECT_THROW(htmlTable(t, {"absent"}), InputError);
}

TEST(ReportHtml, MarkdownSubset) {
    const std::string html = markdownToHtml(
        "# Title <x>\n\n- one `a<b`\n- **two**\n\n| k | v |\n|---|---|\n| x | 1.5 |\n\ntext & more\nnext line\n"
        "<script>alert(1)</script>\n",
        2);
    EXPECT_NE(html.find("<h3>Title &lt;x&gt;</h3>"), std::string::npos) << html;
    EXPECT_NE(html.find("<li>one <code>a&lt;b</code></li>"), std::string::npos) << html;
    EXPECT_NE(html.find("<li><strong>two</strong></li>"), std::string::npos) << html;
    EXPECT_NE(html.find("<th>k</th><th>v</th>"), std::string::npos) << html;
    EXPECT_NE(html.find("<td>x</td><td class=\"num\">1.5</td>"), std::string::npos) << html;
    EXPECT_EQ(html.find("---"), std::string::npos) << "the separator row is not a row";
    EXPECT_NE(html.find("<p>text &amp; more\nnext line\n&lt;script&gt;"), std::string::npos) << html;
    EXPECT_EQ(html.find("<script"), std::string::npos);
}

// --- Scaling scenes ------------------------------------------------------------------

namespace {

double totalArea(const Scene& s, bool emissive) {
    double a = 0;
    for (const Mesh& m : s.meshes)
        for (size_t t = 0; t < m.triangles.size(); ++t)
            if (s.materials[m.materials[t]].emissive() == emissive) a += m.area(t);
    return a;
}

}  // namespace

TEST(ScalingScene, SubdivisionQuadruplesSurfacesAndKeepsLights) {
    const Scene base = makeBenchScene();
    for (int k : {0, 1, 3}) {
        const Scene s = subdivideScene(base, k);
        // 4 non-emissive triangles (occluder, floor) split, 2 light triangles kept.
        EXPECT_EQ(s.triangleCount(), size_t(4) * (size_t(1) << (2 * k)) + 2) << "levels " << k;
        EXPECT_NEAR(totalArea(s, false), totalArea(base, false), 1e-12);
        ASSERT_EQ(s.lights.size(), 1u);
        EXPECT_EQ(s.lights[0].triangles.size(), 2u);
        EXPECT_DOUBLE_EQ(s.lights[0].area, base.lights[0].area);
        EXPECT_EQ(s.bounds.lo, base.bounds.lo);
        EXPECT_EQ(s.bounds.hi, base.bounds.hi);
        // Midpoints are shared: a quad of 2^k × 2^k cells has (2^k + 1)² vertices.
        const Mesh& floor = s.meshes[2];
        const size_t side = (size_t(1) << k) + 1;
        EXPECT_EQ(floor.positions.size(), side * side) << "levels " << k;
        for (size_t t = 0; t < floor.triangles.size(); ++t) EXPECT_GT(floor.areaNormal(t).y, 0) << t;
    }
    EXPECT_THROW(subdivideScene(base, -1), InputError);
    EXPECT_THROW(subdivideScene(base, 13), InputError);
}

TEST(ScalingScene, LightGridKeepsTotalPower) {
    const Scene cornell = makeCornellBox();
    const Rgb power0 = cornell.lights[0].power();
    for (int n : {1, 2, 7, 64}) {
        const Scene s = makeCornellLightGrid(n);
        ASSERT_EQ(s.lights.size(), size_t(n));
        Rgb power(0.0);
        for (const Light& l : s.lights) {
            power += l.power();
            EXPECT_NEAR(l.area, 1600.0, 1e-9);
            EXPECT_LT(l.normal.y, -0.999);
            EXPECT_TRUE(l.planar);
            // Inside the box, below the ceiling.
            EXPECT_GT(l.bounds.lo.x, 0.0);
            EXPECT_LT(l.bounds.hi.x, 556.0);
            EXPECT_GT(l.bounds.lo.z, 0.0);
            EXPECT_LT(l.bounds.hi.z, 559.2);
            EXPECT_LT(l.bounds.hi.y, 548.8);
        }
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(power[c], power0[c], 1e-9 * power0[c]) << n << " lights";
        EXPECT_EQ(s.triangleCount(), cornell.triangleCount() - 2 + size_t(2 * n));
    }
    EXPECT_THROW(makeCornellLightGrid(0), InputError);
}

TEST(ScalingScene, SurfaceReceiversLieOnSurfacesAndRepeat) {
    const Scene bench = makeBenchScene();
    const std::vector<ReceiverPoint> a = surfaceReceivers(bench, 200, 7), b = surfaceReceivers(bench, 200, 7);
    ASSERT_EQ(a.size(), 200u);
    size_t onFloor = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].position, b[i].position);
        const bool floor = a[i].position.y == 0.0, occluder = std::abs(a[i].position.y - 0.5) < 1e-12;
        EXPECT_TRUE(floor || occluder) << a[i].position.y;
        EXPECT_NEAR(glm::length(a[i].normal), 1.0, 1e-12);
        EXPECT_NEAR(std::abs(a[i].normal.y), 1.0, 1e-12);
        onFloor += floor;
    }
    // By area: the floor is 36 times the occluder.
    EXPECT_GT(onFloor, 180u);
    EXPECT_NE(surfaceReceivers(bench, 1, 8)[0].position, a[0].position);
}

// --- The page ---------------------------------------------------------------------------

namespace {

std::string readAll(const fs::path& p) {
    std::ifstream in(p);
    std::ostringstream os;
    os << in.rdbuf();
    return os.str();
}

void writeAll(const fs::path& p, const std::string& text) {
    std::ofstream out(p);
    out << text;
}

// A section that writes a CSV and a summary, names a plot it does not
// write, and a section that fails.
std::vector<ReportSection> fixtureSections() {
    ReportSection good;
    good.id = "fixture";
    good.title = "A <fixture> & more";
    good.about = "Writes known files.";
    good.run = [](const BenchOptions& o) {
        const fs::path dir(o.outDir);  // the report's folder for this section
        fs::create_directories(dir);
        writeAll(dir / "data.csv", "label,ms\n\"x<y\",1.5\nplain,2\n");
        writeAll(dir / "summary.md", "# Fixture\n\n- exponent **0.5**\n");
        writeAll(dir / "plot.png", "not really a PNG; the page only links it");
        return 0;
    };
    good.summary = "summary.md";
    good.figures = {{"plot.png", "A plot of data.csv", {"data.csv"}}, {"never.png", "Never written", {"data.csv"}}};
    good.tables = {{"data.csv", "The data", {"ms", "label"}}};

    ReportSection bad;
    bad.id = "broken";
    bad.title = "Broken";
    bad.about = "Throws.";
    bad.run = [](const BenchOptions&) -> int {
        throw std::runtime_error("no GPU <today>");
    };
    return {good, bad};
}

}  // namespace

TEST(BenchReport, PageShowsSectionsEscapedAndFailuresNamed) {
    const fs::path dir = fs::temp_directory_path() / concat("meshlight-test-report-", ::getpid());
    fs::remove_all(dir);
    BenchReportOptions options;
    options.outDir = dir.string();
    options.commandLine = "meshlight bench report --out <dir>";
    EXPECT_EQ(runBenchReport(options, fixtureSections()), 1);  // one section failed

    const std::string html = readAll(dir / "index.html");
    ASSERT_FALSE(html.empty());
    EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_EQ(html.find("<script"), std::string::npos);
    EXPECT_NE(html.find("--out &lt;dir&gt;"), std::string::npos);
    EXPECT_NE(html.find("A &lt;fixture&gt; &amp; more"), std::string::npos);
    EXPECT_NE(html.find("<img src=\"fixture/plot.png\""), std::string::npos);
    EXPECT_NE(html.find("<a href=\"fixture/data.csv\">data.csv</a>"), std::string::npos);
    EXPECT_EQ(html.find("fixture/never.png\""), std::string::npos) << "a missing plot must not be an <img>";
    EXPECT_NE(html.find("Plot not produced: never.png"), std::string::npos);
    EXPECT_NE(html.find("<td class=\"num\">1.5</td><td>x&lt;y</td>"), std::string::npos) << html;
    EXPECT_NE(html.find("exponent <strong>0.5</strong>"), std::string::npos);
    EXPECT_NE(html.find("no GPU &lt;today&gt;"), std::string::npos);
    EXPECT_NE(html.find("<a href=\"#broken\">broken</a> (<strong>failed</strong>"), std::string::npos);
    // No temporaries left behind by the atomic writes.
    for (const auto& e : fs::directory_iterator(dir)) EXPECT_NE(e.path().filename().string().front(), '.');
    fs::remove_all(dir);
}

TEST(BenchReport, RegistryListsTheBenchesThatExist) {
    std::vector<std::string> ids;
    for (const ReportSection& s : reportSections()) {
        ids.push_back(s.id);
        EXPECT_TRUE(bool(s.run)) << s.id;
        EXPECT_FALSE(s.figures.empty()) << s.id;
    }
    // Later benches add sections; these two exist now, each once.
    for (const char* id : {"direct", "scaling"}) EXPECT_EQ(std::count(ids.begin(), ids.end(), id), 1) << id;
    std::sort(ids.begin(), ids.end());
    EXPECT_EQ(std::adjacent_find(ids.begin(), ids.end()), ids.end()) << "section ids must be unique";
}

// --- Error against a noisy reference (NoisyReference.h), Cycles' discovery ------------------

TEST(NoisyReference, TimeToLevelIsExactOnAPowerLaw) {
    // error = t^-1/2: log-log interpolation between any two points is exact.
    const std::vector<double> t = {1, 4, 16, 64};
    std::vector<double> e;
    for (double s : t) e.push_back(1 / std::sqrt(s));
    EXPECT_NEAR(*timeToLevel(t, e, 0.25), 16.0, 1e-12);
    EXPECT_NEAR(*timeToLevel(t, e, 0.3), 1 / (0.3 * 0.3), 1e-9);
    EXPECT_DOUBLE_EQ(*timeToLevel(t, e, 2.0), 1.0);  // already there at the first point
    EXPECT_FALSE(timeToLevel(t, e, 0.1));            // never reached
    EXPECT_FALSE(timeToLevel({}, {}, 0.1));
}

TEST(NoisyReference, ErrorAgainstTakesTheReferenceNoiseOut) {
    Reference ref;
    ref.radiance = ImageRgb(8, 4, Rgb(0.5));
    ref.standardError = ImageRgb(8, 4, Rgb(0.0));
    ImageRgb x(8, 4, Rgb(0.55));
    // No noise: both are relativeRmse, 0.05 / sqrt(0.25 + 0.01).
    const double expected = 0.05 / std::sqrt(0.26);
    ImageError e = errorAgainst(x, ref);
    EXPECT_NEAR(e.raw, expected, 1e-6);
    EXPECT_NEAR(e.corrected, expected, 1e-6);
    // A reference noise of 0.03 per pixel: the raw error stays, the corrected one is sqrt(d² − σ²)/sqrt(r² + 0.01).
    ref.standardError = ImageRgb(8, 4, Rgb(0.03));
    e = errorAgainst(x, ref);
    EXPECT_NEAR(e.raw, expected, 1e-6);
    EXPECT_NEAR(e.corrected, std::sqrt(0.05 * 0.05 - 0.03 * 0.03) / std::sqrt(0.26), 1e-6);
    EXPECT_NEAR(relativeRmsError(ref.standardError, ref.radiance), 0.03 / std::sqrt(0.26), 1e-6);
    // More noise than difference: zero, not the root of a negative number.
    ref.standardError = ImageRgb(8, 4, Rgb(0.08));
    EXPECT_EQ(errorAgainst(x, ref).corrected, 0.0);
    EXPECT_THROW(errorAgainst(ImageRgb(4, 4), ref), InputError);
}

TEST(NoisyReference, AveragedReferencesCombineTheirNoise) {
    Reference a, b;
    a.radiance = ImageRgb(2, 2, Rgb(1.0));
    a.standardError = ImageRgb(2, 2, Rgb(0.4));
    a.spp = 100;
    a.seconds = 2;
    b.radiance = ImageRgb(2, 2, Rgb(2.0));
    b.standardError = ImageRgb(2, 2, Rgb(0.2));
    b.spp = 300;
    b.seconds = 5;
    const Reference r = averageReferences(a, b);
    EXPECT_EQ(r.spp, 400);
    EXPECT_DOUBLE_EQ(r.seconds, 7.0);
    for (float v : r.radiance.data) EXPECT_NEAR(v, 0.25 * 1.0 + 0.75 * 2.0, 1e-6);
    for (float v : r.standardError.data) EXPECT_NEAR(v, std::sqrt(0.25 * 0.25 * 0.16 + 0.75 * 0.75 * 0.04), 1e-6);
}

TEST(CyclesRunner, BlenderCanBeTurnedOff) {
    const char* saved = std::getenv("MESHLIGHT_BLENDER");
    const std::string keep = saved ? saved : "";
    for (const char* off : {"", "none"}) {
        ::setenv("MESHLIGHT_BLENDER", off, 1);
        std::string why;
        EXPECT_FALSE(findCycles(why)) << off;
        EXPECT_NE(why.find("MESHLIGHT_BLENDER"), std::string::npos) << why;
    }
    ::setenv("MESHLIGHT_BLENDER", "/nonexistent/blender", 1);
    std::string why;
    EXPECT_FALSE(findCycles(why));
    EXPECT_NE(why.find("not an executable"), std::string::npos) << why;
    if (saved)
        ::setenv("MESHLIGHT_BLENDER", keep.c_str(), 1);
    else
        ::unsetenv("MESHLIGHT_BLENDER");
}

// bench lights' walkthrough in three rooms: it starts at the office's own
// view, keeps its eye at the camera's height (above every piece of
// furniture, so it crosses none) and at least 0.5 m inside the walls, sees
// only the room (checkViewsInside), and walks: from one of 30 views to the
// next at most 1.5 (W + D) / 29 m and 20° of heading (the path is shorter
// than W + D, 10.4 m in the default room of 14 m, and turns about 180°;
// smoothstep timing peaks at 1.5× the mean pace).
TEST(OfficeWalkthrough, StartsAtTheOfficeViewAndWalksInsideAboveTheFurniture) {
    for (const char* spec : {"office", "office:size=16x10x3,panels=8x5", "office:size=4x3x2.8,desks=2,cabinets=2"}) {
        SCOPED_TRACE(spec);
        const OfficeSettings settings = parseOfficeSpec(spec);
        const Scene scene = makeOfficeScene(settings);
        const std::vector<Camera> cameras = officeWalkthroughCameras(scene, settings, 30);
        ASSERT_EQ(cameras.size(), 30u);
        const Camera& office = *scene.camera;
        EXPECT_NEAR(glm::length(cameras[0].position - office.position), 0.0, 1e-12);
        EXPECT_NEAR(glm::dot(glm::normalize(cameras[0].target - cameras[0].position),
                             glm::normalize(office.target - office.position)),
                    1.0, 1e-12);
        for (size_t v = 0; v < cameras.size(); ++v) {
            const Vec3& p = cameras[v].position;
            EXPECT_DOUBLE_EQ(p.y, office.position.y) << v;
            EXPECT_LE(std::abs(p.x), 0.5 * settings.width - 0.5 + 1e-9) << v;
            EXPECT_LE(std::abs(p.z), 0.5 * settings.depth - 0.5 + 1e-9) << v;
            EXPECT_DOUBLE_EQ(cameras[v].fovYDegrees, office.fovYDegrees);
            if (v == 0) continue;
            const Camera& before = cameras[v - 1];
            EXPECT_LE(glm::length(p - before.position), 1.5 * (settings.width + settings.depth) / 29) << v;
            const Vec3 a = cameras[v].target - p, b = before.target - before.position;
            const double turn = std::abs(std::remainder(std::atan2(a.z, a.x) - std::atan2(b.z, b.x), 2 * M_PI));
            EXPECT_LE(turn, glm::radians(20.0)) << v;
        }
        const EmbreeScene rays(scene);
        EXPECT_NO_THROW(checkViewsInside(rays, cameras, 32, 18));
    }
}
