// `meshlight bench <name>`: the benches that reproduce the paper's measurements.
#include "Commands.h"
#include "Options.h"

#include "core/Error.h"
#include "gpu_sampling/gl/GlContext.h"
#include "viewer/bench/BenchConvergence.h"
#include "viewer/bench/BenchDirect.h"
#include "viewer/bench/BenchDynamic.h"
#include "viewer/bench/BenchGi.h"
#include "viewer/bench/BenchScenes.h"
#include "viewer/bench/BenchIndirect.h"
#include "viewer/bench/BenchLights.h"
#include "viewer/bench/BenchOptions.h"
#include "viewer/bench/BenchReport.h"
#include "viewer/bench/BenchScaling.h"
#include "viewer/bench/BenchView.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace ml {

namespace {

// More benches arrive with later issues; each adds itself here.
const char* const kBenches = "direct, scaling, convergence, view, indirect, lights, dynamic, scenes, gi, report";

// What a bench's --help says of the options every bench takes: the same
// options, in each bench's own words.
struct CommonHelp {
    const char* quick;  // what --quick makes smaller
    const char* seed;   // what --seed drives
    const char* out = "folder for the CSVs, plots and summary (made if missing)";
    // Takes --gl, a headless back end; false for a bench that opens a window
    // of its own (bench view).
    bool headless = true;
    const char* needs = "the bench needs";  // who, in the message that refuses --gl glfw
};

// The options every bench takes (BenchOptions: --out, --quick, --gl,
// --seed), declared and read in one place. A bench declares its own options
// through options() between the constructor (--out) and parse() (the
// rest), so that its --help lists them in that order.
class BenchCommandLine {
public:
    BenchCommandLine(const std::string& bench, const CommonHelp& help, const BenchOptions& defaults)
        : help_(help), defaults_(defaults), options_("bench " + bench) {
        options_.value("out", "DIR", help.out, defaults.outDir);
    }

    Options& options() { return options_; }
    const Options& options() const { return options_; }

    // Declares the rest of the common options and parses `args`; false when
    // --help was given (printed): nothing more to do.
    bool parse(const std::vector<std::string>& args) {
        options_.flag("quick", help_.quick);
        if (help_.headless)
            options_.value("gl", "BACKEND", "headless OpenGL: osmesa, egl or auto", glBackendName(defaults_.backend));
        options_.value("seed", "N", help_.seed, std::to_string(defaults_.seed));
        return options_.parseOrPrintHelp(args);
    }

