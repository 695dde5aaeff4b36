#include "BenchReport.h"

#include "BenchConvergence.h"
#include "BenchDirect.h"
#include "BenchGi.h"
#include "BenchIndirect.h"
#include "BenchLights.h"
#include "BenchRun.h"
#include "BenchScaling.h"
#include "BenchScenes.h"
#include "BenchView.h"
#include "Gnuplot.h"
#include "ReportHtml.h"

#include "core/Error.h"
#include "core/io/AtomicFile.h"
#include "gpu_sampling/gl/GlContext.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>

#ifndef MESHLIGHT_SOURCE_DIR
#define MESHLIGHT_SOURCE_DIR "."
#endif

namespace ml {

namespace {

namespace fs = std::filesystem;

// --- The sections ----------------------------------------------------------------

// bench direct with its own option at its default (quick mode ignores it).
int runDirect(const BenchOptions& options) {
    BenchDirectOptions direct;
    static_cast<BenchOptions&>(direct) = options;
    return runBenchDirect(direct);
}

}  // namespace

std::vector<ReportSection> reportSections() {
    // Page order; each later bench adds its section here. The fields in
    // ReportSection's order: id, title, about, run, summary, then the
    // figures and the tables.
    return {
        {"direct", "Direct light: error against time per method",
         "Fournier & Péroche §6.1 (Figs. 7–9): every sampling scheme × image size × tests per pixel × estimator on "
         "the bench scene's receiver grid, one pass per point, against the exact visible cosine solid angle (CGAL), "
         "with the median time of each phase of a sample.",
         runDirect, "direct_summary.md",
         {
             {"direct_error_vs_time.png",
              "Error against time: mean and max |error| (% of the unoccluded value) against the median time per "
              "sample, one point per configuration.",
              {"direct_accuracy.csv"}},
             {"direct_phases.png",
              "Time split by phase: median setup, draw, readback and weighting per sample for each configuration "
              "(glFinish between phases).",
              {"direct_accuracy.csv"}},
             {"direct_convergence.png", "Error of the mean of K passes at penumbra receivers.",
              {"direct_convergence.csv"}},
         },
         {
             {"direct_accuracy.csv",
              "Error and time per phase per method (ms per sample; total_ms without glFinish between phases: the "
              "real cost).",
              {"config", "points", "mean_rel_pct", "max_rel_pct", "setup_ms", "draw_ms", "readback_ms",
               "weighting_ms", "timed_total_ms", "total_ms"}},
             {"direct_timing_scenes.csv", "Timings on larger scenes.", {}},
         }},
        {"convergence", "Convergence: progressive image against the path tracer at equal time",
         "Issue 4: the Cornell box, direct light only. A still image: the progressive cache (worker thread, "
         "production settings) composited at fixed elapsed times, and the path tracer (depth 1, every core) at "
         "doubling samples per pixel, both against the exact direct image. A walkthrough with one cache refined all "
         "along, against the path tracer's time to the same error per view. Memory per cached vertex.",
         runBenchConvergence, "convergence_summary.md",
         {
             {"convergence_still.png",
              "Still image: relative RMSE against the exact image over wall-clock time, Meshlight and the path "
              "tracer (labels: samples per pixel); dashed: the targets.",
              {"convergence_still.csv"}},
             {"convergence_walkthrough.png", "Walkthrough: cumulative time over the frames.",
              {"convergence_walkthrough.csv"}},
             {"convergence_walkthrough_error.png", "Walkthrough: relative RMSE per view.",
              {"convergence_walkthrough.csv"}},
         },
         {
             {"convergence_targets.csv", "Targets of issue 4.", {}},
             {"convergence_memory.csv", "Memory per cached vertex, extrapolated to a million vertices.", {}},
         }},
        {"scaling", "Scaling: cost against scene size and number of lights",
         "The bench scene and the Cornell box with every triangle split into 4 recursively, sampled at the same "
         "receivers at every size (the sampler culls occluders with a BVH), with the one-off costs of the sampler, "
         "the cache and the compositor; and the Cornell box with N ceiling lights of constant total power. Growth "
         "exponents are least-squares slopes in log-log.",
         runBenchScaling, "scaling_summary.md",
         {
             {"scaling_triangles_sample.png",
              "Cost per sample at fixed receivers and per estimate of the cache's first pass against the number of "
              "triangles; dashed: least-squares power-law fits.",
              {"scaling_triangles.csv", "scaling_fits.csv"}},
             {"scaling_triangles_setup.png",
              "One-off costs against the number of triangles: occluder BVH, sampler setup, cache build, "
              "compositing.",
              {"scaling_triangles.csv", "scaling_fits.csv"}},
             {"scaling_lights.png", "Costs against the number of lights, total power constant.",
              {"scaling_lights.csv", "scaling_fits.csv"}},
         },
         {
             {"scaling_triangles.csv", "Cost against scene size (ms).",
              {"scene", "triangles", "drawn_triangles", "bvh_build_ms", "setup_ms", "per_sample_ms", "grid_objects",
               "cache_build_ms", "first_pass_estimates", "per_estimate_ms", "composite_ms", "first_image_ms"}},
             {"scaling_lights.csv", "Cost against the number of lights (ms; first_image extrapolated).", {}},
         }},
        {"view", "Viewer: frame rate, first frame and light changes",
         "Issue 6: meshlight view in a real GLFW window (under Xvfb when there is no display), driven by its own "
         "scripts at 1280x720 on the Cornell box: a walk with refinement paused and refining, the same walk over a "
         "cache of about a million triangles, and light changes at a still camera, timed to the end of the frame "
         "that shows them.",
         runBenchView, "view_summary.md",
         {
             {"view_frames.png",
              "Frame time while walking: refinement paused, refining, and over a million-triangle cache.",
              {"view_frames.csv"}},
             {"view_latency.png", "Time from each light change to the end of the frame that shows it.",
              {"view_latency.csv"}},
         },
         {
             {"view_targets.csv", "Targets of issue 6.", {}},
             {"view_scenarios.csv", "Frames per scenario (rates after the first second).", {}},
         }},
        {"indirect", "Indirect light: gather methods, error against time",
         "Fournier & Péroche §6.2 on the Cornell box: one source (the direct cache sampled exactly, as exitant "
         "radiance on the radiance proxy) gathered six ways (voxel slices walked per pixel or drawn as quads, the "
         "voxels ray-marched as a 3D texture, the proxy's triangles in a fish-eye image, one 160-degree "
         "perspective image or a hemicube) at several image sizes and resolutions: time per gather by phase, and "
         "error against the path tracer's one-bounce indirect irradiance and against an exact-geometry gather of "
         "the same source.",
         runBenchIndirect, "indirect_summary.md",
         {
             {"indirect_error_vs_time.png",
              "Error against time: relative RMS error against the path tracer over the points, one gather (solid) "
              "and the mean of K (dashed), against the median time per gather; one curve per method over image "
              "sizes, squares for other resolutions; dotted: the floor (the exact gather of the same source).",
              {"indirect_methods.csv", "indirect_points.csv"}},
             {"indirect_gather_error_vs_time.png",
              "The gathers alone: the same against the exact-geometry gather of the source.",
              {"indirect_methods.csv"}},
             {"indirect_phases.png", "Time split by phase per gather (glFinish between phases).",
              {"indirect_methods.csv"}},
         },
         {
             {"indirect_equal_error.csv",
              "Slices against the perspective triangle gather at equal error (target: 2x).", {}},
             {"indirect_methods.csv", "Every configuration: ms per gather and relative RMS error (%).",
              {"config", "proxy_triangles", "drawn_triangles", "setup_ms", "draw_ms", "readback_ms", "total_ms",
               "rel_rms_pct", "gather_rel_rms_pct", "rel_rms_walls_pct", "rel_rms_blocks_pct",
               "rel_rms_corners_pct"}},
         }},
        {"lights", "Many lights: time to an error level as the lights multiply",
         "The office with 3, 12, 48 and 192 ceiling panels of the same total power, full global illumination: "
         "Meshlight's progressive session composited at fixed times and the path tracer (depth 8) at doubling "
         "samples per pixel, against a path-traced reference, the error corrected for the reference's own noise; "
         "the time to 10%, 5% and 2% for each, their ratio, the exponent of that time in the number of lights, "
         "memory per scene; and a 30-view walkthrough of the 12-panel office, each view until within 5%, against "
         "the path tracer's time for the same views at the same error.",
         runBenchLights, "lights_summary.md",
         {
             {"lights_error_vs_time.png",
              "Relative RMSE (the reference's noise taken out) against wall-clock time, Meshlight (solid) and the "
              "path tracer (dashed) per scene.",
              {"lights_checkpoints.csv"}},
             {"lights_time_to_level.png", "Time to each error level against the number of lights.",
              {"lights_summary.csv", "lights_fits.csv"}},
             {"lights_walkthrough.png",
              "The walkthrough: cumulative time of Meshlight (one cache from cold, each view until within 5%) and "
              "of the path tracer at the same error per view; below, each view's error.",
              {"lights_walkthrough.csv"}},
         },
         {
             {"lights_targets.csv", "Targets of the many-lights issue.", {}},
             {"lights_summary.csv", "Time to each level, Meshlight and the path tracer.", {}},
             {"lights_pairs.csv",
              "Direct-light pairs by how they are answered: below the horizon, nothing in the way (closed form), "
              "the light behind one occluder polygon (zero), few occluders decided on the CPU, rasterised; share "
              "and microseconds each.",
              {}},
         }},
        {"scenes", "Public scenes: render against the path tracer",
         "The scenes of ../shared/scenes as a user renders them: `meshlight render --time T` (left) and "
         "`meshlight reference` (right) of the same view at the reference's exposure, with the relative RMSE and "
         "the mean ratio. A mirror and a glass ball (CornellBox-Sphere: the specular pass and caustics), a water "
         "surface (CornellBox-Water) and the glTF back rooms (textures, 16 lights of which six glowing walls are "
         "gathered).",
         runBenchScenes, "scenes_summary.md",
         {
             {"scenes_sphere.png", "CornellBox-Sphere: render (left), path tracer (right).", {"scenes.csv"}},
             {"scenes_water.png", "CornellBox-Water: render (left), path tracer (right).", {"scenes.csv"}},
             {"scenes_backrooms.png", "The glTF back rooms: render (left), path tracer (right).", {"scenes.csv"}},
         },
         {
             {"scenes.csv", "Relative RMSE and mean ratio of each render against its reference, and the commands.",
              {"scene", "width", "height", "render_s", "reference_spp", "relative_rmse_pct", "mean_ratio"}},
         }},
        {"gi", "Full global illumination: Meshlight, its path tracer and Blender Cycles",
         "Issue 14 (converge to the right answer): the Cornell box at 256x256 with full global illumination (depth "
         "8, Cycles 7 bounces), relative RMSE against a path-traced reference (its noise taken out) over wall-clock "
         "time for Meshlight's progressive render (composited as `render` composites), its path tracer and Blender "
         "Cycles at doubling samples per pixel; the time to 5, 2, 1 and 0.5%; and a walkthrough of 30 views, one "
         "Meshlight cache refined as the views are shown, against Cycles' time to the same error per view. Cycles "
         "is skipped, with a line saying so, where Blender is not installed.",
         runBenchGi, "gi_summary.md",
         {
             {"gi_error_vs_time.png",
              "Relative RMSE (the reference's noise taken out) against wall-clock time: Meshlight (solid), its path "
              "tracer and Cycles (labels: samples per pixel), with the issue's targets.",
              {"gi_curves.csv", "gi_levels.csv"}},
             {"gi_walkthrough.png",
              "Walkthrough: seconds per view for Meshlight and for Cycles at the same error, and Meshlight's error "
              "per view.",
              {"gi_walkthrough.csv"}},
         },
         {
             {"gi_targets.csv", "Targets of issue 14.", {}},
             {"gi_levels.csv", "Seconds to each error level (~: extrapolated).", {}},
         }},
    };
}

namespace {

// --- The machine -------------------------------------------------------------------

// stdout of a shell command, trailing newline dropped; "" when it fails.
std::string commandOutput(const std::string& command) {
    FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) return {};
    std::string out;
    char buf[256];
    while (size_t n = std::fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
    if (::pclose(pipe) != 0) return {};
    while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
    return out;
}

struct HeaderRow {
    std::string name, value;  // plain text
};

std::vector<HeaderRow> machineRows(const BenchReportOptions& options) {
    std::vector<HeaderRow> rows;
    char date[64];
    const std::time_t now = std::time(nullptr);
    std::tm utc{};
    gmtime_r(&now, &utc);
    std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S UTC", &utc);
    rows.push_back({"date", date});
    rows.push_back({"machine", describeMachine()});

    std::string gl;
    try {
        gl = createHeadlessContext(options.backend)->describe();
    } catch (const std::exception& e) {
        gl = concat("no headless context (", glBackendName(options.backend), "): ", e.what());
    }
    rows.push_back({"OpenGL", gl});

    const std::string git = concat("git -C ", shellQuoted(MESHLIGHT_SOURCE_DIR), " ");
    std::string source = commandOutput(git + "log -1 --format='%H (%cs) %s' 2>/dev/null");
    if (source.empty()) {
        source = "unknown (not a git checkout, or git missing)";
    } else if (!commandOutput(git + "status --porcelain --untracked-files=no 2>/dev/null").empty()) {
        source += " — with uncommitted changes";
    }
    rows.push_back({"source", concat(MESHLIGHT_SOURCE_DIR, " at ", source)});
    rows.push_back(
        {"command", options.commandLine.empty() ? std::string("meshlight bench report") : options.commandLine});
    rows.push_back({"options", concat(options.quick ? "quick (CI size)" : "full", ", seed ", options.seed, ", GL ",
                                      glBackendName(options.backend))});
    return rows;
}

// --- The page --------------------------------------------------------------------------

struct Outcome {
    const ReportSection* section = nullptr;
    bool ok = false;
    std::string error;  // when not ok
    double seconds = 0;
};

// A relative URL path: every byte outside [A-Za-z0-9._~/-] percent-encoded.
std::string urlPath(const std::string& path) {
    static const char* hex = "0123456789ABCDEF";
    std::string out;
    for (unsigned char c : path) {
        if (std::isalnum(c) || c == '.' || c == '_' || c == '~' || c == '/' || c == '-') {
            out += char(c);
        } else {
            out += '%';
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    return out;
}

std::string link(const std::string& href, const std::string& text) {
    return concat("<a href=\"", htmlEscape(urlPath(href)), "\">", htmlEscape(text), "</a>");
}

std::string readFile(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream os;
    os << in.rdbuf();
    if (!in && !in.eof()) throwInputError(SourceLocation{path.string()}, "cannot read");
    return os.str();
}

bool isFile(const fs::path& p) {
    std::error_code ec;
    return fs::is_regular_file(p, ec);
}

const char* kStyle = R"(
body { font-family: "DejaVu Sans", Arial, sans-serif; font-size: 15px; line-height: 1.45; color: #1b1b1b;
       max-width: 1160px; margin: 0 auto; padding: 16px 20px 48px; background: #fff; }
h1 { font-size: 26px; margin: 8px 0 12px; }
h2 { font-size: 21px; margin: 36px 0 8px; padding-top: 10px; border-top: 2px solid #3a5f8f; }
h3 { font-size: 17px; margin: 20px 0 6px; }
h4, h5, h6 { font-size: 15px; margin: 14px 0 4px; }
table { border-collapse: collapse; font-size: 13px; margin: 6px 0 12px; }
th, td { border: 1px solid #c8c8c8; padding: 3px 7px; vertical-align: top; text-align: left; }
th { background: #eef1f5; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
table.meta th { width: 90px; }
.scroll { overflow-x: auto; max-width: 100%; }
figure { margin: 14px 0 22px; }
figure img { display: block; max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption, .caption { font-size: 13px; color: #444; margin: 4px 0; }
.summary { background: #f8f9fb; border-left: 4px solid #3a5f8f; padding: 2px 14px; margin: 10px 0; }
.failed { background: #fdecea; border-left: 4px solid #b3261e; padding: 6px 12px; }
.missing { color: #8a5a00; font-size: 13px; }
.files { font-size: 13px; color: #444; }
code { font-size: 13px; background: #f0f0f0; padding: 0 3px; }
)";

// The section's part of the page; files are looked up in outDir/<id>/.
std::string sectionHtml(const Outcome& o, int number, const fs::path& outDir) {
    const ReportSection& s = *o.section;
    const fs::path dir = outDir / s.id;
    std::ostringstream h;
    h << "<section id=\"" << htmlEscape(s.id) << "\">\n<h2>" << number << ". " << htmlEscape(s.title) << "</h2>\n"
      << "<p>" << htmlEscape(s.about) << "</p>\n";
    if (!o.ok)
        h << "<p class=\"failed\">This bench failed after " << concat(std::lround(o.seconds * 10) / 10.0)
          << " s: " << htmlEscape(o.error) << ". What it wrote before failing is shown below.</p>\n";
    if (!s.summary.empty() && isFile(dir / s.summary))
        h << "<div class=\"summary\">\n" << markdownToHtml(readFile(dir / s.summary), 2) << "</div>\n";

    for (const ReportFigure& f : s.figures) {
        const std::string src = s.id + "/" + f.png;
        if (!isFile(dir / f.png)) {
            h << "<p class=\"missing\">Plot not produced: " << htmlEscape(f.png)
              << " (is gnuplot installed?). " << htmlEscape(f.caption) << "</p>\n";
            continue;
        }
        h << "<figure>\n<img src=\"" << htmlEscape(urlPath(src)) << "\" alt=\"" << htmlEscape(f.caption)
          << "\">\n<figcaption>" << htmlEscape(f.caption);
        bool first = true;
        for (const std::string& csv : f.data) {
            if (!isFile(dir / csv)) continue;
            h << (first ? " Data: " : ", ") << link(s.id + "/" + csv, csv);
            first = false;
        }
        h << "</figcaption>\n</figure>\n";
    }

    for (const ReportTable& t : s.tables) {
        if (!isFile(dir / t.csv)) {
            h << "<p class=\"missing\">Table not produced: " << htmlEscape(t.csv) << "</p>\n";
            continue;
        }
        const CsvTable csv = parseCsv(readFile(dir / t.csv), (dir / t.csv).string());
        h << "<h3>" << htmlEscape(t.caption) << "</h3>\n<p class=\"caption\">From "
          << link(s.id + "/" + t.csv, t.csv)
          << (t.columns.empty() || t.columns.size() == csv.header.size() ? "" : " (some columns; all in the CSV)")
          << ".</p>\n<div class=\"scroll\">\n" << htmlTable(csv, t.columns) << "</div>\n";
    }

    // Every file the bench left, so that nothing it wrote is out of reach.
    std::vector<std::string> files;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
        const std::string name = entry.path().filename().string();
        if (name.empty() || name.front() == '.' || !entry.is_regular_file(ec)) continue;  // temporaries
        files.push_back(name);
    }
    std::sort(files.begin(), files.end());
    if (!files.empty()) {
        h << "<p class=\"files\">All files of this bench: ";
        for (size_t i = 0; i < files.size(); ++i) h << (i ? ", " : "") << link(s.id + "/" + files[i], files[i]);
        h << ".</p>\n";
    }
    h << "</section>\n";
    return h.str();
}

// What the page shows of a section whose files could not be read.
std::string brokenSectionHtml(const Outcome& o, int number) {
    return concat("<section id=\"", htmlEscape(o.section->id), "\">\n<h2>", number, ". ",
                  htmlEscape(o.section->title), "</h2>\n<p class=\"failed\">", htmlEscape(o.error),
                  "</p>\n</section>\n");
}

// `bodies`: the sections' HTML, parallel to `outcomes`.
std::string pageHtml(const std::vector<HeaderRow>& header, const std::vector<Outcome>& outcomes,
                     const std::vector<std::string>& bodies) {
    std::ostringstream h;
    h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
         "<title>Meshlight bench report</title>\n<style>"
      << kStyle << "</style>\n</head>\n<body>\n<h1>Meshlight bench report</h1>\n<table class=\"meta\">\n";
    for (const HeaderRow& r : header)
        h << "<tr><th>" << htmlEscape(r.name) << "</th><td>" << htmlEscape(r.value) << "</td></tr>\n";
    h << "</table>\n<p>Benches in this report, in order: ";
    for (size_t i = 0; i < outcomes.size(); ++i) {
        const Outcome& o = outcomes[i];
        h << (i ? "; " : "") << "<a href=\"#" << htmlEscape(o.section->id) << "\">" << htmlEscape(o.section->id)
          << "</a> (" << (o.ok ? "ran in " : "<strong>failed</strong> after ")
          << concat(std::lround(o.seconds * 10) / 10.0) << " s)";
    }
    if (outcomes.empty()) h << "none";
    h << ". Times come from this machine while it ran the benches; other processes disturb them, which is why "
         "the benches report medians.</p>\n<ol>\n";
    for (const Outcome& o : outcomes)
        h << "<li><a href=\"#" << htmlEscape(o.section->id) << "\">" << htmlEscape(o.section->title) << "</a></li>\n";
    h << "</ol>\n";
    for (const std::string& body : bodies) h << body;
    h << "</body>\n</html>\n";
    return h.str();
}

void checkSection(const ReportSection& s) {
    ML_ASSERT(!s.id.empty() && s.id.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-") == std::string::npos,
              "report section id '", s.id, "' must be lower-case letters, digits and '-'");
    ML_ASSERT(bool(s.run), "report section '", s.id, "' has nothing to run");
}

}  // namespace

int runBenchReport(const BenchReportOptions& options, const std::vector<ReportSection>& sections) {
    for (const ReportSection& s : sections) checkSection(s);
    const fs::path outDir(options.outDir);
    makeOutputDirectory(options.outDir);
    const std::vector<HeaderRow> header = machineRows(options);

    std::vector<Outcome> outcomes;
    for (const ReportSection& s : sections) {
        std::printf("\n=== bench %s ===\n", s.id.c_str());
        Outcome o;
        o.section = &s;
        const auto start = std::chrono::steady_clock::now();
        // The report's options, with the bench's own folder.
        BenchOptions bench = options;
        bench.outDir = (outDir / s.id).string();
        try {
            const int code = s.run(bench);
            o.ok = code == 0;
            if (!o.ok) o.error = concat("exit code ", code);
        } catch (const std::exception& e) {
            o.error = e.what();
        }
        o.seconds = secondsSince(start);
        if (!o.ok) std::fprintf(stderr, "meshlight: bench %s failed: %s\n", s.id.c_str(), o.error.c_str());
        outcomes.push_back(std::move(o));
    }

    // A file the section names but cannot be read fails that section, not the page.
    std::vector<std::string> bodies;
    for (size_t i = 0; i < outcomes.size(); ++i) {
        try {
            bodies.push_back(sectionHtml(outcomes[i], int(i) + 1, outDir));
        } catch (const std::exception& e) {
            outcomes[i].ok = false;
            outcomes[i].error = concat("its results could not be shown: ", e.what());
            std::fprintf(stderr, "meshlight: bench %s: %s\n", outcomes[i].section->id.c_str(),
                         outcomes[i].error.c_str());
            bodies.push_back(brokenSectionHtml(outcomes[i], int(i) + 1));
        }
    }
    const fs::path index = outDir / "index.html";
    writeTextFileAtomically(index.string(), pageHtml(header, outcomes, bodies));
    const bool allOk = std::all_of(outcomes.begin(), outcomes.end(), [](const Outcome& o) { return o.ok; });
    std::printf("\nreport: %s (%zu benches, %s)\n", index.string().c_str(), outcomes.size(),
                allOk ? "all ran" : "some failed");
    return allOk ? 0 : 1;
}

}  // namespace ml
