// What every bench is told: where to write, in which size, on which OpenGL
// back end and with which seed. `meshlight bench <name>` reads it from the
// same four options (--out, --quick, --gl, --seed) for every bench, and the
// report hands its own to each bench with the bench's folder as outDir.
#pragma once

#include <cstdint>
#include <string>

namespace ml {

enum class GlBackend;

struct BenchOptions {
    // The defaults below; out of line, where GlBackend is defined, so that
    // the benches' headers need not include GL's.
    BenchOptions();

    std::string outDir = "bench-out";  // made if missing; files in it are replaced whole
    // CI size: seconds to a minute on a CPU rasteriser instead of minutes;
    // what it makes smaller, each bench's header says.
    bool quick = false;
    // GlBackend::OsMesa by default; headless only: OsMesa, Egl or Auto.
    // bench view draws in a GLFW window of its own and does not read it.
    GlBackend backend;
    // Jitter, points and path tracer streams, as each bench's header says:
    // the same seed repeats a run, as far as its timing allows.
    uint32_t seed = 1;
};

}  // namespace ml
