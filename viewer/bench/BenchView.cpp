#include "BenchView.h"

#include "BenchRun.h"
#include "BenchTable.h"
#include "Gnuplot.h"

#include "core/Error.h"
#include "core/scenes/CornellBox.h"
#include "viewer/window/ViewScript.h"
#include "viewer/window/ViewSession.h"

#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <thread>

namespace ml {

namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 1280, kHeight = 720;
// Frames in the first second after the first snapshot is shown are left
// out of the rates: llvmpipe compiles each shader at its first draw, and the
// first snapshot is copied whole.
constexpr double kWarmUp = 1.0;
// --cache-edge of the million scenario: the Cornell box's base cache mesh
// then has about 1.2 million triangles before any refinement. Quick mode
// (CI) doubles it, a quarter of the triangles: its first snapshot takes
// 35 s at a million on 2 cores, and the scenario is run, not judged, there.
constexpr double kMillionEdge = 0.003;
// The targets of issue 6.
constexpr double kTargetFirstFrame = 1.0, kTargetFps = 30, kTargetMillionFps = 10;

struct Scenario {
    std::string name;
    std::string about;
    bool paused = false;         // refinement paused for the whole run
    double cacheEdge = 1.0 / 32;  // CacheSettings::maxEdgeFraction
    bool lights = false;         // still camera, light changes
    double seconds = 15;
    // The Cornell box with its tall block a mirror and its short block glass
    // (specularCornell), with the compositor's specular pass on or off.
    bool specularScene = false;
    bool specularPass = true;
};

struct Result {
    Scenario scenario;
    std::vector<FrameRecord> frames;
    std::vector<double> latencies;  // seconds
    double firstFrame = -1, firstSnapshotFrame = -1;
    std::string gl;
};

struct Stats {
    size_t frames = 0;
    double fps = 0, medianMs = 0, p95Ms = 0, maxMs = 0, medianComposeMs = 0, maxUploadMs = 0;
    size_t specularTraces = 0;  // frames that traced the specular pass
    double medianSpecularMs = 0, maxSpecularMs = 0;
    size_t triangles = 0, medianDrawn = 0;
    uint64_t samplesStart = 0, samplesEnd = 0;
};

double percentile(std::vector<double> v, double p) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))];
}

Stats statsOf(const Result& r) {
    Stats s;
    // From a second after the first frame showing a snapshot.
    double from = 1e300;
    for (const FrameRecord& f : r.frames)
        if (f.snapshot) {
            from = f.start + kWarmUp;
            break;
        }
    std::vector<double> ms, compose, drawn, specular;
    double first = -1, last = 0;
    for (const FrameRecord& f : r.frames) {
        s.triangles = std::max(s.triangles, f.triangles);
        s.maxUploadMs = std::max(s.maxUploadMs, f.uploadMs);
        if (f.start < from) continue;
        if (first < 0) {
            first = f.start;
            s.samplesStart = f.samples;
        }
        last = f.start + f.seconds;
        s.samplesEnd = f.samples;
        ms.push_back(1e3 * f.seconds);
        compose.push_back(f.composeMs);
        drawn.push_back(double(f.drawnTriangles));
        if (f.specularMs > 0) specular.push_back(f.specularMs);
    }
    s.frames = ms.size();
    if (s.frames > 0 && last > first) s.fps = double(s.frames) / (last - first);
    s.medianMs = percentile(ms, 0.5);
    s.p95Ms = percentile(ms, 0.95);
    s.maxMs = percentile(ms, 1.0);
    s.medianComposeMs = percentile(compose, 0.5);
    s.specularTraces = specular.size();
    s.medianSpecularMs = percentile(specular, 0.5);
    s.maxSpecularMs = percentile(specular, 1.0);
    s.medianDrawn = size_t(percentile(drawn, 0.5));
    return s;
}

std::string vec(const Vec3& v) { return concat(v.x, ",", v.y, ",", v.z); }

// The Cornell box with a mirror (the tall block, reflectance 0.95) and glass
// (the short block, index 1.5): the specular pass's bench scene, of the
// same geometry and cache as the others.
Scene specularCornell() {
    Scene scene = makeCornellBox();
    Material mirror = Material::diffuse("mirror", Rgb(0.0));
    mirror.smooth.kind = SpecularKind::Mirror;
    mirror.smooth.reflectance = Rgb(0.95);
    Material glass = Material::diffuse("glass", Rgb(0.0));
    glass.smooth.kind = SpecularKind::Glass;
    glass.smooth.ior = 1.5;
    scene.materials.push_back(mirror);
    scene.materials.push_back(glass);
    for (Mesh& m : scene.meshes) {
        if (m.name == "tallBlock") m.materials.assign(m.materials.size(), uint32_t(scene.materials.size() - 2));
        if (m.name == "shortBlock") m.materials.assign(m.materials.size(), uint32_t(scene.materials.size() - 1));
    }
    scene.name = "cornell-specular";
    return scene;
}

