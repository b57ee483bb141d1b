// Doorbell: a consumer that sleeps only when its ring is empty never misses a ring. The consumer
// waits with a timeout far longer than the test: a lost wake-up would hang it (ctest's timeout
// fails it), a kept one lets 100 000 items through, each after a possible sleep.

#include "drivers/capture/doorbell.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "core/spsc_ring.hpp"

namespace livod::drivers::capture {
namespace {

TEST(Doorbell, RingBeforeWaitReturnsAtOnce) {
  Doorbell bell;
  const std::uint32_t token = bell.prepare();
  bell.ring();
  bell.wait(token, Nanoseconds(3'600'000'000'000));  // would hang for an hour if it slept
  SUCCEED();
}

TEST(Doorbell, TimesOutWhenNobodyRings) {
  Doorbell bell;
  bell.wait(bell.prepare(), Nanoseconds(1'000'000));
  EXPECT_EQ(bell.wakes(), 0U);
}

TEST(Doorbell, NoLostWakeUps) {
  constexpr std::uint64_t kItems = 100'000;
  SpscRing<std::uint64_t> ring(64);
  Doorbell bell;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kItems; ++i) {
      while (!ring.try_push(i)) std::this_thread::yield();
      bell.ring();
      // Let the consumer fall asleep now and then, so that both orders are exercised.
      if (i % 64 == 0) std::this_thread::yield();
    }
  });
  std::uint64_t expected = 0;
  bool in_order = true;
  while (expected < kItems) {
    const std::uint32_t token = bell.prepare();
    std::uint64_t v = 0;
    if (ring.try_pop(v)) {
      in_order = in_order && v == expected;
      ++expected;
      continue;
    }
    bell.wait(token, Nanoseconds(3'600'000'000'000));
  }
  producer.join();
  EXPECT_TRUE(in_order);
}

}  // namespace
}  // namespace livod::drivers::capture
