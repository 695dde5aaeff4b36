// `meshlight bench <name>`: the benches that reproduce the paper's measurements.
#include "Commands.h"
#include "Options.h"

#include "core/Error.h"
#include "viewer/bench/BenchDirect.h"

#include <cstdio>

namespace ml {

namespace {

// More benches arrive with later issues; each adds itself here.
const char* const kBenches = "direct";

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

}  // namespace

int runBench(const std::vector<std::string>& args) {
    if (args.empty()) throw InputError(concat("'bench' needs the name of a bench: ", kBenches));
    const std::string& name = args.front();
    const std::vector<std::string> rest(args.begin() + 1, args.end());
    if (name == "direct") return runDirect(rest);
    if (name == "--help" || name == "-h") {
        std::printf("usage: meshlight bench <name> [options]\nbenches: %s\n"
                    "Run 'meshlight bench <name> --help' for its options.\n",
                    kBenches);
        return 0;
    }
    throw InputError(concat("unknown bench '", name, "' (valid: ", kBenches, ")"));
}

}  // namespace ml