// A walk into the box, round the blocks and back out, in `d` seconds, once
// the first snapshot is shown (the million-triangle cache's first round
// takes seconds); with refinement paused from then on, or not.
std::string walkScript(const Camera& start, double d, bool paused) {
    std::ostringstream s;
    s << "# bench view: a walk through the Cornell box\nwait-samples 1\n";
    if (paused) s << "pause\n";
    auto key = [&](double in, const Vec3& pos, const Vec3& target) {
        s << "camera in=" << in << " pos=" << vec(pos) << " target=" << vec(target) << " up=" << vec(start.up)
          << " fov=" << start.fovYDegrees << "\n";
    };
    key(0.3 * d, Vec3(278, 273, -150), Vec3(278, 250, 300));
    key(0.25 * d, Vec3(150, 320, 120), Vec3(420, 120, 420));
    key(0.25 * d, Vec3(420, 230, -200), Vec3(250, 180, 350));
    key(0.2 * d, start.position, start.target);
    s << "quit\n";
    return s.str();
}

// Light changes every 0.3 s, from a second after the first snapshot.
std::string lightScript(int changes) {
    static const char* const kChanges[] = {"off", "on", "intensity 0.5", "color 1,0.7,0.4", "intensity 2",
                                           "color 1,1,1", "intensity 1"};
    std::ostringstream s;
    s << "# bench view: light changes at a still camera\nwait-samples 1\nwait 1\n";
    for (int i = 0; i < changes; ++i) s << "light 0 " << kChanges[size_t(i) % std::size(kChanges)] << "\nwait 0.3\n";
    s << "quit\n";
    return s.str();
}

Result runScenario(const Scene& scene, const Scenario& sc, const BenchOptions& options) {
    ViewSettings s;
    s.width = kWidth;
    s.height = kHeight;
    s.supersample = 1;
    s.camera = scene.cameraOrDefault(double(kWidth) / kHeight);
    s.direct.seed = options.seed;
    s.cache.maxEdgeFraction = sc.cacheEdge;
    s.indirect.decide(scene);  // what `view` does by default
    s.worker.seed = options.seed;
    s.unit = LengthUnit::Millimetre;
    s.maxFps = 0;
    s.printProgress = false;
    s.specular = sc.specularPass;
    const int changes = options.quick ? 8 : 20;
    const std::string text = sc.lights ? lightScript(changes) : walkScript(s.camera, sc.seconds, sc.paused);
    ViewScript script = parseViewScript(text, "bench-view-" + sc.name + ".txt");
    std::vector<std::string> names;
    for (const Light& l : scene.lights) names.push_back(l.name);
    resolveViewScript(script, names);
    s.script = std::move(script);

    std::printf("%s: %s\n", sc.name.c_str(), sc.about.c_str());
    ViewSession session(scene, s);
    Result r;
    r.scenario = sc;
    r.gl = session.glDescription();
    const int status = session.run();
    if (status != 0) throw std::runtime_error(concat("bench view: the '", sc.name, "' session ended with status ", status));
    r.frames = session.frames();
    r.latencies = session.lightChangeLatencies();
    r.firstFrame = session.firstFrameSeconds();
    r.firstSnapshotFrame = session.firstSnapshotFrameSeconds();
    return r;
}

