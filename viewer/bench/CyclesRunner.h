// Blender Cycles as a bench's peer: one Blender process running
// viewer/bench/cycles/cornell_cycles.py --serve, which builds the Cornell
// box once (data/cornell_box.obj, set up to compute what `meshlight
// reference` computes; see viewer/bench/cycles/README.md) and then renders
// the jobs it is sent, one camera and sample count each. A render's time is
// Cycles' wall time in that process (bpy.ops.render.render: scene sync, BVH
// and path tracing), without Blender's start-up, which a user pays once per
// session (a walkthrough rendered as an animation, or a still rendered again
// at more samples), and without the EXR write (timed apart).
//
// Blender is optional: findCycles() says why it cannot be used (not on
// PATH, no script) and the benches skip Cycles with that line.
#pragma once

#include "core/Camera.h"
#include "core/image/Image.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <sys/types.h>

namespace ml {

// Where Blender and the script are.
struct CyclesSetup {
    std::string blender;                // the program, as found on PATH or named by MESHLIGHT_BLENDER
    std::filesystem::path script, obj;  // cornell_cycles.py, data/cornell_box.obj
};

// The Blender to use: $MESHLIGHT_BLENDER if set (empty or "none": none), else
// `blender` on PATH; the script and the OBJ from the source tree this binary
// was built from. None, with `why` set, when any of them is missing.
std::optional<CyclesSetup> findCycles(std::string& why);

// One render of a job.
struct CyclesRender {
    ImageRgb image;       // linear radiance, read back from the EXR
    int spp = 0;
    double seconds = 0;   // wall time of bpy.ops.render.render
    double cpuSeconds = 0;
    double pathSeconds = 0;  // Cycles' own path-tracing time (status lines), -1 when not printed
    double saveSeconds = 0;  // the EXR write, not in `seconds`
};

class CyclesRunner {
public:
    // Starts Blender and waits until the scene is built. `bounces`: Cycles'
    // max bounces (Meshlight depth D = D - 1 bounces); `threads` 0: every
    // core. Blender's output goes to `log`. Throws std::runtime_error when
    // Blender cannot be started or ends before it is ready.
    CyclesRunner(const CyclesSetup& setup, int bounces, int threads, const std::filesystem::path& log);
    ~CyclesRunner();  // asks Blender to quit and waits for it
    CyclesRunner(const CyclesRunner&) = delete;
    CyclesRunner& operator=(const CyclesRunner&) = delete;

    // Renders `camera` (the scene's units: the built-in box's millimetres)
    // at width × height and `spp` samples per pixel into `exr`, and reads it
    // back. Throws std::runtime_error when Blender fails or ends.
    CyclesRender render(const Camera& camera, int width, int height, int spp, uint32_t seed,
                        const std::filesystem::path& exr);

    double startupSeconds() const { return startup_; }  // spawn to "ready": Blender's start and the scene
    const std::string& version() const { return version_; }

private:
    // The next "@@cycles ..." line of Blender's output (the others go to the
    // log); throws when Blender's output ends.
    std::string nextAnswer();
    // Asks Blender to quit, waits for it, closes the log; idempotent.
    void shutdown();

    pid_t pid_ = -1;
    int toBlender_ = -1;
    FILE* fromBlender_ = nullptr;
    FILE* log_ = nullptr;
    double startup_ = 0;
    std::string version_;
    void (*oldSigpipe_)(int) = nullptr;
};

}  // namespace ml
