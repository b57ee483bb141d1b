// The real `livod run` process end to end, inside the private network namespace that
// scripts/netns-run.sh provides (loopback only, multicast routed to lo: nothing leaves the
// machine). The test is the robot: it streams a simulated capture of each LiDAR family with its
// internal IMU (Ouster IMU port, Velodyne HDL-32E position packets, Livox Mid-360 IMU packets)
// over UDP to the daemon's default ports at the recorded pace, and a real `lcm-logger` records
// what the daemon broadcasts over udpm, as lcm-spy would see it. The decoded log must hold one pose
// per scan equal to `livod replay`'s of the same capture, IMU-rate poses at the IMU rate and health
// without loss; SIGTERM then stops the daemon within 2 s with its configured trajectory complete.

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "io/lcm_log.hpp"
#include "io/pcap.hpp"
#include "lcmtypes/livod/health_t.hpp"
#include "lcmtypes/livod/pose_t.hpp"
#include "tests/replay/sim_replay.hpp"
#include "tests/runtime/pose_comparison.hpp"
#include "tests/runtime/udp_replayer.hpp"
#include "tests/support/lcm_logger.hpp"
#include "tests/support/process.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace livod {
namespace {

using daemon::publish::PoseRecord;
using daemon::publish::PoseStatus;

const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0";

bool inside_private_namespace() {
  const char* flag = std::getenv("LIVOD_NETNS");
  return flag != nullptr && std::string(flag) == "1";
}

// The simulator's configuration with its LiDAR turned into a live UDP source on loopback (the
// driver's default ports, those of the capture), LCM on udpm, health five times a second and the
// trajectory in `trajectory`.
std::filesystem::path write_live_config(const std::filesystem::path& folder,
                                        const std::string& lidar,
                                        const std::filesystem::path& trajectory) {
  std::string text = test::read_text_file(folder / "config.yaml");
  const std::string replay = "      replay: {file: " + lidar + ".pcap}\n";
  const auto at = text.find(replay);
  if (at == std::string::npos) throw std::runtime_error("unexpected simulator configuration");
  text.replace(at, replay.size(),
               "      udp: {bind_address: 127.0.0.1, sensor_address: 127.0.0.1,\n"
               "            socket_buffer_bytes: 16777216}\n");
  const std::string outputs = "outputs:\n  trajectory: trajectory.txt\n";
  const auto o = text.find(outputs);
  if (o == std::string::npos) throw std::runtime_error("unexpected simulator outputs");
  text.replace(o, outputs.size(),
               "outputs:\n  trajectory: " + trajectory.string() + "\n  lcm: {url: \"" + kUrl +
                   "\", publish_imu_rate: true}\nhealth: {period_s: 0.2}\n");
  const auto path = folder / "live.yaml";
  std::ofstream(path) << text;
  return path;
}

bool wait_for_text(const std::filesystem::path& file, const std::string& text,
                   std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (test::read_text_file(file).find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

PoseRecord to_record(const livod::pose_t& m) {
  PoseRecord p;
  p.t.ns = m.mapped_time_ns;
  p.status = static_cast<PoseStatus>(m.status);
  p.p_world_body = Eigen::Vector3d(m.position[0], m.position[1], m.position[2]);
  const Eigen::Quaterniond q(m.orientation[0], m.orientation[1], m.orientation[2],
                             m.orientation[3]);
  p.R_world_body = q.normalized().toRotationMatrix();
  return p;
}

struct Recorded {
  std::vector<PoseRecord> poses;     // LIVOD_POSE
  std::vector<std::int64_t> imu_ns;  // LIVOD_POSE_IMU mapped times
  std::vector<livod::health_t> health;
};

template <typename Message>
bool decode(const io::LcmLogEvent& e, Message& m) {
  return m.decode(e.data.data(), 0, static_cast<int>(e.data.size())) ==
         static_cast<int>(e.data.size());
}

Recorded read_log(const std::filesystem::path& log) {
  Recorded r;
  io::LcmLogReader reader(log);
  while (const auto e = reader.next()) {
    if (e->channel == "LIVOD_POSE") {
      livod::pose_t m;
      EXPECT_TRUE(decode(*e, m));
      EXPECT_EQ(m.source, livod::pose_t::SOURCE_FILTER);
      r.poses.push_back(to_record(m));
    } else if (e->channel == "LIVOD_POSE_IMU") {
      livod::pose_t m;
      EXPECT_TRUE(decode(*e, m));
      EXPECT_EQ(m.source, livod::pose_t::SOURCE_IMU_PROPAGATED);
      r.imu_ns.push_back(m.mapped_time_ns);
    } else if (e->channel == "LIVOD_HEALTH") {
      livod::health_t m;
      EXPECT_TRUE(decode(*e, m));
      r.health.push_back(m);
    }
  }
  return r;
}

// Every destination port of a capture, sent to the same port on loopback.
std::vector<test::UdpRoute> same_ports(const std::filesystem::path& pcap) {
  std::set<std::uint16_t> ports;
  io::PcapReader reader(pcap);
  while (const auto d = reader.next()) ports.insert(d->dst_port);
  std::vector<test::UdpRoute> routes;
  for (const auto p : ports) routes.push_back({p, p});
  return routes;
}

struct Rig {
  const char* scenario;
  double imu_rate_hz;  // the LiDAR's internal IMU
  // How far a live pose may be from the replay's: the realistic 10 m/s street amplifies the live
  // path's timing differences to 0.03-2.03 mm over runs (daemon_live_test.cpp,
  // live_matches_replay, has the bound's reasoning).
  double max_dp_m = 1e-3;
};

class LivodRunProcess : public testing::TestWithParam<Rig> {};

TEST_P(LivodRunProcess, BroadcastsOverUdpmThePosesReplayComputes) {
  ASSERT_TRUE(inside_private_namespace())
      << "sends multicast: run through scripts/netns-run.sh (ctest does)";
  const sim::Scenario scenario = sim::make_scenario(GetParam().scenario);
  const std::string lidar = scenario.lidars.front().name;
  const auto folder = test::simulate(scenario, 8.0, "run-udpm");
  const auto replayed = test::replay(folder / "config.yaml", test::temp_dir("run-udpm-replay"));
  const auto trajectory = eval::read_tum(replayed.trajectory);
  const auto out = test::temp_dir("run-udpm-out");
  const auto live_trajectory = out / "trajectory.txt";
  const auto config = write_live_config(folder, lidar, live_trajectory);
  const auto pcap = folder / (lidar + ".pcap");
  const double imu_rate_hz = GetParam().imu_rate_hz;

  // A 4 MiB receive buffer: a logger starved of CPU by parallel tests must not lose datagrams.
  test::LcmLoggerProcess logger(kUrl + "&recv_buf_size=4194304", out / "run.lcmlog");
  const auto daemon_log = out / "livod.log";
  test::ChildProcess livod({LIVOD_BINARY, "run", "--config", config.string()},
                           {.output = daemon_log, .environment = {}});
  ASSERT_TRUE(wait_for_text(daemon_log, "ready", std::chrono::seconds(30)))
      << test::read_text_file(daemon_log);

  const test::SenderResult sent = test::send_capture(pcap, same_ports(pcap));
  EXPECT_GT(sent.sent, 1000U);
  std::this_thread::sleep_for(std::chrono::seconds(1));

  livod.signal(SIGTERM);
  const auto signalled = std::chrono::steady_clock::now();
  const auto status = livod.wait_for(std::chrono::seconds(10));
  const double stop_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  ASSERT_TRUE(status.has_value()) << "still running 10 s after SIGTERM";
  EXPECT_EQ(*status, 0) << test::read_text_file(daemon_log);
  EXPECT_LT(stop_s, 2.0) << "SIGTERM to exit";
  logger.stop();

  const Recorded r = read_log(logger.log());
  ASSERT_FALSE(r.health.empty());
  const livod::health_t& last = r.health.back();
  ASSERT_EQ(last.num_sensors, 1);
  const auto& sensor = last.sensors.front();
  EXPECT_EQ(sensor.kernel_drops, 0);
  EXPECT_EQ(sensor.ring_overruns, 0);
  EXPECT_EQ(sensor.decode_errors, 0);
  EXPECT_EQ(sensor.truncated, 0);
  EXPECT_EQ(last.estimator.outputs_dropped, 0);

  // One pose per scan the estimator took (a loaded machine may make it drop whole scans; it says
  // so in health), each equal to the replay's.
  const std::size_t n = test::real_poses(r.poses);
  const auto dropped = static_cast<std::size_t>(last.estimator.scans_dropped_queue);
  EXPECT_EQ(n + dropped, replayed.summary.frames);
  const test::PoseComparison c = test::compare_with_replay(r.poses, trajectory);
  EXPECT_GE(c.matched + 1, n);
  EXPECT_LE(c.max_position_m, GetParam().max_dp_m);
  EXPECT_LE(c.max_rotation_deg, 0.05);
  std::printf(
      "[run] %zu poses over udpm (replay %zu, dropped %zu), max |dp| %.3f mm, |dR| %.4f deg\n", n,
      replayed.summary.frames, dropped, 1e3 * c.max_position_m, c.max_rotation_deg);

  // IMU-rate poses at the LiDAR's IMU rate.
  ASSERT_GT(r.imu_ns.size(), 100U);
  const double span_s = static_cast<double>(r.imu_ns.back() - r.imu_ns.front()) * 1e-9;
  const double rate = static_cast<double>(r.imu_ns.size() - 1) / span_s;
  EXPECT_NEAR(rate, imu_rate_hz, 0.1 * imu_rate_hz);
  std::printf("[run] %zu IMU-rate poses at %.1f Hz; stopped %.2f s after SIGTERM\n",
              r.imu_ns.size(), rate, stop_s);

  // The configured trajectory is complete: one row per pose sent, no partial file left.
  EXPECT_FALSE(std::filesystem::exists(live_trajectory.string() + ".partial"));
  const auto written = eval::read_tum(live_trajectory);
  EXPECT_EQ(written.size(), n);
}

INSTANTIATE_TEST_SUITE_P(EachFamily, LivodRunProcess,
                         testing::Values(Rig{"room_handheld_os1_64", 100.0},
                                         Rig{"street_vehicle_hdl32e", 200.0, 5e-3},
                                         Rig{"room_handheld_mid360", 200.0}),
                         [](const testing::TestParamInfo<Rig>& rig) {
                           return std::string(rig.param.scenario);
                         });

}  // namespace
}  // namespace livod