std::string gnuplotScript(const std::vector<Result>& results, const std::vector<GnuplotOutput>& plots) {
    std::ostringstream gp;
    gp << "# Written by 'meshlight bench view'; run with gnuplot in this folder.\n"
       << gnuplotOutputDefaults(plots)
       << "set terminal pngcairo enhanced size 1200,700 font ',11'\n"
          "set datafile separator ','\n"
          "set grid\n"
          "set key top left\n\n";
    std::vector<std::string> parts;
    for (size_t i = 0; i < results.size(); ++i) {
        const Result& r = results[i];
        if (r.scenario.lights) continue;
        gp << "# seconds since start, frame ms\n$s" << i << " << EOD\n";
        for (const FrameRecord& f : r.frames) gp << benchNumber(f.start) << "," << benchNumber(1e3 * f.seconds) << "\n";
        gp << "EOD\n";
        parts.push_back(concat("$s", i, " using 1:2 with lines lw 1.5 title ", gnuplotQuoted(r.scenario.name)));
    }
    gp << "set output out_frames\n"
          "set title 'Frame time while walking, 1280x720 (dashed: 30 and 10 frames/s)'\n"
          "set xlabel 'seconds since the window opened'\n"
          "set ylabel 'ms per frame'\n"
          "set logscale y\n";
    for (size_t i = 0; i < parts.size(); ++i) gp << (i ? ", \\\n     " : "plot ") << parts[i];
    gp << ", \\\n     1000.0/30 with lines dt 2 lc rgb 'black' notitle, 1000.0/10 with lines dt 2 lc rgb 'gray' "
          "notitle\n\n";

    for (const Result& r : results) {
        if (!r.scenario.lights) continue;
        gp << "# change, ms to the end of the frame showing it\n$latency << EOD\n";
        for (size_t i = 0; i < r.latencies.size(); ++i) gp << i + 1 << "," << benchNumber(1e3 * r.latencies[i]) << "\n";
        gp << "EOD\n"
              "set output out_latency\n"
              "set title 'Light change to the frame showing it (dashed: the median frame time)'\n"
              "set xlabel 'change'\n"
              "set ylabel 'ms'\n"
              "set style fill solid 0.6\n"
              "set boxwidth 0.6\n"
              "unset logscale y\n"
              "set yrange [0:*]\n"
              "plot $latency using 1:2 with boxes title 'latency', "
           << benchNumber(statsOf(r).medianMs) << " with lines dt 2 lc rgb 'black' title 'median frame'\n";
    }
    return gp.str();
}

// Runs `meshlight bench view ...` again inside a virtual display.
int runUnderXvfb(const BenchOptions& o) {
    if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0)
        throw std::runtime_error("bench view opens a window and there is no display, nor xvfb-run to make one "
                                 "(Debian: apt-get install xvfb xauth)");
    const std::string self = fs::read_symlink("/proc/self/exe").string();
    const std::string command = concat("xvfb-run -a -s '-screen 0 1920x1080x24' ", shellQuoted(self),
                                       " bench view --out ", shellQuoted(o.outDir), o.quick ? " --quick" : "",
                                       " --seed ", o.seed);
    std::printf("no display: %s\n", command.c_str());
    std::fflush(stdout);
    const int status = std::system(command.c_str());
    if (status == -1 || !WIFEXITED(status)) throw std::runtime_error("bench view: xvfb-run did not run");
    return WEXITSTATUS(status);
}

}  // namespace

