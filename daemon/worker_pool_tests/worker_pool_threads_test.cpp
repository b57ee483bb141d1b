// The estimator's worker pool: every task runs exactly once per call, calls follow each other
// without mixing (a late worker never runs a task of the next call with the previous function),
// results written by workers are visible to the caller, and shutdown joins cleanly. Runs under
// ThreadSanitizer in CI (label "threads").

#include <gtest/gtest.h>

#include <atomic>
#include <numeric>
#include <vector>

#include "daemon/worker_pool.hpp"
#include "estimator/task_runner.hpp"

namespace livod::daemon {
namespace {

TEST(WorkerPool, RunsEveryTaskOncePerCall) {
  WorkerPool pool(4);
  EXPECT_EQ(pool.concurrency(), 4);
  for (std::size_t count : {0U, 1U, 2U, 3U, 17U, 1000U, 4096U}) {
    std::vector<int> hits(count, 0);  // each slot written by exactly one task
    pool.run(count, [&](std::size_t i) { ++hits[i]; });
    for (std::size_t i = 0; i < count; ++i)
      ASSERT_EQ(hits[i], 1) << "count " << count << " i " << i;
  }
}

TEST(WorkerPool, ManyShortCallsDoNotMix) {
  WorkerPool pool(3);
  std::vector<std::uint64_t> slots(64);
  for (std::uint64_t call = 1; call <= 3000; ++call) {
    // Each call writes its own number: a task of an earlier call running late would leave a stale
    // value, a task run twice or never would be caught by the sum.
    std::atomic<std::uint64_t> runs{0};
    pool.run(slots.size(), [&](std::size_t i) {
      slots[i] = call;
      runs.fetch_add(1, std::memory_order_relaxed);
    });
    ASSERT_EQ(runs.load(), slots.size());
    for (const auto v : slots) ASSERT_EQ(v, call);
  }
}

TEST(WorkerPool, SerialPoolRunsOnTheCaller) {
  WorkerPool pool(1);
  EXPECT_EQ(pool.concurrency(), 1);
  const auto caller = std::this_thread::get_id();
  bool all_on_caller = true;
  pool.run(100, [&](std::size_t) {
    all_on_caller = all_on_caller && std::this_thread::get_id() == caller;
  });
  EXPECT_TRUE(all_on_caller);
}

TEST(WorkerPool, ParallelForCoversTheRangeInContiguousPieces) {
  WorkerPool pool(2);
  for (std::size_t n : {1U, 255U, 256U, 257U, 10'000U}) {
    std::vector<int> covered(n, 0);
    estimator::parallel_for(pool, n, 256, [&](std::size_t begin, std::size_t end) {
      ASSERT_LT(begin, end);
      ASSERT_LE(end, n);
      for (std::size_t i = begin; i < end; ++i) ++covered[i];
    });
    EXPECT_EQ(std::accumulate(covered.begin(), covered.end(), 0), static_cast<int>(n));
    EXPECT_TRUE(std::all_of(covered.begin(), covered.end(), [](int c) { return c == 1; }));
  }
}

TEST(WorkerPool, DestroyedRightAfterUse) {
  for (int i = 0; i < 200; ++i) {
    WorkerPool pool(2 + i % 3);
    std::atomic<int> sum{0};
    pool.run(10, [&](std::size_t k) { sum += static_cast<int>(k); });
    ASSERT_EQ(sum.load(), 45);
  }
}

}  // namespace
}  // namespace livod::daemon
