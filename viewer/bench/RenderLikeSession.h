// The session `meshlight render SCENE` makes with its defaults, for the
// benches that time Meshlight as a user runs it (bench gi, bench lights).
#pragma once

#include "cache/ProgressiveSession.h"
#include "gpu_sampling/SamplerFactory.h"

namespace ml {

class BenchRun;

// The production direct sampler, the plan's gather and bounces, the cache's
// default tolerances tightened progressively (every refinement level, as
// `render` refines); seeds and the GL back end from the bench's options.
struct RenderLikeSession {
    DirectChoice direct;
    IndirectChoice indirect;
    SessionSettings settings;

    // The plan's indirect bounces (0: direct light only).
    int bounces() const { return indirect.active() ? indirect.solver.bounces : 0; }
};

RenderLikeSession renderLikeSession(const BenchRun& run, const Scene& scene);

}  // namespace ml
