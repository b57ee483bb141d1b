// Two-thread stress of livod::SpscRing: exact order and count across real threads. Also runs under
// ThreadSanitizer in CI (file name ends in _threads_test), which checks that the acquire/release
// protocol publishes every item before the consumer reads it and frees every slot before the
// producer reuses it.

#include "core/spsc_ring.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace livod {
namespace {

// A sequence number plus a value derived from it: a torn or stale slot read shows up as a
// mismatch between the two halves, not only as an order error.
struct Token {
  std::uint64_t sequence = 0;
  std::uint64_t check = 0;
};

constexpr std::uint64_t check_of(std::uint64_t sequence) {
  return (sequence * 0x9E3779B97F4A7C15ULL) ^ 0xD1B54A32D192ED03ULL;
}

// Spin on a failed try_*: yield so that, on a machine with fewer free cores than threads, the
// peer gets the CPU instead of waiting for the spinner's time slice to end.
inline void back_off() {
  std::this_thread::yield();
}

struct StressResult {
  std::uint64_t received = 0;
  std::uint64_t order_errors = 0;
  std::uint64_t check_errors = 0;
  std::uint64_t failed_pushes = 0;
};

StressResult run_stress(std::uint64_t count, SpscRing<Token>& ring) {
  StressResult result;
  std::thread consumer([&] {
    std::uint64_t expected = 0;
    Token token;
    while (expected < count) {
      if (!ring.try_pop(token)) {
        back_off();
        continue;
      }
      if (token.sequence != expected) ++result.order_errors;
      if (token.check != check_of(token.sequence)) ++result.check_errors;
      expected = token.sequence + 1;  // resynchronise so one error is not counted forever
      ++result.received;
    }
  });
  std::uint64_t failed = 0;
  for (std::uint64_t i = 0; i < count; ++i) {
    const Token token{i, check_of(i)};
    while (!ring.try_push(token)) {
      ++failed;
      back_off();
    }
  }
  consumer.join();
  result.failed_pushes = failed;
  return result;
}

TEST(SpscRingThreads, TenMillionItemsArriveExactlyOnceInOrder) {
  constexpr std::uint64_t kCount = 10'000'000;
  SpscRing<Token> ring(1024);
  const StressResult r = run_stress(kCount, ring);
  EXPECT_EQ(r.received, kCount);
  EXPECT_EQ(r.order_errors, 0U);
  EXPECT_EQ(r.check_errors, 0U);
  EXPECT_EQ(ring.overruns(), r.failed_pushes) << "every failed push is counted, nothing else";
  EXPECT_TRUE(ring.empty_approx());
}

TEST(SpscRingThreads, TinyRingWrapsAndFillsConstantly) {
  // Capacity 3: the indices wrap every 4 items and the producer hits "full" all the time, so the
  // cached-index refresh paths on both sides run constantly. A third thread polls the monitoring
  // accessors concurrently, as the health thread does.
  constexpr std::uint64_t kCount = 1'000'000;
  SpscRing<Token> ring(3);
  std::atomic<bool> done{false};
  std::uint64_t max_seen_size = 0;
  std::uint64_t last_overruns = 0;
  bool overruns_monotonic = true;
  std::thread monitor([&] {
    while (!done.load(std::memory_order_acquire)) {
      const std::uint64_t size = ring.size_approx();
      if (size > max_seen_size) max_seen_size = size;
      const std::uint64_t overruns = ring.overruns();
      if (overruns < last_overruns) overruns_monotonic = false;
      last_overruns = overruns;
      std::this_thread::yield();
    }
  });
  const StressResult r = run_stress(kCount, ring);
  done.store(true, std::memory_order_release);
  monitor.join();

  EXPECT_EQ(r.received, kCount);
  EXPECT_EQ(r.order_errors, 0U);
  EXPECT_EQ(r.check_errors, 0U);
  EXPECT_EQ(ring.overruns(), r.failed_pushes);
  EXPECT_LE(max_seen_size, 3U) << "size_approx never exceeds the capacity";
  EXPECT_TRUE(overruns_monotonic);
}

TEST(SpscRingThreads, InPlaceConsumerOfHeapOwningItems) {
  // Items that own heap memory, consumed in place through front()/pop(): checks that the
  // consumer sees fully constructed items and that the producer's reuse of a slot happens after
  // the consumer's destruction of the previous occupant.
  constexpr std::uint32_t kCount = 100'000;
  SpscRing<std::vector<std::uint32_t>> ring(8);
  std::uint64_t errors = 0;
  std::uint32_t received = 0;
  std::thread consumer([&] {
    while (received < kCount) {
      std::vector<std::uint32_t>* item = ring.front();
      if (item == nullptr) {
        back_off();
        continue;
      }
      const std::uint32_t length = 1 + received % 17;
      if (item->size() != length) {
        ++errors;
      } else {
        for (std::uint32_t k = 0; k < length; ++k) {
          if ((*item)[k] != received + k) ++errors;
        }
      }
      ring.pop();
      ++received;
    }
  });
  for (std::uint32_t i = 0; i < kCount; ++i) {
    const std::uint32_t length = 1 + i % 17;
    std::vector<std::uint32_t> item(length);
    for (std::uint32_t k = 0; k < length; ++k) item[k] = i + k;
    while (!ring.try_push(std::move(item))) back_off();
  }
  consumer.join();
  EXPECT_EQ(received, kCount);
  EXPECT_EQ(errors, 0U);
  EXPECT_EQ(ring.front(), nullptr);
}

}  // namespace
}  // namespace livod
