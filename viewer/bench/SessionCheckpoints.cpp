#include "SessionCheckpoints.h"

#include "BenchRun.h"  // secondsSince
#include "core/Error.h"

#include <algorithm>
#include <optional>
#include <thread>

namespace ml {

const CacheSnapshot* firstSnapshot(ProgressiveSession& session, CacheWorker::Reader& reader) {
    for (;;) {
        session.rethrowIfFailed();
        if (const CacheSnapshot* s = reader.acquire()) return s;
        ML_ASSERT(!session.finished(), "the cache worker ended without publishing a snapshot");
        session.waitForVersion(1, 0.05);
    }
}

const CacheSnapshot* snapshotAt(ProgressiveSession& session, CacheWorker::Reader& reader,
                                std::chrono::steady_clock::time_point start, double due) {
    for (double left; (left = due - secondsSince(start)) > 0;) {
        session.rethrowIfFailed();
        std::this_thread::sleep_for(std::chrono::duration<double>(std::min(left, 0.05)));
    }
    return firstSnapshot(session, reader);
}

ViewShown showViewUntilWithin(ProgressiveSession& session, CacheWorker::Reader& reader, Compositor& compositor,
                              const Camera& camera, const CompositorSettings& settings, const Reference& reference,
                              double level, std::chrono::steady_clock::time_point start, double limitSeconds) {
    ViewShown out;
    uint64_t checked = 0;
    for (;;) {
        const CacheSnapshot* s = firstSnapshot(session, reader);
        if (s->version == checked) {
            if (secondsSince(start) >= limitSeconds || session.finished()) break;
            session.waitForVersion(checked + 1, 0.05);
            continue;
        }
        checked = s->version;
        const std::chrono::steady_clock::time_point c = std::chrono::steady_clock::now();
        out.image = compositor.render(camera, s->direct, s->indirect, settings);
        out.compositeSeconds += secondsSince(c);
        ++out.composites;
        out.error = errorAgainst(out.image, reference);
        out.estimatedError = s->estimatedError;
        out.vertices = s->vertices;
        out.reached = out.error.corrected <= level;
        if (out.reached || secondsSince(start) >= limitSeconds) break;
    }
    out.seconds = secondsSince(start);
    return out;
}

double walkViewsUntilWithin(const Scene& scene, const RenderLikeSession& how, Compositor& compositor,
                            const std::vector<Camera>& cameras, const CompositorSettings& settings,
                            const std::vector<Reference>& refs, double level, double firstLimit, double limit,
                            const std::function<void(size_t, ViewShown&&)>& onView) {
    const std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    ProgressiveSession session(scene, how.settings, samplerFactory(scene, how.direct, how.indirect));
    const double made = secondsSince(start);
    std::optional<CacheWorker::Reader> reader;
    for (size_t v = 0; v < cameras.size(); ++v) {
        const std::chrono::steady_clock::time_point viewStart = v == 0 ? start : std::chrono::steady_clock::now();
        const RefinementCamera view{cameras[v], settings.width, settings.height};
        if (v == 0) {
            session.start(view);
            reader.emplace(session.reader());
        } else {
            session.setCamera(view);
        }
        onView(v, showViewUntilWithin(session, *reader, compositor, cameras[v], settings, refs[v], level, viewStart,
                                      v == 0 ? firstLimit : limit));
    }
    session.stop();
    session.rethrowIfFailed();
    return made;
}

}  // namespace ml
