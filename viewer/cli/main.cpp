// meshlight: progressive global illumination by multi-mesh caching with
// hardware sampling (Fournier & Péroche).
#include "Commands.h"
#include "core/Error.h"

#include <cstdio>
#include <exception>

namespace {

const char* kUsage =
    "usage: meshlight <command> [options]\n"
    "commands:\n"
    "  render SCENE   render an image (SCENE: cornell, office[:KEY=VALUE,...], bench, an OBJ or glTF file)\n"
    "  plan SCENE     what a render of SCENE would simulate, and why\n"
    "  probe SCENE    direct and indirect irradiance and lux at sensor points (a CSV, or rtrace's x y z dx dy dz)\n"
    "  grid SCENE     illuminance on a work plane or objects: lux per point, EN 12464-1 statistics, HTML report\n"
    "  reference SCENE --spp N --out REF.exr\n"
    "                 path-traced reference image (and REF.noise.exr, its standard error)\n"
    "  view SCENE     walk through SCENE in a window while its lighting converges\n"
    "  bench direct   accuracy against time of the direct-light samplers\n"
    "  bench scaling  how cost grows with triangles and with lights\n"
    "  bench convergence\n"
    "                 progressive image against the exact one and the path tracer, in time\n"
    "  bench indirect the hemispherical gathers: time and error against the path tracer\n"
    "  bench lights   the office with 3 to 192 panels: time to 10, 5 and 2% against the path tracer\n"
    "  bench view     frame rate, first frame and light-change latency of the viewer\n"
    "  bench report   run the benches and write one HTML page of their results\n"
    "Run 'meshlight <command> --help' for its options.\n";

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fputs(kUsage, stderr);
        return 2;
    }
    // Line-buffered so the plan and the progress (stderr) interleave in order.
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    const std::string command = argv[1];
    const std::vector<std::string> args(argv + 2, argv + argc);
    try {
        if (command == "render") return ml::runRender(args);
        if (command == "probe") return ml::runProbe(args);
        if (command == "grid") return ml::runGrid(args);
        if (command == "plan") return ml::runPlan(args);
        if (command == "bench") return ml::runBench(args);
        if (command == "reference") return ml::runReference(args);
        if (command == "view") return ml::runView(args);
        if (command == "--help" || command == "-h" || command == "help") {
            std::fputs(kUsage, stdout);
            return 0;
        }
        std::fprintf(stderr, "meshlight: unknown command '%s'\n%s", command.c_str(), kUsage);
        return 2;
    } catch (const ml::InputError& e) {
        std::fprintf(stderr, "meshlight: error: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "meshlight: failed: %s\n", e.what());
        return 1;
    }
}
