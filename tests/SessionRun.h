// Running a ProgressiveSession to a stop rule in a test, on the calling
// thread: the start, read and stop the tests share.
#pragma once

#include "cache/ProgressiveSession.h"

namespace ml::test {

// Starts `session`, refines until `stop` holds and stops its worker. A
// worker's failure is rethrown here (ProgressiveSession::refineUntil).
inline void refineUntilStopped(ProgressiveSession& session, const StopRule& stop) {
    session.start();
    CacheWorker::Reader reader = session.reader();
    session.refineUntil(reader, stop, 0);
    session.stop();
}

}  // namespace ml::test
