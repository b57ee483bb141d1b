// Single-threaded semantics of livod::SpscRing (the two-thread stress is in
// spsc_ring_threads_test.cpp).

#include "core/spsc_ring.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace livod {
namespace {

TEST(SpscRing, PopsInPushOrder) {
  SpscRing<int> ring(4);
  EXPECT_TRUE(ring.try_push(1));
  EXPECT_TRUE(ring.try_push(2));
  EXPECT_TRUE(ring.try_push(3));
  int out = 0;
  ASSERT_TRUE(ring.try_pop(out));
  EXPECT_EQ(out, 1);
  ASSERT_TRUE(ring.try_pop(out));
  EXPECT_EQ(out, 2);
  ASSERT_TRUE(ring.try_pop(out));
  EXPECT_EQ(out, 3);
  EXPECT_FALSE(ring.try_pop(out));
  EXPECT_EQ(out, 3) << "a failed pop must not touch the output";
}

TEST(SpscRing, FullRingRejectsAndCountsOverruns) {
  SpscRing<int> ring(3);
  EXPECT_EQ(ring.capacity(), 3U);
  EXPECT_TRUE(ring.empty_approx());
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(ring.try_push(i));
  EXPECT_EQ(ring.size_approx(), 3U);
  EXPECT_EQ(ring.overruns(), 0U);
  EXPECT_FALSE(ring.try_push(99));
  EXPECT_FALSE(ring.try_emplace(98));
  EXPECT_EQ(ring.overruns(), 2U);
  EXPECT_EQ(ring.size_approx(), 3U);

  int out = -1;
  ASSERT_TRUE(ring.try_pop(out));
  EXPECT_EQ(out, 0);
  EXPECT_TRUE(ring.try_push(3)) << "one slot was freed";
  EXPECT_FALSE(ring.try_push(4));
  EXPECT_EQ(ring.overruns(), 3U);
  for (int expected = 1; expected <= 3; ++expected) {
    ASSERT_TRUE(ring.try_pop(out));
    EXPECT_EQ(out, expected) << "the rejected items must not have entered the ring";
  }
  EXPECT_TRUE(ring.empty_approx());
}

TEST(SpscRing, CapacityOneAlternates) {
  SpscRing<std::uint64_t> ring(1);
  std::uint64_t out = 0;
  for (std::uint64_t i = 0; i < 1000; ++i) {
    ASSERT_TRUE(ring.try_push(i));
    ASSERT_FALSE(ring.try_push(i + 1000));
    ASSERT_EQ(ring.size_approx(), 1U);
    ASSERT_TRUE(ring.try_pop(out));
    ASSERT_EQ(out, i);
    ASSERT_FALSE(ring.try_pop(out));
  }
  EXPECT_EQ(ring.overruns(), 1000U);
}

TEST(SpscRing, ZeroCapacityIsRejected) {
  EXPECT_THROW(SpscRing<int>(0), std::invalid_argument);
}

TEST(SpscRing, WrapsAroundManyTimesKeepingOrder) {
  // Capacity 5 (not a power of two) with a fill level that varies, so the indices wrap at every
  // possible offset.
  SpscRing<std::uint32_t> ring(5);
  std::uint32_t next_in = 0;
  std::uint32_t next_out = 0;
  for (int round = 0; round < 20000; ++round) {
    const int pushes = 1 + round % 5;
    const int pops = 1 + (round * 7) % 5;
    for (int i = 0; i < pushes; ++i) {
      if (ring.try_push(next_in)) ++next_in;
    }
    for (int i = 0; i < pops; ++i) {
      std::uint32_t out = 0;
      if (!ring.try_pop(out)) break;
      ASSERT_EQ(out, next_out);
      ++next_out;
    }
    ASSERT_EQ(ring.size_approx(), next_in - next_out);
    ASSERT_LE(ring.size_approx(), ring.capacity());
  }
  EXPECT_GT(next_out, 40000U) << "the loop must actually move items through";
}

struct Point3 {
  Point3(double x_in, double y_in, double z_in) : x(x_in), y(y_in), z(z_in) {}
  double x, y, z;
};

TEST(SpscRing, EmplaceConstructsInPlace) {
  static_assert(!std::is_default_constructible_v<Point3>);
  SpscRing<Point3> ring(2);
  EXPECT_TRUE(ring.try_emplace(1.0, 2.0, 3.0));
  Point3* front = ring.front();
  ASSERT_NE(front, nullptr);
  EXPECT_EQ(front->x, 1.0);
  EXPECT_EQ(front->y, 2.0);
  EXPECT_EQ(front->z, 3.0);
  ring.pop();
  EXPECT_EQ(ring.front(), nullptr);
}

TEST(SpscRing, MoveOnlyItems) {
  SpscRing<std::unique_ptr<int>> ring(2);
  auto a = std::make_unique<int>(7);
  EXPECT_TRUE(ring.try_push(std::move(a)));
  EXPECT_EQ(a, nullptr);
  EXPECT_TRUE(ring.try_emplace(std::make_unique<int>(8)));

  auto rejected = std::make_unique<int>(9);
  EXPECT_FALSE(ring.try_push(std::move(rejected)));
  ASSERT_NE(rejected, nullptr) << "a failed push must leave the argument intact";
  EXPECT_EQ(*rejected, 9);

  std::unique_ptr<int> out;
  ASSERT_TRUE(ring.try_pop(out));
  ASSERT_NE(out, nullptr);
  EXPECT_EQ(*out, 7);
  ASSERT_TRUE(ring.try_pop(out));
  EXPECT_EQ(*out, 8);
}

TEST(SpscRing, FrontGivesInPlaceAccessWithoutCopies) {
  // A large, heap-owning item (like a scan): the consumer works on it where it lies.
  SpscRing<std::vector<float>> ring(2);
  std::vector<float> scan(100000, 1.5F);
  const float* storage = scan.data();
  ASSERT_TRUE(ring.try_push(std::move(scan)));
  std::vector<float>* front = ring.front();
  ASSERT_NE(front, nullptr);
  EXPECT_EQ(front->data(), storage) << "moved in, not copied";
  (*front)[0] = 2.5F;  // the consumer may modify the item in place
  EXPECT_EQ(ring.front(), front) << "front() is stable until pop()";
  EXPECT_EQ((*ring.front())[0], 2.5F);
  ring.pop();
  EXPECT_EQ(ring.front(), nullptr);
}

// Counts live instances and copies so destruction and copy/move behaviour can be checked.
struct Tracked {
  static inline int live = 0;
  static inline int copies = 0;
  explicit Tracked(int v) : value(v) { ++live; }
  Tracked(const Tracked& other) : value(other.value) {
    ++live;
    ++copies;
  }
  Tracked(Tracked&& other) noexcept : value(other.value) { ++live; }
  Tracked& operator=(const Tracked& other) {
    value = other.value;
    ++copies;
    return *this;
  }
  Tracked& operator=(Tracked&& other) noexcept {
    value = other.value;
    return *this;
  }
  ~Tracked() { --live; }
  int value;
};

TEST(SpscRing, DestroysLeftoverItemsAndEveryPoppedItem) {
  Tracked::live = 0;
  Tracked::copies = 0;
  {
    SpscRing<Tracked> ring(8);
    for (int i = 0; i < 6; ++i) ASSERT_TRUE(ring.try_emplace(i));
    EXPECT_EQ(Tracked::live, 6);
    Tracked out(-1);
    ASSERT_TRUE(ring.try_pop(out));
    EXPECT_EQ(out.value, 0);
    EXPECT_EQ(Tracked::live, 6) << "5 in the ring + out";
    ring.pop();  // destroys item 1 in place
    EXPECT_EQ(Tracked::live, 5);
    EXPECT_EQ(Tracked::copies, 0) << "emplace, pop and try_pop never copy";
    // Wrap the indices so the leftovers straddle the end of the storage.
    for (int i = 6; i < 9; ++i) ASSERT_TRUE(ring.try_push(Tracked(i)));
    EXPECT_EQ(Tracked::live, 8) << "7 in the ring + out; the moved-from temporaries are gone";
    const Tracked copied(9);
    ASSERT_TRUE(ring.try_push(copied));
    EXPECT_EQ(Tracked::copies, 1);
    EXPECT_EQ(Tracked::live, 10);
    EXPECT_EQ(ring.size_approx(), 8U);
    EXPECT_FALSE(ring.try_emplace(10)) << "full";
    EXPECT_EQ(Tracked::live, 10) << "a rejected emplace constructs nothing";
  }
  EXPECT_EQ(Tracked::live, 0) << "the ring destructor must destroy the 8 items left in it";
}

struct ThrowsOnCopy {
  explicit ThrowsOnCopy(bool t) : throw_on_copy(t) {}
  ThrowsOnCopy(const ThrowsOnCopy& other) : throw_on_copy(other.throw_on_copy) {
    if (throw_on_copy) throw std::runtime_error("copy");
  }
  ThrowsOnCopy& operator=(const ThrowsOnCopy&) = default;
  bool throw_on_copy;
};

TEST(SpscRing, ThrowingConstructorLeavesRingUnchanged) {
  SpscRing<ThrowsOnCopy> ring(2);
  const ThrowsOnCopy bad(true);
  EXPECT_THROW(ring.try_push(bad), std::runtime_error);
  EXPECT_TRUE(ring.empty_approx());
  EXPECT_EQ(ring.front(), nullptr);
  const ThrowsOnCopy good(false);
  EXPECT_TRUE(ring.try_push(good));
  EXPECT_EQ(ring.size_approx(), 1U);
}

TEST(SpscRing, IndicesDoNotShareCacheLines) {
  // The layout promise of the header: producer and consumer state are a cache line apart.
  EXPECT_GE(sizeof(SpscRing<char>), 3 * kCacheLineBytes);
  EXPECT_EQ(alignof(SpscRing<char>), kCacheLineBytes);
  // Slot storage starts on a cache line (64 B items then occupy exactly one line each).
  SpscRing<std::array<std::uint64_t, 8>> ring(4);
  ASSERT_TRUE(ring.try_emplace());
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(ring.front()) % kCacheLineBytes, 0U);
}

TEST(SpscRing, StringsSurviveWrapAround) {
  SpscRing<std::string> ring(3);
  std::string out;
  for (int i = 0; i < 1000; ++i) {
    // Long enough to defeat the small-string buffer, so a lost destructor would leak (ASan).
    ASSERT_TRUE(ring.try_push(std::string(40, static_cast<char>('a' + i % 26))));
    if (i % 2 == 1) {
      ASSERT_TRUE(ring.try_pop(out));
      ASSERT_TRUE(ring.try_pop(out));
      ASSERT_EQ(out, std::string(40, static_cast<char>('a' + i % 26)));
    }
  }
}

}  // namespace
}  // namespace livod
