// Work spread over threads where each item is independent of the others:
// the benches' CPU references (exact images, exact-geometry gathers), the
// irradiance volume's probes (gpu_sampling/indirect/IrradianceVolume.h).
// New threads inherit the caller's niceness (Linux), so helpers of a thread
// running at the frames' priority run at it too.
#pragma once

#include <cstddef>
#include <functional>

namespace ml {

// Runs work(i) for every i in [0, count) on `threads` threads, handing out
// items one at a time so that uneven items balance. Once an item throws, no
// more are handed out; when every thread has stopped, the first exception
// is rethrown on the calling thread. With one thread (or at most one item)
// the items run in order on the calling thread, which starts none.
void parallelFor(size_t count, int threads, const std::function<void(size_t)>& work);

}  // namespace ml
