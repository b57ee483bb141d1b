// RecordChannel between two threads: every published record arrives once, in order, with the
// content written by the producer; a full pool drops and counts instead of blocking.

#include "daemon/runtime/record_channel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

namespace livod::daemon::runtime {
namespace {

struct Item {
  std::uint64_t seq = 0;
  std::vector<std::uint64_t> payload;
};

TEST(RecordChannel, FullPoolDropsAndCounts) {
  RecordChannel<Item> ch(2);
  Item* a = ch.acquire();
  Item* b = ch.acquire();
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(ch.acquire(), nullptr);
  EXPECT_EQ(ch.dropped(), 1U);
  ch.publish(a);
  EXPECT_EQ(ch.next(), a);
  EXPECT_EQ(ch.next(), nullptr);
  ch.release(a);
  EXPECT_EQ(ch.acquire(), a);
}

TEST(RecordChannel, TwoThreadsEveryRecordOnceInOrder) {
  constexpr std::uint64_t kRecords = 200'000;
  RecordChannel<Item> ch(8, [](Item& i) { i.payload.reserve(16); });
  std::atomic<bool> done{false};
  std::uint64_t produced = 0;
  std::thread producer([&] {
    std::uint64_t seq = 0;
    while (seq < kRecords) {
      Item* r = ch.acquire();
      if (r == nullptr) {
        std::this_thread::yield();
        continue;
      }
      r->seq = seq;
      r->payload.assign(16, seq * 3 + 1);
      ch.publish(r);
      ++seq;
    }
    produced = seq;
    done.store(true, std::memory_order_release);
  });
  std::uint64_t expected = 0;
  bool ok = true;
  while (expected < kRecords) {
    Item* r = ch.next();
    if (r == nullptr) {
      std::this_thread::yield();
      continue;
    }
    ok = ok && r->seq == expected && r->payload.size() == 16 && r->payload[15] == expected * 3 + 1;
    ++expected;
    ch.release(r);
  }
  producer.join();
  EXPECT_TRUE(ok);
  EXPECT_EQ(produced, kRecords);
  EXPECT_EQ(ch.next(), nullptr);
}

}  // namespace
}  // namespace livod::daemon::runtime
