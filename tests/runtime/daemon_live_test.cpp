// The daemon's live path end to end, in-process: a simulated capture is sent over loopback at its
// recorded pace to `run_daemon` (capture threads -> rings -> scheduler thread -> estimator ->
// publisher thread), whose poses are compared with `livod replay` of the same capture; then the
// faults of a real link: the sensor falling silent for 2 s, malformed datagrams, and a Livox LiDAR
// (a fake speaking the SDK1 control protocol) powered off and on, which must be handshaken anew.
//
// Real time: each case streams 6-10 s of recording.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "core/so3.hpp"
#include "daemon/config/sensor_models.hpp"
#include "daemon/runtime/daemon.hpp"
#include "io/udp_socket.hpp"
#include "tests/replay/sim_replay.hpp"
#include "tests/runtime/fake_livox.hpp"
#include "tests/runtime/pose_comparison.hpp"
#include "tests/runtime/udp_replayer.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace livod {
namespace {

using daemon::runtime::HealthRecord;
using daemon::runtime::PoseRecord;
using daemon::runtime::PoseStatus;

// Records what the publisher thread sends (read after the daemon returned).
class RecordingBus final : public daemon::runtime::MessageBus {
 public:
  void publish_pose(const PoseRecord& p) override {
    (p.source == daemon::runtime::PoseSource::kFilter ? poses : imu_poses).push_back(p);
  }
  void publish_health(const HealthRecord& h) override { health.push_back(h); }
  void publish_cloud(const daemon::publish::CloudRecord& /*c*/) override { ++clouds; }
  [[nodiscard]] std::uint64_t failures() const override { return 0; }

