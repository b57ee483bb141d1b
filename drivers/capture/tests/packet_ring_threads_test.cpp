// PacketRing: fixed-size payload slots over the core SPSC ring; overrun accounting, truncation,
// slot reuse, and a two-thread stress run (also built under ThreadSanitizer).

#include "drivers/capture/packet_ring.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <vector>

namespace livod::drivers::capture {
namespace {

// A payload whose bytes are all derived from `tag`, `size` bytes long (size >= 4).
std::vector<std::byte> payload(std::uint32_t tag, std::size_t size) {
  std::vector<std::byte> p(size);
  for (std::size_t i = 0; i < size; ++i) p[i] = static_cast<std::byte>((tag * 31 + i) & 0xFF);
  std::memcpy(p.data(), &tag, sizeof(tag));
  return p;
}

std::uint32_t tag_of(std::span<const std::byte> bytes) {
  std::uint32_t tag = 0;
  std::memcpy(&tag, bytes.data(), sizeof(tag));
  return tag;
}

bool intact(std::span<const std::byte> bytes) {
  const std::uint32_t tag = tag_of(bytes);
  for (std::size_t i = 4; i < bytes.size(); ++i) {
    if (bytes[i] != static_cast<std::byte>((tag * 31 + i) & 0xFF)) return false;
  }
  return true;
}

TEST(PacketRing, FifoWithMetadataAndOverrunsWhenFull) {
  PacketRing ring(3, 64);
  EXPECT_EQ(ring.capacity(), 3u);
  EXPECT_EQ(ring.max_payload_bytes(), 64u);
  EXPECT_EQ(ring.front(), nullptr);
  for (std::uint32_t t = 0; t < 3; ++t) {
    EXPECT_TRUE(ring.try_push(payload(t, 10 + t), HostTime(1000 + t), 2368));
  }
  EXPECT_EQ(ring.size_approx(), 3u);
  // Full: dropped and counted, never blocking, the queued items untouched.
  EXPECT_FALSE(ring.try_push(payload(99, 20), HostTime(5000), 2368));
  EXPECT_FALSE(ring.try_push(payload(98, 20), HostTime(5001), 2368));
  EXPECT_EQ(ring.overruns(), 2u);
  for (std::uint32_t t = 0; t < 3; ++t) {
    const RawPacket* p = ring.front();
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(tag_of(p->payload), t);
    EXPECT_EQ(p->payload.size(), 10 + t);
    EXPECT_TRUE(intact(p->payload));
    EXPECT_EQ(p->rx.ns, 1000 + static_cast<std::int64_t>(t));
    EXPECT_EQ(p->dst_port, 2368);
    EXPECT_FALSE(p->truncated);
    ring.pop();
  }
  EXPECT_EQ(ring.front(), nullptr);
  EXPECT_EQ(ring.overruns(), 2u);
}

TEST(PacketRing, LongPayloadsAreCutAndFlagged) {
  PacketRing ring(2, 16);
  ASSERT_TRUE(ring.try_push(payload(7, 40), HostTime(1), 7502));
  ASSERT_TRUE(ring.try_push(payload(8, 16), HostTime(2), 7502, /*truncated=*/true));
  const RawPacket* p = ring.front();
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->payload.size(), 16u);
  EXPECT_TRUE(p->truncated);
  EXPECT_TRUE(intact(p->payload));  // the first 16 bytes are the datagram's
  ring.pop();
  p = ring.front();
  ASSERT_NE(p, nullptr);
  EXPECT_TRUE(p->truncated);  // cut by the socket already: the flag is kept
  ring.pop();
  EXPECT_THROW(PacketRing(0, 16), std::invalid_argument);
  EXPECT_THROW(PacketRing(4, 0), std::invalid_argument);
}

TEST(PacketRing, FailedPushesNeverDisturbQueuedPayloadsAcrossManyWraps) {
  // Capacity 2 with interleaved pushes, drops and pops: every payload read back is the one
  // pushed, although failed pushes wrote into the arena.
  PacketRing ring(2, 32);
  std::uint32_t next_tag = 0;
  std::uint32_t expected = 0;
  std::uint64_t dropped = 0;
  for (int round = 0; round < 500; ++round) {
    const int pushes = round % 4;
    for (int i = 0; i < pushes; ++i) {
      if (ring.try_push(payload(next_tag, 4 + (next_tag % 29)), HostTime(next_tag), 1)) {
        ++next_tag;
      } else {
        ++dropped;
        // The dropped payload is rebuilt for the next attempt; the tag sequence stays dense.
      }
    }
    const int pops = (round * 7) % 3;
    for (int i = 0; i < pops; ++i) {
      const RawPacket* p = ring.front();
      if (p == nullptr) break;
      ASSERT_EQ(tag_of(p->payload), expected);
      ASSERT_EQ(p->payload.size(), 4 + (expected % 29));
      ASSERT_TRUE(intact(p->payload));
      ++expected;
      ring.pop();
    }
  }
  EXPECT_EQ(ring.overruns(), dropped);
  EXPECT_GT(dropped, 0u);
  EXPECT_GT(expected, 100u);
}

TEST(PacketRing, ProducerAndConsumerThreadsExchangeIntactPayloads) {
  // A small ring forces constant wrap-around, fullness and emptiness. The consumer checks every
  // byte; the count of received plus dropped equals the count offered.
  PacketRing ring(7, 256);
  constexpr std::uint32_t kOffered = 200'000;
  std::atomic<bool> producer_done{false};
  std::uint64_t received = 0;
  std::uint64_t corrupt = 0;
  std::uint64_t out_of_order = 0;
  std::thread consumer([&] {
    std::int64_t last_rx = -1;
    for (;;) {
      const RawPacket* p = ring.front();
      if (p == nullptr) {
        if (producer_done.load(std::memory_order_acquire) && ring.front() == nullptr) break;
        std::this_thread::yield();
        continue;
      }
      if (!intact(p->payload) || p->payload.size() != 8 + (tag_of(p->payload) % 240)) ++corrupt;
      if (p->rx.ns <= last_rx) ++out_of_order;
      last_rx = p->rx.ns;
      ++received;
      ring.pop();
    }
  });
  std::vector<std::byte> buffer;
  for (std::uint32_t t = 0; t < kOffered; ++t) {
    buffer = payload(t, 8 + (t % 240));
    ring.try_push(buffer, HostTime(t), 9);
  }
  producer_done.store(true, std::memory_order_release);
  consumer.join();
  EXPECT_EQ(corrupt, 0u);
  EXPECT_EQ(out_of_order, 0u);
  EXPECT_EQ(received + ring.overruns(), kOffered);
  EXPECT_GT(received, 0u);
}

}  // namespace
}  // namespace livod::drivers::capture
