// What the convergence benches do at each checkpoint of a running
// ProgressiveSession: wait for the time, then take the latest snapshot.
#pragma once

#include "NoisyReference.h"
#include "RenderLikeSession.h"

#include "cache/ProgressiveSession.h"
#include "viewer/compositor/Compositor.h"

#include <chrono>
#include <functional>
#include <vector>

namespace ml {

// The reader's latest snapshot, waiting for the worker's first one if none
// is out yet (that time counts); the worker's failure is rethrown.
const CacheSnapshot* firstSnapshot(ProgressiveSession& session, CacheWorker::Reader& reader);

// Sleeps until `due` seconds after `start` (rethrowing the worker's failure
// meanwhile), then returns firstSnapshot's.
const CacheSnapshot* snapshotAt(ProgressiveSession& session, CacheWorker::Reader& reader,
                                std::chrono::steady_clock::time_point start, double due);

// A walkthrough's view as the benches show it (bench gi, bench lights):
// every new snapshot composited until the image is within `level` of the
// view's reference (noise-corrected relative RMSE) or `limitSeconds` have
// passed since `start` (when the view's camera was set; the first view's:
// before the session was made). The session's camera must already be the
// view's. The last composite's image and numbers are returned.
struct ViewShown {
    double seconds = 0;           // from `start` to the last composite's end
    double compositeSeconds = 0;  // of all its composites
    int composites = 0;
    bool reached = false;
    ImageError error;
    double estimatedError = 0;  // the snapshot's
    size_t vertices = 0;        // the snapshot's
    ImageRgb image;
};
ViewShown showViewUntilWithin(ProgressiveSession& session, CacheWorker::Reader& reader, Compositor& compositor,
                              const Camera& camera, const CompositorSettings& settings, const Reference& reference,
                              double level, std::chrono::steady_clock::time_point start, double limitSeconds);

// A walkthrough as the benches time it: one session made from cold as
// `render` makes it (`how`), started on the first camera and set to each
// next one; every view shown by showViewUntilWithin against refs[v] at
// settings' size, within firstLimit seconds for view 0 (whose time
// includes making the session) and `limit` for the others. onView(v, shown)
// takes each view as it ends. The session is stopped and its worker's
// failure rethrown at the end. Returns the seconds the session took to make.
double walkViewsUntilWithin(const Scene& scene, const RenderLikeSession& how, Compositor& compositor,
                            const std::vector<Camera>& cameras, const CompositorSettings& settings,
                            const std::vector<Reference>& refs, double level, double firstLimit, double limit,
                            const std::function<void(size_t, ViewShown&&)>& onView);

}  // namespace ml
