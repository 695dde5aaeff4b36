// `meshlight bench <name>`: the benches that reproduce the paper's measurements.
#include "Commands.h"
#include "Options.h"

#include "core/Error.h"
#include "viewer/bench/BenchConvergence.h"
#include "viewer/bench/BenchDirect.h"
#include "viewer/bench/BenchIndirect.h"
#include "viewer/bench/BenchReport.h"
#include "viewer/bench/BenchScaling.h"
#include "viewer/bench/BenchView.h"

#include <cstdio>

namespace ml {

namespace {

// More benches arrive with later issues; each adds itself here.
const char* const kBenches = "direct, scaling, convergence, view, indirect, report";

int runDirect(const std::vector<std::string>& args) {
    const BenchDirectOptions defaults;
    Options o("bench direct");
    o.value("out", "DIR", "folder for the CSVs, plots and summary (made if missing)", defaults.outDir);
    // No default here, so that combining it with --quick can be refused.
    o.value("points-per-side", "N",
            concat("receivers per side of the bench floor, N x N in all (default ", defaults.pointsPerSide,
                   "; --quick uses 20)"));
    o.flag("quick", "CI size: 20x20 points, fewer configurations and passes, no Water scene");
    o.value("gl", "BACKEND", "headless OpenGL: osmesa, egl or auto", glBackendName(defaults.backend));
    o.value("seed", "N", "jitter seed; the same seed repeats a run bit for bit", std::to_string(defaults.seed));
    if (!o.parseOrPrintHelp(args)) return 0;

    BenchDirectOptions options;
    options.outDir = o.str("out");
    options.quick = o.isSet("quick");
    if (o.has("points-per-side")) {
        if (options.quick)
            throw InputError("--points-per-side cannot be combined with --quick, which uses 20 per side");
        options.pointsPerSide = o.integer("points-per-side", 1, 1000);
    }
    options.backend = parseGlBackend(o.str("gl"));
    if (options.backend == GlBackend::Glfw)
        throw InputError("option --gl: the bench needs a headless back end (osmesa, egl or auto), not glfw");
    options.seed = o.seed("seed");
    return runBenchDirect(options);
}

int runScaling(const std::vector<std::string>& args) {
    const BenchScalingOptions defaults;
    Options o("bench scaling");
    o.value("out", "DIR", "folder for the CSVs, plots and summary (made if missing)", defaults.outDir);
    o.flag("quick", "CI size: 1k to 64k triangles, 1 to 8 lights, fewer points");
    o.value("gl", "BACKEND", "headless OpenGL: osmesa, egl or auto", glBackendName(defaults.backend));
    o.value("seed", "N", "jitter and receiver seed; the same seed repeats a run", std::to_string(defaults.seed));
    if (!o.parseOrPrintHelp(args)) return 0;

    BenchScalingOptions options;
    options.outDir = o.str("out");
    options.quick = o.isSet("quick");
    options.backend = parseGlBackend(o.str("gl"));
    if (options.backend == GlBackend::Glfw)
        throw InputError("option --gl: the bench needs a headless back end (osmesa, egl or auto), not glfw");
    options.seed = o.seed("seed");
    return runBenchScaling(options);
}

int runConvergence(const std::vector<std::string>& args) {
    const BenchConvergenceOptions defaults;
    Options o("bench convergence");
    o.value("out", "DIR", "folder for the CSVs, plots and summary (made if missing)", defaults.outDir);
    o.flag("quick", "CI size: still 64x64 for 3 s, walkthrough of 3 views at 32x32");
    o.value("gl", "BACKEND", "headless OpenGL: osmesa, egl or auto", glBackendName(defaults.backend));
    o.value("seed", "N", "jitter seed of the cache's sampler and the path tracer", std::to_string(defaults.seed));
    if (!o.parseOrPrintHelp(args)) return 0;

    BenchConvergenceOptions options;
    options.outDir = o.str("out");
    options.quick = o.isSet("quick");
    options.backend = parseGlBackend(o.str("gl"));
    if (options.backend == GlBackend::Glfw)
        throw InputError("option --gl: the bench needs a headless back end (osmesa, egl or auto), not glfw");
    options.seed = o.seed("seed");
    return runBenchConvergence(options);
}

int runViewBench(const std::vector<std::string>& args) {
    const BenchViewOptions defaults;
    Options o("bench view");
    o.value("out", "DIR", "folder for the CSVs, plots and summary (made if missing)", defaults.outDir);
    o.flag("quick", "CI size: 4 s per scenario, 8 light changes");
    o.value("seed", "N", "the worker's jitter seed", std::to_string(defaults.seed));
    if (!o.parseOrPrintHelp(args)) return 0;

    BenchViewOptions options;
    options.outDir = o.str("out");
    options.quick = o.isSet("quick");
    options.seed = o.seed("seed");
    return runBenchView(options);
}

int runIndirect(const std::vector<std::string>& args) {
    const BenchIndirectOptions defaults;
    Options o("bench indirect");
    o.value("out", "DIR", "folder for the CSVs, plots and summary (made if missing)", defaults.outDir);
    o.flag("quick", "CI size: fewer points, passes and configurations, coarse voxels and proxies");
    o.value("gl", "BACKEND", "headless OpenGL: osmesa, egl or auto", glBackendName(defaults.backend));
    o.value("seed", "N", "points, jitter and path tracer seed; the same seed repeats a run",
            std::to_string(defaults.seed));
    if (!o.parseOrPrintHelp(args)) return 0;

    BenchIndirectOptions options;
    options.outDir = o.str("out");
    options.quick = o.isSet("quick");
    options.backend = parseGlBackend(o.str("gl"));
    if (options.backend == GlBackend::Glfw)
        throw InputError("option --gl: the bench needs a headless back end (osmesa, egl or auto), not glfw");
    options.seed = o.seed("seed");
    return runBenchIndirect(options);
}

int runReport(const std::vector<std::string>& args) {
    const BenchReportOptions defaults;
    Options o("bench report");
    o.value("out", "DIR", "folder for index.html and one subfolder per bench (made if missing)", defaults.outDir);
    o.flag("quick", "every bench in its CI size");
    o.value("gl", "BACKEND", "headless OpenGL: osmesa, egl or auto", glBackendName(defaults.backend));
    o.value("seed", "N", "seed passed to every bench", std::to_string(defaults.seed));
    if (!o.parseOrPrintHelp(args)) return 0;

    BenchReportOptions options;
    options.outDir = o.str("out");
    options.quick = o.isSet("quick");
    options.backend = parseGlBackend(o.str("gl"));
    if (options.backend == GlBackend::Glfw)
        throw InputError("option --gl: the benches need a headless back end (osmesa, egl or auto), not glfw");
    options.seed = o.seed("seed");
    options.commandLine = "meshlight bench report";
    for (const std::string& a : args) options.commandLine += " " + a;
    return runBenchReport(options);
}

}  // namespace

int runBench(const std::vector<std::string>& args) {
    if (args.empty()) throw InputError(concat("'bench' needs the name of a bench: ", kBenches));
    const std::string& name = args.front();
    const std::vector<std::string> rest(args.begin() + 1, args.end());
    if (name == "direct") return runDirect(rest);
    if (name == "scaling") return runScaling(rest);
    if (name == "convergence") return runConvergence(rest);
    if (name == "indirect") return runIndirect(rest);
    if (name == "view") return runViewBench(rest);
    if (name == "report") return runReport(rest);
    if (name == "--help" || name == "-h") {
        std::printf("usage: meshlight bench <name> [options]\nbenches: %s\n"
                    "Run 'meshlight bench <name> --help' for its options.\n",
                    kBenches);
        return 0;
    }
    throw InputError(concat("unknown bench '", name, "' (valid: ", kBenches, ")"));
}

}  // namespace ml
