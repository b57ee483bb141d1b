// HeartbeatMonitor: ages, stuck threads, and the watchdog's "every thread advanced" question.

#include "daemon/runtime/heartbeat.hpp"

#include <gtest/gtest.h>

namespace livod::daemon::runtime {
namespace {

HostTime at_ms(std::int64_t ms) {
  return HostTime(ms * 1'000'000);
}

TEST(HeartbeatMonitor, AgeCountsFromTheLastMove) {
  Heartbeat a;
  std::uint64_t b = 0;
  HeartbeatMonitor m(Nanoseconds(1'000'000'000));
  m.add("a", [&a] { return a.beats(); });
  m.add("b", [&b] { return b; });

  auto beats = m.update(at_ms(0));
  ASSERT_EQ(beats.size(), 2U);
  EXPECT_EQ(beats[0].name, "a");
  EXPECT_EQ(beats[0].age, Nanoseconds(0));

  a.beat();
  beats = m.update(at_ms(400));
  EXPECT_EQ(beats[0].beats, 1U);
  EXPECT_EQ(beats[0].age, Nanoseconds(0));
  EXPECT_EQ(beats[1].age, Nanoseconds(400'000'000));
  EXPECT_FALSE(beats[1].stuck);

  beats = m.update(at_ms(1500));
  EXPECT_EQ(beats[0].age, Nanoseconds(1'100'000'000));
  EXPECT_TRUE(beats[0].stuck);
  EXPECT_TRUE(beats[1].stuck);

  b = 7;
  beats = m.update(at_ms(1600));
  EXPECT_FALSE(beats[1].stuck);
  EXPECT_EQ(beats[1].beats, 7U);
}

TEST(HeartbeatMonitor, AdvancedSinceLastNeedsEveryThread) {
  Heartbeat a;
  Heartbeat b;
  HeartbeatMonitor m(Nanoseconds(1'000'000'000));
  m.add("a", [&a] { return a.beats(); });
  m.add("b", [&b] { return b.beats(); });
  EXPECT_FALSE(m.advanced_since_last());  // nothing moved since registration
  a.beat();
  EXPECT_FALSE(m.advanced_since_last());  // b did not
  a.beat();
  b.beat();
  EXPECT_TRUE(m.advanced_since_last());
  EXPECT_FALSE(m.advanced_since_last());  // nothing since the previous question
}

}  // namespace
}  // namespace livod::daemon::runtime
