// The real `livod run` process as systemd starts it (Type=notify, WatchdogSec=), without systemd:
// the test binds NOTIFY_SOCKET (an abstract AF_UNIX datagram address, private to the network
// namespace scripts/netns-run.sh provides) and sets WATCHDOG_USEC. The configuration is the
// shipped example (systemd/livod.example.yaml, installed as /etc/livod/livod.yaml) pointed at
// loopback, with no sensor answering: READY=1 arrives once the sockets are bound, STATUS= says the
// LiDAR is WAITING, WATCHDOG=1 keeps arriving every half period although no data comes (idle
// capture threads still beat), and SIGTERM gives STOPPING=1 then exit 0.

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

#include "tests/replay/sim_replay.hpp"
#include "tests/runtime/fake_service_manager.hpp"
#include "tests/support/process.hpp"

namespace livod {
namespace {

bool inside_private_namespace() {
  const char* flag = std::getenv("LIVOD_NETNS");
  return flag != nullptr && std::string(flag) == "1";
}

void replace(std::string& text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("not in the example: " + from);
  text.replace(at, from.size(), to);
}

TEST(LivodRunNotify, ReadyStatusWatchdogWhileIdleStoppingOnSigterm) {
  ASSERT_TRUE(inside_private_namespace())
      << "binds fixed ports and an abstract socket: run through scripts/netns-run.sh (ctest does)";
  std::string text = test::read_text_file(LIVOD_EXAMPLE_CONFIG);
  replace(text, "bind_address: 0.0.0.0", "bind_address: 127.0.0.1");
  replace(text, "sensor_address: 192.168.1.170", "sensor_address: 127.0.0.1");
  replace(text, "ttl=1", "ttl=0");
  // Normal scheduling: the test machine is shared.
  replace(text, "capture_priority: 50, scheduler_priority: 40",
          "capture_priority: 0, scheduler_priority: 0");
  const auto out = test::temp_dir("run-notify");
  const auto config = out / "livod.yaml";
  std::ofstream(config) << text;

  test::FakeServiceManager manager;
  const auto log = out / "livod.log";
  test::ChildProcess livod(
      {LIVOD_BINARY, "run", "--config", config.string()},
      {.output = log,
       .environment = {"NOTIFY_SOCKET=" + manager.address(), "WATCHDOG_USEC=1000000"}});
  ASSERT_TRUE(manager.wait_for("READY=1", std::chrono::seconds(30))) << test::read_text_file(log);
  const auto ready = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::milliseconds(3000));
  livod.signal(SIGTERM);
  const auto status = livod.wait_for(std::chrono::seconds(10));
  ASSERT_TRUE(status.has_value()) << "still running 10 s after SIGTERM";
  EXPECT_EQ(*status, 0) << test::read_text_file(log);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));

  const auto messages = manager.messages();
  ASSERT_FALSE(messages.empty());
  EXPECT_EQ(messages.front().text.rfind("READY=1\nSTATUS=started: avia", 0), 0U)
      << messages.front().text;
  EXPECT_EQ(messages.back().text.rfind("STOPPING=1\nSTATUS=stopping (SIGTERM)", 0), 0U)
      << messages.back().text;
  int pings = 0;
  bool waiting = false;
  for (const auto& m : messages) {
    if (m.text == "WATCHDOG=1" && m.at > ready) ++pings;
    waiting = waiting || m.text.rfind("STATUS=avia WAITING", 0) == 0;
  }
  // 3 s at one ping per 0.5 s, nothing received from the sensor.
  EXPECT_GE(pings, 4) << test::read_text_file(log);
  EXPECT_TRUE(waiting);
  std::printf("[notify] %d WATCHDOG=1 in 3 s with WATCHDOG_USEC=1 s, %zu messages\n", pings,
              messages.size());
}

}  // namespace
}  // namespace livod
