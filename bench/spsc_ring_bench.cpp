// Throughput of livod::SpscRing against moodycamel::ReaderWriterQueue (Debian
// libreaderwriterqueue-dev): one producer thread and one consumer thread move a fixed number of
// items through a queue of the same capacity; items/s is reported. The *_OneThread variants give
// the per-operation cost from a single thread. Both queues are driven with the
// same non-blocking calls (try_push/try_enqueue, try_pop/try_dequeue) and the same spin policy.
//
//   build/<dir>/bench/spsc_ring_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only
//
// Results and the machine they were taken on: docs/ring.md.

#include <benchmark/benchmark.h>
#include <readerwriterqueue/readerwriterqueue.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <thread>

#include "core/spsc_ring.hpp"

namespace {

constexpr std::size_t kCapacity = 1024;
constexpr std::uint64_t kItemsPerIteration = 1 << 20;

struct SmallItem {  // 8 B: an index or a pointer-sized handle
  std::uint64_t sequence = 0;
};

struct LargeItem {  // 64 B: about an IMU sample with its stamps
  std::uint64_t sequence = 0;
  std::array<std::uint64_t, 7> payload{};
};
static_assert(sizeof(SmallItem) == 8);
static_assert(sizeof(LargeItem) == 64);

template <class Item>
class LivodQueue {
 public:
  explicit LivodQueue(std::size_t capacity) : ring_(capacity) {}
  bool push(const Item& item) { return ring_.try_push(item); }
  bool pop(Item& item) { return ring_.try_pop(item); }

 private:
  livod::SpscRing<Item> ring_;
};

template <class Item>
class MoodycamelQueue {
 public:
  // Pre-allocates room for `capacity` items; try_enqueue never allocates, so a full queue
  // rejects the push like the livod ring does.
  explicit MoodycamelQueue(std::size_t capacity) : queue_(capacity) {}
  bool push(const Item& item) { return queue_.try_enqueue(item); }
  bool pop(Item& item) { return queue_.try_dequeue(item); }

 private:
  moodycamel::ReaderWriterQueue<Item> queue_;
};

// Spin a while, then yield: with two cores shared by both threads (and possibly other work) pure
// spinning would burn the peer's time slice.
class Backoff {
 public:
  void operator()() {
    if (++spins_ >= kSpinsBeforeYield) {
      spins_ = 0;
      std::this_thread::yield();
    }
  }

 private:
  static constexpr int kSpinsBeforeYield = 64;
  int spins_ = 0;
};

template <class Queue, class Item>
void producer_consumer(benchmark::State& state) {
  std::uint64_t checksum = 0;
  for (auto _ : state) {
    Queue queue(kCapacity);
    std::thread consumer([&queue, &checksum] {
      Item item;
      Backoff backoff;
      std::uint64_t sum = 0;
      for (std::uint64_t received = 0; received < kItemsPerIteration;) {
        if (queue.pop(item)) {
          sum += item.sequence;
          ++received;
        } else {
          backoff();
        }
      }
      checksum += sum;
    });
    Item item;
    Backoff backoff;
    for (std::uint64_t i = 0; i < kItemsPerIteration; ++i) {
      item.sequence = i;
      while (!queue.push(item)) backoff();
    }
    consumer.join();
  }
  benchmark::DoNotOptimize(checksum);
  const std::uint64_t expected = kItemsPerIteration * (kItemsPerIteration - 1) / 2 *
                                 static_cast<std::uint64_t>(state.iterations());
  if (checksum != expected) state.SkipWithError("items lost or duplicated");
  state.SetItemsProcessed(static_cast<std::int64_t>(kItemsPerIteration) * state.iterations());
  state.SetBytesProcessed(static_cast<std::int64_t>(kItemsPerIteration * sizeof(Item)) *
                          state.iterations());
}

// The same queues driven from one thread (a batch pushed, then popped): the per-operation cost
// without any cache-line traffic between cores. Much less sensitive to other load on the machine
// than the two-thread figure, because it is measured in CPU time.
template <class Queue, class Item>
void single_thread(benchmark::State& state) {
  constexpr std::uint64_t kBatch = 256;  // < kCapacity: every push and pop succeeds
  Queue queue(kCapacity);
  Item item;
  std::uint64_t failures = 0;
  for (auto _ : state) {
    for (std::uint64_t i = 0; i < kBatch; ++i) {
      item.sequence = i;
      failures += queue.push(item) ? 0 : 1;
    }
    for (std::uint64_t i = 0; i < kBatch; ++i) {
      failures += queue.pop(item) ? 0 : 1;
      benchmark::DoNotOptimize(item);
    }
  }
  if (failures != 0) state.SkipWithError("push or pop failed");
  // Each item is pushed and popped: items/s counts both operations as one item.
  state.SetItemsProcessed(static_cast<std::int64_t>(kBatch) * state.iterations());
}

void BM_LivodSpscRing_8B(benchmark::State& state) {
  producer_consumer<LivodQueue<SmallItem>, SmallItem>(state);
}
void BM_MoodycamelRWQ_8B(benchmark::State& state) {
  producer_consumer<MoodycamelQueue<SmallItem>, SmallItem>(state);
}
void BM_LivodSpscRing_64B(benchmark::State& state) {
  producer_consumer<LivodQueue<LargeItem>, LargeItem>(state);
}
void BM_MoodycamelRWQ_64B(benchmark::State& state) {
  producer_consumer<MoodycamelQueue<LargeItem>, LargeItem>(state);
}

void BM_LivodSpscRing_8B_OneThread(benchmark::State& state) {
  single_thread<LivodQueue<SmallItem>, SmallItem>(state);
}
void BM_MoodycamelRWQ_8B_OneThread(benchmark::State& state) {
  single_thread<MoodycamelQueue<SmallItem>, SmallItem>(state);
}
void BM_LivodSpscRing_64B_OneThread(benchmark::State& state) {
  single_thread<LivodQueue<LargeItem>, LargeItem>(state);
}
void BM_MoodycamelRWQ_64B_OneThread(benchmark::State& state) {
  single_thread<MoodycamelQueue<LargeItem>, LargeItem>(state);
}

// Real (wall) time: the work happens on two threads, CPU time of the main thread alone would
// overstate the rate.
BENCHMARK(BM_LivodSpscRing_8B)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MoodycamelRWQ_8B)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LivodSpscRing_64B)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MoodycamelRWQ_64B)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LivodSpscRing_8B_OneThread);
BENCHMARK(BM_MoodycamelRWQ_8B_OneThread);
BENCHMARK(BM_LivodSpscRing_64B_OneThread);
BENCHMARK(BM_MoodycamelRWQ_64B_OneThread);

}  // namespace

BENCHMARK_MAIN();