  std::vector<PoseRecord> poses;
  std::vector<PoseRecord> imu_poses;
  std::vector<HealthRecord> health;
  std::uint64_t clouds = 0;
};

// The simulator's replay configuration with every LiDAR turned into a live UDP source on
// loopback (nominal ports; the daemon binds ephemeral ones and reports them).
daemon::LivodConfig live_config(const std::filesystem::path& folder) {
  daemon::LivodConfig config = test::load_clean_config(folder / "config.yaml");
  for (auto& s : config.sensors) {
    if (!daemon::is_packet_lidar(s.driver)) continue;
    daemon::UdpSourceConfig udp;
    udp.bind_address = "127.0.0.1";
    udp.sensor_address = "127.0.0.1";
    udp.ports = daemon::default_ports(s.driver, s.model);
    udp.socket_buffer_bytes = 16 * 1024 * 1024;
    s.source = udp;
  }
  config.health.period_s = 0.2;
  return config;
}

struct LiveRun {
  daemon::runtime::DaemonResult result;
  RecordingBus bus;
  test::SenderResult sent;
};

// Streams folder/<lidar>.pcap to the daemon, stops it 1 s after the last packet.
void run_live(const daemon::LivodConfig& config, const std::filesystem::path& pcap,
              const test::ReplayFaults& faults, LiveRun& out) {
  std::stop_source stop;
  std::thread sender;
  daemon::runtime::DaemonOptions options;
  options.bus = &out.bus;
  options.ephemeral_ports = true;
  options.stop = stop.get_token();
  options.max_queued_scans = 50;  // this test compares with replay: no scan may be dropped
  options.on_ready = [&](const std::vector<std::pair<std::string, std::uint16_t>>& ports) {
    std::vector<test::UdpRoute> routes;
    for (const auto& s : config.sensors) {
      const auto* udp = std::get_if<daemon::UdpSourceConfig>(&s.source);
      if (udp == nullptr) continue;
      const std::map<std::string, std::uint16_t> nominal = {
          {s.name + ".lidar", udp->ports.lidar},
          {s.name + ".imu", udp->ports.imu},
          {s.name + ".position", udp->ports.position}};
      for (const auto& [name, port] : ports) {
        if (const auto it = nominal.find(name); it != nominal.end()) {
          routes.push_back({it->second, port});
        }
      }
    }
    sender = std::thread([&, routes] {
      out.sent = test::send_capture(pcap, routes, faults);
      std::this_thread::sleep_for(std::chrono::seconds(1));
      stop.request_stop();
    });
  };
  out.result = daemon::runtime::run_daemon(config, options);
  if (sender.joinable()) sender.join();
}

using test::compare_with_replay;
using test::PoseComparison;
using test::real_poses;

void live_matches_replay(const std::string& scenario_name, double duration_s) {
  const sim::Scenario scenario = sim::make_scenario(scenario_name);
  const auto folder = test::simulate(scenario, duration_s, "live-" + scenario_name);
  const auto replayed = test::replay(folder / "config.yaml", test::temp_dir("live-replay"));
  const auto trajectory = eval::read_tum(replayed.trajectory);

  LiveRun live;
  run_live(live_config(folder), folder / (scenario.lidars.front().name + ".pcap"), {}, live);
  ASSERT_EQ(live.result.exit_code, 0) << (live.result.errors.empty() ? "" : live.result.errors[0]);
  EXPECT_EQ(live.result.stopped_by, "stop request");

  // One pose per scan, the same poses as the replay.
  const std::size_t n = real_poses(live.bus.poses);
  EXPECT_EQ(n, replayed.summary.frames);
  const PoseComparison c = compare_with_replay(live.bus.poses, trajectory);
  EXPECT_GE(c.matched, replayed.summary.frames - 1) << "poses paired with the replay's";
  EXPECT_LE(c.max_position_m, 1e-3);
  EXPECT_LE(c.max_rotation_deg, 0.05);
  std::printf(
      "[live] %s: %zu poses (replay %zu), %zu paired, max |dp| %.3f mm, max |dR| %.4f deg\n",
      scenario_name.c_str(), n, replayed.summary.frames, c.matched, 1e3 * c.max_position_m,
      c.max_rotation_deg);

  // IMU-rate poses at the IMU rate, in time order.
  ASSERT_FALSE(live.bus.imu_poses.empty());
  const auto& imu = live.bus.imu_poses;
  const double span_s = static_cast<double>(imu.back().t.ns - imu.front().t.ns) * 1e-9;
  const double rate = static_cast<double>(imu.size() - 1) / span_s;
  std::printf("[live] %s: %zu IMU-rate poses at %.1f Hz\n", scenario_name.c_str(), imu.size(),
              rate);
  EXPECT_TRUE(std::is_sorted(imu.begin(), imu.end(),
                             [](const auto& a, const auto& b) { return a.t < b.t; }));

  // Health: zero loss, the sensor streamed.
  ASSERT_FALSE(live.bus.health.empty());
  const HealthRecord& last = live.bus.health.back();
  for (const auto& s : last.sensors) {
    EXPECT_EQ(s.kernel_drops, 0U) << s.name;
    EXPECT_EQ(s.ring_overruns, 0U) << s.name;
    EXPECT_EQ(s.decode_errors, 0U) << s.name;
    EXPECT_EQ(s.truncated, 0U) << s.name;
  }
  const bool streamed =
      std::any_of(live.bus.health.begin(), live.bus.health.end(), [](const HealthRecord& h) {
        return !h.sensors.empty() &&
               h.sensors.front().state == daemon::publish::SensorState::kStreaming;
      });
  EXPECT_TRUE(streamed);
  EXPECT_EQ(live.result.publisher.poses, n);
  EXPECT_GT(live.result.publisher.pose_latency_ms.count(), 0U);
}

TEST(DaemonLive, OusterMatchesReplay) {
  live_matches_replay("room_handheld_os1_64", 8.0);
}

TEST(DaemonLive, VelodyneHdl32eMatchesReplay) {
  live_matches_replay("street_vehicle_hdl32e", 8.0);
}

TEST(DaemonLive, LivoxMid360MatchesReplay) {
  live_matches_replay("room_handheld_mid360", 8.0);
}

TEST(DaemonLive, SilentSensorGoesStaleAndComesBack) {
  const sim::Scenario scenario = sim::make_scenario("room_handheld_os1_64");
  const auto folder = test::simulate(scenario, 10.0, "live-stale");
  LiveRun live;
  test::ReplayFaults faults;
  faults.silent_from_s = 5.0;
  faults.silent_to_s = 7.0;
  run_live(live_config(folder), folder / "os1.pcap", faults, live);
  ASSERT_EQ(live.result.exit_code, 0);
  EXPECT_GT(live.sent.silenced, 0U);

  // Health: STREAMING, then STALE during the silence, then STREAMING again; the daemon went on.
  using daemon::publish::SensorState;
  std::vector<SensorState> states;
  for (const auto& h : live.bus.health) {
    const SensorState s = h.sensors.front().state;
    if (states.empty() || states.back() != s) states.push_back(s);
  }
  const auto stale = std::find(states.begin(), states.end(), SensorState::kStale);
  ASSERT_NE(stale, states.end());
  EXPECT_NE(std::find(states.begin(), stale, SensorState::kStreaming), stale);
  EXPECT_NE(std::find(stale, states.end(), SensorState::kStreaming), states.end());
  const bool estimator_said_so = std::any_of(
      live.bus.health.begin(), live.bus.health.end(),
      [](const HealthRecord& h) { return h.estimator.status == PoseStatus::kSensorStale; });
  EXPECT_TRUE(estimator_said_so);

  // The pose said so too, and poses continued after the silence.
  const auto stale_pose =
      std::find_if(live.bus.poses.begin(), live.bus.poses.end(),
                   [](const auto& p) { return p.status == PoseStatus::kSensorStale; });
  ASSERT_NE(stale_pose, live.bus.poses.end());
  const auto after = std::find_if(stale_pose, live.bus.poses.end(), [](const auto& p) {
    return p.status != PoseStatus::kSensorStale;
  });
  ASSERT_NE(after, live.bus.poses.end());
  EXPECT_GT((after->t - stale_pose->t).count(), 1'500'000'000);  // the next pose is after the gap
  EXPECT_GE(std::count_if(after, live.bus.poses.end(),
                          [](const auto& p) { return p.status == PoseStatus::kOk; }),
            20);
}

TEST(DaemonLive, MalformedDatagramsAreCountedAndSkipped) {
  const sim::Scenario scenario = sim::make_scenario("room_handheld_os1_64");
  const auto folder = test::simulate(scenario, 6.0, "live-malformed");
  const auto replayed = test::replay(folder / "config.yaml", test::temp_dir("live-malformed-r"));
  const auto trajectory = eval::read_tum(replayed.trajectory);
  LiveRun live;
  test::ReplayFaults faults;
  faults.malformed_every = 10;
  run_live(live_config(folder), folder / "os1.pcap", faults, live);
  ASSERT_EQ(live.result.exit_code, 0);
  ASSERT_FALSE(live.bus.health.empty());
  const auto& sensor = live.bus.health.back().sensors.front();
  // Short junk fails decoding; junk longer than the port's packets is cut by the slot and skipped.
  EXPECT_EQ(sensor.decode_errors + sensor.truncated, live.sent.malformed);
  EXPECT_GT(live.sent.malformed, live.sent.sent / 12);
  const PoseComparison c = compare_with_replay(live.bus.poses, trajectory);
  EXPECT_GE(c.matched, replayed.summary.frames - 1);
  EXPECT_LE(c.max_position_m, 1e-3);
  EXPECT_LE(c.max_rotation_deg, 0.05);
}

// A Livox Avia (SDK1) that loses power for 4 s: its heartbeats go unanswered, the supervisor marks
// it STALE and, the address being configured, handshakes it again as soon as it answers; the
// capture threads, rings and decoder kept running, and poses resume.
TEST(DaemonLive, LivoxLidarPoweredOffIsHandshakenAgain) {
  const sim::Scenario scenario = sim::make_scenario("room_handheld_avia");
  const auto folder = test::simulate(scenario, 12.0, "live-livox-power");
  const std::uint32_t lidar_ip = test::FakeAvia::loopback_ip();
  daemon::LivodConfig config = live_config(folder);
  auto& udp = std::get<daemon::UdpSourceConfig>(config.sensors.front().source);
  udp.sensor_address = io::format_ipv4(lidar_ip);

  test::FakeAvia lidar(lidar_ip, folder / "avia.pcap");
  std::stop_source stop;
  std::thread power;
  LiveRun live;
  daemon::runtime::DaemonOptions options;
  options.bus = &live.bus;
  options.ephemeral_ports = true;
  options.stop = stop.get_token();
  options.on_ready = [&](const auto& /*ports*/) {
    power = std::thread([&] {
      using namespace std::chrono_literals;
      const auto deadline = std::chrono::steady_clock::now() + 30s;
      while (lidar.handshakes.load() == 0 && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(10ms);
      }
      std::this_thread::sleep_for(4s);
      lidar.online = false;
      std::this_thread::sleep_for(4s);
      lidar.online = true;
      while (!lidar.finished.load() && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(10ms);
      }
      std::this_thread::sleep_for(1s);
      stop.request_stop();
    });
  };
  live.result = daemon::runtime::run_daemon(config, options);
  if (power.joinable()) power.join();
  ASSERT_EQ(live.result.exit_code, 0) << (live.result.errors.empty() ? "" : live.result.errors[0]);
  EXPECT_TRUE(lidar.finished.load());
  EXPECT_GE(lidar.handshakes.load(), 2) << "handshaken again after the power cycle";
  EXPECT_GT(lidar.lost.load(), 0U);

  using daemon::publish::SensorState;
  std::vector<SensorState> states;
  for (const auto& h : live.bus.health) {
    const SensorState s = h.sensors.front().state;
    if (states.empty() || states.back() != s) states.push_back(s);
  }
  const auto stale = std::find(states.begin(), states.end(), SensorState::kStale);
  ASSERT_NE(stale, states.end());
  EXPECT_NE(std::find(states.begin(), stale, SensorState::kStreaming), stale);
  EXPECT_NE(std::find(stale, states.end(), SensorState::kStreaming), states.end());
  const auto& last = live.bus.health.back().sensors.front();
  EXPECT_GE(last.reconnects, 1U) << last.device_state;
  EXPECT_EQ(last.decode_errors, 0U);

  // Poses before the power cut and again after it.
  const auto stale_pose =
      std::find_if(live.bus.poses.begin(), live.bus.poses.end(),
                   [](const auto& p) { return p.status == PoseStatus::kSensorStale; });
  ASSERT_NE(stale_pose, live.bus.poses.end());
  EXPECT_GE(std::count_if(live.bus.poses.begin(), stale_pose,
                          [](const auto& p) { return p.status == PoseStatus::kOk; }),
            10);
  EXPECT_GE(std::count_if(stale_pose, live.bus.poses.end(),
                          [](const auto& p) { return p.status == PoseStatus::kOk; }),
            10);
}

}  // namespace
}  // namespace livod
