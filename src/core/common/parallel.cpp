#include "kneed_walker/core/common/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>

namespace kneed_walker::core::common {

int resolveThreads(int threads) {
  return threads >= 1 ? threads : std::max(1, tbb::info::default_concurrency());
}

void parallelFor(int count, int threads, const std::function<void(int begin, int end)>& body,
                 int grain) {
  if (count <= 0) return;
  threads = resolveThreads(threads);
  if (threads == 1 || count <= grain) {
    body(0, count);
    return;
  }
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, count, std::max(1, grain)),
                      [&](const tbb::blocked_range<int>& range) { body(range.begin(), range.end()); });
  });
}

}  // namespace kneed_walker::core::common