int runBenchView(const BenchOptions& options) {
    if (!std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY")) return runUnderXvfb(options);
    BenchRun run(options);
    const Scene scene = makeCornellBox();
    const Scene specular = specularCornell();
    const double d = options.quick ? 2.5 : 15;

    std::vector<Scenario> scenarios = {
        {"walk-paused", "walking, refinement paused after its first snapshot", true, 1.0 / 32, false, d},
        {"walk-refining", "walking while the worker refines", false, 1.0 / 32, false, d},
        {"million",
         options.quick ? "walking over a cache of about 300,000 triangles (quick: a million in full), refining"
                       : "walking over a cache of about a million triangles, refining",
         false, options.quick ? 2 * kMillionEdge : kMillionEdge, false, d},
        {"lights", "still camera, a light changed every 0.3 s, refining", false, 1.0 / 32, true, d},
        {"specular", "walking, paused, a mirror and a glass block, the specular pass on", true, 1.0 / 32, false, d,
         true, true},
        {"specular-off", "the same without the specular pass (the blocks' Kd 0 alone)", true, 1.0 / 32, false, d,
         true, false},
    };
    std::vector<Result> results;
    for (const Scenario& sc : scenarios) results.push_back(runScenario(sc.specularScene ? specular : scene, sc, options));

    BenchTable table({"scenario", "width", "height", "cache_triangles", "median_drawn_triangles", "frames", "fps",
                      "median_ms", "p95_ms", "max_ms", "median_composite_ms", "max_upload_ms", "samples_during",
                      "specular_traces", "median_specular_ms", "max_specular_ms"});
    BenchTable frames({"scenario", "seconds", "frame_ms", "composite_ms", "upload_ms", "samples", "cache_triangles",
                       "drawn_triangles", "specular_ms"});
    for (const Result& r : results) {
        const Stats s = statsOf(r);
        table.addRow({r.scenario.name, std::to_string(kWidth), std::to_string(kHeight), std::to_string(s.triangles),
                      std::to_string(s.medianDrawn), std::to_string(s.frames), benchNumber(s.fps), benchNumber(s.medianMs), benchNumber(s.p95Ms),
                      benchNumber(s.maxMs), benchNumber(s.medianComposeMs), benchNumber(s.maxUploadMs),
                      std::to_string(s.samplesEnd - s.samplesStart), std::to_string(s.specularTraces),
                      benchNumber(s.medianSpecularMs), benchNumber(s.maxSpecularMs)});
        for (const FrameRecord& f : r.frames)
            frames.addRow({r.scenario.name, benchNumber(f.start), benchNumber(1e3 * f.seconds),
                           benchNumber(f.composeMs), benchNumber(f.uploadMs), std::to_string(f.samples),
                           std::to_string(f.triangles), std::to_string(f.drawnTriangles), benchNumber(f.specularMs)});
    }
    const Result& walk = results[1];
    const Result& million = results[2];
    const Result& lights = results[3];
    const Stats withSpecular = statsOf(results[4]), withoutSpecular = statsOf(results[5]);
    BenchTable latency({"change", "latency_ms", "median_frame_ms"});
    const double lightFrameMs = statsOf(lights).medianMs;
    for (size_t i = 0; i < lights.latencies.size(); ++i)
        latency.addRow({std::to_string(i + 1), benchNumber(1e3 * lights.latencies[i]), benchNumber(lightFrameMs)});
    const double maxLatency = lights.latencies.empty()
                                  ? 0
                                  : *std::max_element(lights.latencies.begin(), lights.latencies.end());

    BenchTable targets({"target", "value", "met"});
    targets.addRow({"first frame within 1 s of start (s)", benchNumber(walk.firstFrame),
                    benchYesNo(walk.firstFrame >= 0 && walk.firstFrame <= kTargetFirstFrame)});
    targets.addRow({"first frame showing a snapshot (s; informative)", benchNumber(walk.firstSnapshotFrame), "-"});
    const Stats ws = statsOf(walk), ms = statsOf(million);
    targets.addRow({"30 frames/s at 1280x720 on the Cornell box while refining", benchNumber(ws.fps),
                    benchYesNo(ws.fps >= kTargetFps)});
    targets.addRow({concat("10 frames/s with ", ms.triangles, " cached triangles"), benchNumber(ms.fps),
                    benchYesNo(ms.fps >= kTargetMillionFps && ms.triangles >= 1000000)});
    targets.addRow({"mirrors and glass at 1280x720 (issue 16; informative): frames/s with the pass vs without; "
                    "median frame ms",
                    concat(benchNumber(withSpecular.fps), " vs ", benchNumber(withoutSpecular.fps), "; ",
                           benchNumber(withSpecular.medianMs), " vs ", benchNumber(withoutSpecular.medianMs)),
                    "-"});
    // The change is applied before the frame is composited: shown by that frame.
    targets.addRow({"a light change shows in the next frame (max latency ms vs median frame ms)",
                    concat(benchNumber(1e3 * maxLatency), " vs ", benchNumber(lightFrameMs)),
                    benchYesNo(!lights.latencies.empty() && 1e3 * maxLatency <= 2 * std::max(lightFrameMs, 1.0))});

    std::printf("\nViewer frames at %dx%d (rates from %.0f s after the first snapshot shown).\n\n%s", kWidth,
                kHeight, kWarmUp,
                table.aligned().c_str());
    std::printf("\nLight changes (%zu).\n\n%s", lights.latencies.size(), latency.aligned().c_str());
    std::printf("\nTargets (issue 6).\n\n%s", targets.aligned().c_str());
    run.writeCsv("view_scenarios.csv", table);
    run.writeCsv("view_frames.csv", frames);
    run.writeCsv("view_latency.csv", latency);
    run.writeCsv("view_targets.csv", targets);
    const std::vector<GnuplotOutput> plots = {{"out_frames", "view_frames.png"}, {"out_latency", "view_latency.png"}};
    run.plot("view_plots.gp", gnuplotScript(results, plots), plots);

    const double wall = run.seconds();
    std::ostringstream md;
    md << "# Viewer bench\n\n"
       << "- OpenGL (window): " << walk.gl << "\n"
       << "- mode: " << run.mode() << ", " << d << " s per walk, seed " << options.seed
       << "; 1280×720, one sub-pixel per pixel, no frame cap; rates from " << kWarmUp
       << " s after the first snapshot shown\n"
       << "- load average " << run.loadAtStart() << " at the start, " << loadAverage() << " at the end; wall time "
       << benchNumber(wall) << " s\n"
       << "- the worker and the window share this machine's " << std::thread::hardware_concurrency()
       << " hardware threads: on llvmpipe both render on the CPU\n\n"
       << targets.markdown() << "\n" << table.markdown();
    run.write("view_summary.md", md.str());
    std::printf("\n");
    run.printWallTime(wall);
    return 0;
}

}  // namespace ml
