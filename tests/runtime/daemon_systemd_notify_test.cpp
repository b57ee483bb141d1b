// The daemon as a systemd Type=notify service, without systemd: the test binds the AF_UNIX datagram
// socket systemd would (an abstract address in NOTIFY_SOCKET), sets WATCHDOG_USEC, runs the daemon
// in-process on a simulated Mid-360 streamed over loopback, and reads what the daemon tells the
// service manager:
//   READY=1 once the sockets are bound; STATUS= lines with the sensor's state;
//   WATCHDOG=1 every half period while healthy, also once the sensor has gone silent (idle is not
//   stuck); no WATCHDOG=1 later than one watchdog period after the scheduler is stalled (systemd
//   would restart it), and pings again once it runs; STOPPING=1 on SIGTERM, then exit 0.

#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "daemon/config/sensor_models.hpp"
#include "daemon/runtime/daemon.hpp"
#include "tests/replay/sim_replay.hpp"
#include "tests/runtime/fake_service_manager.hpp"
#include "tests/runtime/udp_replayer.hpp"

namespace livod {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;
using test::FakeServiceManager;

bool starts_with(const std::string& s, const std::string& prefix) {
  return s.rfind(prefix, 0) == 0;
}

double seconds_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

TEST(DaemonSystemdNotify, ReadyWatchdogGatedOnHeartbeatsStopping) {
  const auto folder = test::simulate(sim::make_scenario("room_handheld_mid360"), 6.0, "notify");
  daemon::LivodConfig config = test::load_clean_config(folder / "config.yaml");
  for (auto& s : config.sensors) {
    if (!daemon::is_packet_lidar(s.driver)) continue;
    daemon::UdpSourceConfig udp;
    udp.bind_address = "127.0.0.1";
    udp.sensor_address = "127.0.0.1";
    udp.ports = daemon::default_ports(s.driver, s.model);
    s.source = udp;
  }
  config.health.period_s = 0.2;
  config.health.stale_after_s = 0.5;

  // WATCHDOG_USEC = 2 s: pings every second.
  constexpr double kWatchdogS = 2.0;
  FakeServiceManager manager;
  ::setenv("NOTIFY_SOCKET", manager.address().c_str(), 1);
  ::setenv("WATCHDOG_USEC", "2000000", 1);
  ::unsetenv("WATCHDOG_PID");

  std::atomic<bool> stall{false};
  Clock::time_point t_stall;
  Clock::time_point t_release;
  Clock::time_point t_term;
  std::atomic<std::int64_t> sender_end_ns{0};
  std::thread sender;
  std::thread controller;
  std::stop_source sender_stop;
  const pthread_t daemon_thread = pthread_self();

  daemon::runtime::DaemonOptions options;
  options.ephemeral_ports = true;
  options.notify_systemd = true;
  options.out_dir = test::temp_dir("notify-out");
  options.scheduler_turn_hook = [&stall] {
    while (stall.load(std::memory_order_acquire)) std::this_thread::sleep_for(milliseconds(5));
  };
  options.on_ready = [&](const std::vector<std::pair<std::string, std::uint16_t>>& ports) {
    std::vector<test::UdpRoute> routes;
    for (const auto& [name, port] : ports) {
      if (name == "mid360.lidar") routes.push_back({56301, port});
      if (name == "mid360.imu") routes.push_back({56401, port});
    }
    sender = std::thread([&, routes] {
      test::send_capture(folder / "mid360.pcap", routes, {}, sender_stop.get_token());
      sender_end_ns.store(Clock::now().time_since_epoch().count());
    });
    controller = std::thread([&] {
      std::this_thread::sleep_for(milliseconds(3000));  // healthy, streaming
      t_stall = Clock::now();
      stall.store(true, std::memory_order_release);
      std::this_thread::sleep_for(milliseconds(4500));  // more than two watchdog periods
      t_release = Clock::now();
      stall.store(false, std::memory_order_release);
      std::this_thread::sleep_for(milliseconds(3000));  // running again; the 6 s capture is over
      t_term = Clock::now();
      pthread_kill(daemon_thread, SIGTERM);
    });
  };
  const auto r = daemon::runtime::run_daemon(config, options);
  sender_stop.request_stop();
  sender.join();
  controller.join();
  std::this_thread::sleep_for(milliseconds(200));  // the last datagram reaches the reader
  ::unsetenv("NOTIFY_SOCKET");
  ::unsetenv("WATCHDOG_USEC");

  ASSERT_EQ(r.exit_code, 0) << (r.errors.empty() ? "" : r.errors.front());
  EXPECT_EQ(r.stopped_by, "SIGTERM");
  EXPECT_GT(r.frames, 0U);

  const auto messages = manager.messages();
  ASSERT_FALSE(messages.empty());
  EXPECT_TRUE(starts_with(messages.front().text, "READY=1\n")) << messages.front().text;
  EXPECT_TRUE(starts_with(messages.back().text, "STOPPING=1\n")) << messages.back().text;
  EXPECT_GE(messages.back().at, t_term);

  const Clock::time_point sender_end{Clock::duration(sender_end_ns.load())};
  ASSERT_LT(sender_end, t_release + milliseconds(500)) << "the capture should be over by then";
  const Clock::time_point idle_from = std::max(sender_end, t_release);

  int healthy_pings = 0;
  int idle_pings = 0;
  std::optional<Clock::time_point> last_ping_in_stall;
  bool streaming_status = false;
  bool stale_status = false;
  int readies = 0;
  for (const auto& m : messages) {
    readies += starts_with(m.text, "READY=1") ? 1 : 0;
    if (m.text == "WATCHDOG=1") {
      if (m.at < t_stall) ++healthy_pings;
      if (m.at >= t_stall && m.at < t_release) last_ping_in_stall = m.at;
      if (m.at >= idle_from && m.at < t_term) ++idle_pings;
    }
    if (m.text.find("STATUS=mid360 STREAMING") != std::string::npos && m.at < t_stall) {
      streaming_status = true;
    }
    if (m.text.find("STATUS=mid360 STALE") != std::string::npos && m.at >= idle_from) {
      stale_status = true;
    }
  }
  EXPECT_EQ(readies, 1);
  // 3 s healthy at one ping per second.
  EXPECT_GE(healthy_pings, 2);
  // The last ping after the stall began is within one watchdog period of it: systemd would
  // restart the service.
  if (last_ping_in_stall) {
    const double after = seconds_between(t_stall, *last_ping_in_stall);
    std::printf("last WATCHDOG=1 %.3f s after the scheduler stalled (watchdog %.1f s)\n", after,
                kWatchdogS);
    EXPECT_LT(after, kWatchdogS);
  }
  // An idle sensor (the capture is over, the scheduler runs) keeps the pings going.
  EXPECT_GE(idle_pings, 2) << "idle from " << seconds_between(t_release, idle_from)
                           << " s after the release";
  EXPECT_TRUE(streaming_status);
  EXPECT_TRUE(stale_status);
}

}  // namespace
}  // namespace livod
