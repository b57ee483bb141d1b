#include "core/time.hpp"

#include <gtest/gtest.h>

#include <type_traits>

namespace livod {
namespace {

TEST(Time, ClocksAreDistinctTypes) {
  static_assert(!std::is_convertible_v<SensorTime, HostTime>);
  static_assert(!std::is_convertible_v<HostTime, MappedTime>);
  static_assert(!std::is_convertible_v<std::int64_t, MappedTime>);
}

TEST(Time, ArithmeticWithDurations) {
  const MappedTime t0(1'000'000'000);
  const MappedTime t1 = t0 + Nanoseconds(250);
  EXPECT_EQ(t1.ns, 1'000'000'250);
  EXPECT_EQ((t1 - t0).count(), 250);
  EXPECT_LT(t0, t1);
  EXPECT_EQ(t1 - Nanoseconds(250), t0);
}

TEST(Time, SecondsRoundTripRoundsToNearestNanosecond) {
  EXPECT_EQ(MappedTime::from_seconds(1.0000000004).ns, 1'000'000'000);
  EXPECT_EQ(MappedTime::from_seconds(1.0000000006).ns, 1'000'000'001);
  EXPECT_EQ(MappedTime::from_seconds(-0.5).ns, -500'000'000);
  EXPECT_DOUBLE_EQ(MappedTime(1'500'000'000).seconds(), 1.5);
  EXPECT_EQ(from_seconds(0.001).count(), 1'000'000);
}

TEST(Time, HostNowIsMonotonic) {
  const HostTime a = host_now();
  const HostTime b = host_now();
  EXPECT_LE(a, b);
  EXPECT_GT(a.ns, 0);
}

}  // namespace
}  // namespace livod
