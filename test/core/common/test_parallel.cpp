#include "kneed_walker/core/common/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

namespace kneed_walker::core::common {
namespace {

TEST(Parallel, CoversEveryIndexOnce) {
  for (int threads : {0, 1, 2, 3}) {
    for (int count : {0, 1, 15, 16, 17, 1000, 5001}) {
      std::vector<int> visits(count, 0);
      parallelFor(count, threads, [&](int begin, int end) {
        ASSERT_LE(0, begin);
        ASSERT_LE(begin, end);
        ASSERT_LE(end, count);
        for (int i = begin; i < end; ++i) ++visits[i];
      });
      for (int i = 0; i < count; ++i) ASSERT_EQ(visits[i], 1) << "index " << i << " of " << count;
    }
  }
}

TEST(Parallel, OneThreadRunsInTheCallersThreadInOrder) {
  std::vector<int> order;
  const auto caller = std::this_thread::get_id();
  parallelFor(100, 1, [&](int begin, int end) {
    EXPECT_EQ(std::this_thread::get_id(), caller);
    for (int i = begin; i < end; ++i) order.push_back(i);
  });
  ASSERT_EQ(order.size(), 100u);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(order[i], i);
}

TEST(Parallel, UsesNoMoreThreadsThanAsked) {
  std::mutex mutex;
  std::set<std::thread::id> ids;
  std::atomic<int> running{0}, most{0};
  parallelFor(2000, 2, [&](int begin, int end) {
    const int now = ++running;
    int seen = most.load();
    while (now > seen && !most.compare_exchange_weak(seen, now)) {}
    {
      std::lock_guard<std::mutex> lock(mutex);
      ids.insert(std::this_thread::get_id());
    }
    volatile double sink = 0;
    for (int i = begin; i < end; ++i)
      for (int k = 0; k < 2000; ++k) sink = sink + k;
    --running;
  }, 8);
  EXPECT_LE(most.load(), 2);
  EXPECT_GE(ids.size(), 1u);
}

TEST(Parallel, ResolvesZeroToAllCores) {
  EXPECT_EQ(resolveThreads(3), 3);
  EXPECT_GE(resolveThreads(0), 1);
}

}  // namespace
}  // namespace kneed_walker::core::common