    // Fills the common part of `into` from the parsed arguments.
    void read(BenchOptions& into) const {
        into.outDir = options_.str("out");
        into.quick = options_.isSet("quick");
        if (help_.headless) {
            into.backend = parseGlBackend(options_.str("gl"));
            if (into.backend == GlBackend::Glfw)
                throw InputError(concat("option --gl: ", help_.needs,
                                        " a headless back end (osmesa, egl or auto), not glfw"));
        }
        into.seed = options_.seed("seed");
    }

private:
    CommonHelp help_;
    BenchOptions defaults_;
    Options options_;
};

// A bench with no options of its own.
int runCommon(const std::string& bench, const CommonHelp& help, const std::vector<std::string>& args,
              int (*run)(const BenchOptions&)) {
    BenchCommandLine command(bench, help, BenchOptions{});
    if (!command.parse(args)) return 0;
    BenchOptions options;
    command.read(options);
    return run(options);
}

int runDirect(const std::vector<std::string>& args) {
    const BenchDirectOptions defaults;
    BenchCommandLine command("direct",
                             {"CI size: 20x20 points, fewer configurations and passes, no Water scene",
                              "jitter seed; the same seed repeats a run bit for bit"},
                             defaults);
    // No default here, so that combining it with --quick can be refused.
    command.options().value("points-per-side", "N",
                            concat("receivers per side of the bench floor, N x N in all (default ",
                                   defaults.pointsPerSide, "; --quick uses 20)"));
    if (!command.parse(args)) return 0;

    BenchDirectOptions options;
    command.read(options);
    if (command.options().has("points-per-side")) {
        if (options.quick)
            throw InputError("--points-per-side cannot be combined with --quick, which uses 20 per side");
        options.pointsPerSide = command.options().integer("points-per-side", 1, 1000);
    }
    return runBenchDirect(options);
}

int runDynamic(const std::vector<std::string>& args) {
    const BenchDynamicOptions defaults;
    BenchCommandLine command("dynamic",
                             {"CI size: 320x180 frames, errors at 64x36 against 64 spp, 3 steps, 8 s after each motion",
                              "jitter seed of the cache's sampler and the path tracer's streams"},
                             defaults);
    command.options().value("realtime", "METHOD",
                            "what stands in for indirect light while the cache catches up, as in 'view': auto, "
                            "volume, vpl, lpv or off (the cache's old bounces)",
                            defaults.realtime.realtime);
    command.options().value("realtime-bounces", "N", RealtimeChoice::kBouncesHelp, defaults.realtime.bouncesText());
    command.options().value("motions", "LIST",
                            "the motions to run, comma-separated: light and block (the Cornell box), panel (the "
                            "office, not with --quick); all: every one the mode runs",
                            "all");
    if (!command.parse(args)) return 0;
    BenchDynamicOptions options;
    command.read(options);
    options.realtime.realtime = command.options().str("realtime");
    options.realtime.methodBounces = RealtimeChoice::parseBounces(command.options().str("realtime-bounces"));
    options.realtime.validate();
    if (const std::string list = command.options().str("motions"); list != "all") {
        std::stringstream names(list);
        for (std::string name; std::getline(names, name, ',');) {
            if (name.empty()) throw InputError(concat("--motions: an empty name in '", list, "'"));
            if (std::find(options.motions.begin(), options.motions.end(), name) != options.motions.end())
                throw InputError(concat("--motions: '", name, "' is named twice"));
            options.motions.push_back(name);
        }
    }
    return runBenchDynamic(options);
}

int runReport(const std::vector<std::string>& args) {
    CommonHelp help{"every bench in its CI size", "seed passed to every bench"};
    help.out = "folder for index.html and one subfolder per bench (made if missing)";
    help.needs = "the benches need";
    BenchCommandLine command("report", help, BenchReportOptions{});
    if (!command.parse(args)) return 0;

    BenchReportOptions options;
    command.read(options);
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
    if (name == "scaling")
        return runCommon(name,
                         {"CI size: 1k to 64k triangles, 1 to 8 lights, fewer points",
                          "jitter and receiver seed; the same seed repeats a run"},
                         rest, runBenchScaling);
    if (name == "convergence")
        return runCommon(name,
                         {"CI size: still 64x64 for 3 s, walkthrough of 3 views at 32x32",
                          "jitter seed of the cache's sampler and the path tracer"},
                         rest, runBenchConvergence);
    if (name == "indirect")
        return runCommon(name,
                         {"CI size: fewer points, passes and configurations, coarse voxels and proxies",
                          "points, jitter and path tracer seed; the same seed repeats a run"},
                         rest, runBenchIndirect);
    if (name == "lights")
        return runCommon(name,
                         {"CI size: 3 and 12 panels at 96x54, 5 s each, a 512-spp reference",
                          "jitter seed of the cache's sampler and the path tracer's streams"},
                         rest, runBenchLights);
    if (name == "dynamic") return runDynamic(rest);
    if (name == "scenes")
        return runCommon(name,
                         {"CI size: 64 pixels wide, 3 s against 64 spp",
                          "the render's and the reference's seed"},
                         rest, runBenchScenes);
    if (name == "gi")
        return runCommon(name,
                         {"CI size: 64x64 for 3 s against 2x128 spp, Cycles to 64 spp, 3 views of 32x32",
                          "jitter seed of the cache's sampler and the path tracer's streams"},
                         rest, runBenchGi);
    if (name == "view") {
        CommonHelp help{"CI size: 4 s per scenario, 8 light changes", "the worker's jitter seed"};
        help.headless = false;  // it opens a GLFW window, as `view` does
        return runCommon(name, help, rest, runBenchView);
    }
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
