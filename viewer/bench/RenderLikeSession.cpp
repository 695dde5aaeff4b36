#include "RenderLikeSession.h"

#include "BenchRun.h"

#include "cache/IrradianceCache.h"

namespace ml {

RenderLikeSession renderLikeSession(const BenchRun& run, const Scene& scene) {
    RenderLikeSession s;
    s.direct.seed = run.options().seed;
    s.direct.backend = run.options().backend;
    s.indirect.decide(scene);
    s.settings.worker.seed = s.direct.seed;
    s.settings.worker.refinementLevels = IrradianceCache::kMaxRefinementLevel;
    if (s.indirect.active()) s.settings.indirect = s.indirect.solver;
    return s;
}

}  // namespace ml
