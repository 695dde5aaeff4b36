#include "SessionCheckpoints.h"

#include "BenchRun.h"  // secondsSince
#include "core/Error.h"

#include <algorithm>
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

}  // namespace ml
