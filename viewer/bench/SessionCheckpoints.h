// What the convergence benches do at each checkpoint of a running
// ProgressiveSession: wait for the time, then take the latest snapshot.
#pragma once

#include "cache/ProgressiveSession.h"

#include <chrono>

namespace ml {

// The reader's latest snapshot, waiting for the worker's first one if none
// is out yet (that time counts); the worker's failure is rethrown.
const CacheSnapshot* firstSnapshot(ProgressiveSession& session, CacheWorker::Reader& reader);

// Sleeps until `due` seconds after `start` (rethrowing the worker's failure
// meanwhile), then returns firstSnapshot's.
const CacheSnapshot* snapshotAt(ProgressiveSession& session, CacheWorker::Reader& reader,
                                std::chrono::steady_clock::time_point start, double due);

}  // namespace ml
