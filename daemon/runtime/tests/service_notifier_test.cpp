// ServiceNotifier: READY/STATUS/STOPPING and the heartbeat-gated watchdog ping, with a recording
// sender and hand-moved heartbeats (no systemd, no clock).

#include "daemon/runtime/service_notifier.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace livod::daemon::runtime {
namespace {

HostTime at_ms(std::int64_t ms) {
  return HostTime(ms * 1'000'000);
}

struct Sent {
  std::vector<std::string> messages;
  ServiceNotifier::Send sender() {
    return [this](const std::string& m) {
      messages.push_back(m);
      return true;
    };
  }
  [[nodiscard]] int count(const std::string& m) const {
    int n = 0;
    for (const auto& x : messages) n += x == m ? 1 : 0;
    return n;
  }
};

TEST(ServiceNotifier, PingsEveryHalfPeriodWhileEveryThreadAdvances) {
  Sent sent;
  ServiceNotifier n(sent.sender(), Nanoseconds(1'000'000'000));  // WATCHDOG_USEC = 1 s
  std::uint64_t capture = 0;
  std::uint64_t scheduler = 0;
  n.watch("capture", [&] { return capture; });
  n.watch("scheduler", [&] { return scheduler; });
  EXPECT_EQ(n.ping_interval(), Nanoseconds(500'000'000));

  n.ready(at_ms(0), "started");
  ASSERT_EQ(sent.messages.size(), 1U);
  EXPECT_EQ(sent.messages[0], "READY=1\nSTATUS=started");

  ++capture;
  ++scheduler;
  n.tick(at_ms(400));  // not due yet
  EXPECT_EQ(sent.count("WATCHDOG=1"), 0);
  n.tick(at_ms(500));
  EXPECT_EQ(sent.count("WATCHDOG=1"), 1);

  // Only the capture thread beats: the scheduler is stuck; due pings are withheld.
  for (int t = 600; t <= 1500; t += 100) {
    ++capture;
    n.tick(at_ms(t));
  }
  EXPECT_EQ(sent.count("WATCHDOG=1"), 1);
  EXPECT_EQ(n.withheld(), 6U);  // 1000, 1100, ..., 1500

  // One scheduler beat and the withheld ping goes at the next tick, not half a period later.
  ++scheduler;
  n.tick(at_ms(1600));
  EXPECT_EQ(sent.count("WATCHDOG=1"), 2);
  EXPECT_EQ(n.pings(), 2U);
}

TEST(ServiceNotifier, ABeatBeforeThePingIsNotCountedTwice) {
  Sent sent;
  ServiceNotifier n(sent.sender(), Nanoseconds(1'000'000'000));
  std::uint64_t scheduler = 0;
  n.watch("scheduler", [&] { return scheduler; });
  n.ready(at_ms(0), "s");
  ++scheduler;
  n.tick(at_ms(500));
  EXPECT_EQ(n.pings(), 1U);
  // No beat since that ping: the next due ping must not go, however long we wait.
  n.tick(at_ms(1000));
  n.tick(at_ms(5000));
  EXPECT_EQ(n.pings(), 1U);
}

TEST(ServiceNotifier, StatusIsSentOnceWhenItChanges) {
  Sent sent;
  ServiceNotifier n(sent.sender(), std::nullopt);
  n.ready(at_ms(0), "started");
  n.set_status("lidar STREAMING; filter OK 10.0 Hz");
  n.tick(at_ms(100));
  n.tick(at_ms(200));
  n.set_status("lidar STALE; filter SENSOR_STALE 0.0 Hz");
  n.tick(at_ms(300));
  EXPECT_EQ(sent.messages, (std::vector<std::string>{
                               "READY=1\nSTATUS=started",
                               "STATUS=lidar STREAMING; filter OK 10.0 Hz",
                               "STATUS=lidar STALE; filter SENSOR_STALE 0.0 Hz",
                           }));
  EXPECT_FALSE(n.watchdog_enabled());
  EXPECT_EQ(n.pings(), 0U);
}

TEST(ServiceNotifier, NothingAfterStopping) {
  Sent sent;
  ServiceNotifier n(sent.sender(), Nanoseconds(200'000'000));
  std::uint64_t beats = 0;
  n.watch("publisher", [&] { return beats; });
  n.ready(at_ms(0), "s");
  n.stopping("SIGTERM");
  n.stopping("SIGTERM");
  ++beats;
  n.set_status("later");
  n.tick(at_ms(1000));
  ASSERT_EQ(sent.messages.size(), 2U);
  EXPECT_EQ(sent.messages[1], "STOPPING=1\nSTATUS=stopping (SIGTERM)");
}

TEST(ServiceNotifier, NoPingBeforeReady) {
  Sent sent;
  ServiceNotifier n(sent.sender(), Nanoseconds(200'000'000));
  n.tick(at_ms(1000));
  EXPECT_TRUE(sent.messages.empty());
}

TEST(ServiceStatusLine, SensorsStatesAndTheFilterRate) {
  HealthRecord a;
  a.host_time = at_ms(1000);
  a.sensors.resize(2);
  a.sensors[0].name = "front";
  a.sensors[0].state = publish::SensorState::kStreaming;
  a.sensors[1].name = "rear";
  a.sensors[1].state = publish::SensorState::kStale;
  a.estimator.status = PoseStatus::kOk;
  a.estimator.scans_processed = 100;
  EXPECT_EQ(service_status_line(a, nullptr), "front STREAMING, rear STALE; filter OK");
  HealthRecord b = a;
  b.host_time = at_ms(3000);
  b.estimator.scans_processed = 120;
  EXPECT_EQ(service_status_line(b, &a), "front STREAMING, rear STALE; filter OK 10.0 Hz");
}

}  // namespace
}  // namespace livod::daemon::runtime
