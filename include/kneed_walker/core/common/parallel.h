// The one way the core spreads per-particle work over the cores: a parallel loop over index
// ranges on TBB's work-stealing scheduler, in an arena of the requested size.
//
// Chosen by measurement (bench_dynamics' batch, 5000 particles × ~6 µs, 2 cores): TBB, OpenCV's parallel_for_ and a hand-written pool of persistent threads
// were within noise of each other; TBB is a well-kept library, lets nested loops share the
// cores, and bounds the thread count per call.
//
// The body must write only to the elements of its own range: results then do not depend on
// the scheduling, so the same seed gives the same output on any number of threads.
#pragma once

#include <functional>

namespace kneed_walker::core::common {

// The number of threads a `threads` option means: itself when ≥ 1, all cores when 0.
int resolveThreads(int threads);

// Calls body(begin, end) on disjoint ranges that cover [0, count), on up to `threads` threads
// (0: all cores; 1: in the caller's thread, in order). `grain` is the smallest range worth a
// task of its own. Returns when all ranges are done.
void parallelFor(int count, int threads, const std::function<void(int begin, int end)>& body,
                 int grain = 16);

}  // namespace kneed_walker::core::common
