// ROS1 bag input gives the trajectory of the capture it was recorded from, compared pose by pose
// with the replay of the pcap itself:
//  - the bag `livod sim --bag` writes (docs/simulator.md: livox_ros_driver/CustomMsg and
//    sensor_msgs/Imu, header stamps already on the host clock, so dataset_* sensors map them
//    directly, the configuration's default);
//  - the capture recorded here the way a driver without time synchronisation would
//    (CustomMsg, or a PointCloud2 with a per-point time field; header stamps on the sensor's own
//    clock, record times on the host clock), replayed with free-running clock domains.

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <map>

#include "drivers/livox/livox_decoder.hpp"
#include "io/pcap.hpp"
#include "io/rosbag/bag_writer.hpp"
#include "tests/replay/sim_replay.hpp"

namespace livod {
namespace {

namespace rb = io::rosbag;

// The Mid-360 capture recorded as a bag: /livox/imu, /livox/lidar (CustomMsg), /points
// (PointCloud2: x y z intensity float32, t uint32 ns from the scan start, header = scan start).
void record_bag(const std::filesystem::path& pcap, const std::filesystem::path& bag_path) {
  livox::LivoxDecoder decoder(*livox::livox_model("MID-360"), livox::LivoxDecoderOptions{});
  io::PcapReader reader(pcap);
  reader.set_port_filter(decoder.default_ports());
  rb::BagWriter bag(bag_path, {.compression = rb::Compression::kLz4});
  const auto imu_conn = bag.add_connection<rb::sensor_msgs::Imu>("/livox/imu");
  const auto livox_conn = bag.add_connection<rb::livox_ros_driver::CustomMsg>("/livox/lidar");
  const auto cloud_conn = bag.add_connection<rb::sensor_msgs::PointCloud2>("/points");
  // A scan is complete when the decoder sees the next scan's first point: a driver publishes it
  // at the receive time of that packet (which usually also holds the scan's last points).
  std::int64_t now_ns = 0;

  drivers::DecoderSinks sinks;
  sinks.on_imu = [&](const ImuSample& s) {
    rb::sensor_msgs::Imu m;
    m.header.stamp = rb::RosTime::from_ns(s.stamp.sensor.ns);
    m.header.frame_id = "livox_frame";
    m.angular_velocity = {s.gyro_rad_s.x(), s.gyro_rad_s.y(), s.gyro_rad_s.z()};
    m.linear_acceleration = {s.accel_m_s2.x(), s.accel_m_s2.y(), s.accel_m_s2.z()};
    bag.write(imu_conn, s.stamp.host.ns, m);
  };
  sinks.on_scan = [&](const LidarScan& scan) {
    rb::livox_ros_driver::CustomMsg m;
    m.header.stamp = rb::RosTime::from_ns(scan.start.sensor.ns);
    m.timebase = static_cast<std::uint64_t>(scan.start.sensor.ns);
    m.point_num = static_cast<std::uint32_t>(scan.size());
    rb::sensor_msgs::PointCloud2 c;
    c.header = m.header;
    c.height = 1;
    c.width = m.point_num;
    c.point_step = 20;
    c.row_step = c.point_step * c.width;
    c.fields = {{"x", 0, rb::sensor_msgs::PointField::kFloat32, 1},
                {"y", 4, rb::sensor_msgs::PointField::kFloat32, 1},
                {"z", 8, rb::sensor_msgs::PointField::kFloat32, 1},
                {"intensity", 12, rb::sensor_msgs::PointField::kFloat32, 1},
                {"t", 16, rb::sensor_msgs::PointField::kUint32, 1}};
    c.data.resize(static_cast<std::size_t>(c.row_step));
    for (std::size_t i = 0; i < scan.size(); ++i) {
      rb::livox_ros_driver::CustomPoint p;
      p.offset_time = static_cast<std::uint32_t>(scan.t_offset_ns[i]);
      p.x = scan.x[i];
      p.y = scan.y[i];
      p.z = scan.z[i];
      p.reflectivity = static_cast<std::uint8_t>(scan.intensity[i]);
      p.line = static_cast<std::uint8_t>(scan.ring[i]);
      m.points.push_back(p);
      const float v[4] = {scan.x[i], scan.y[i], scan.z[i], scan.intensity[i]};
      std::memcpy(&c.data[i * 20], v, 16);
      std::memcpy(&c.data[i * 20 + 16], &p.offset_time, 4);
    }
    bag.write(livox_conn, now_ns, m);
    bag.write(cloud_conn, now_ns, c);
  };
  while (const auto d = reader.next()) {
    now_ns = d->capture_time_ns;
    decoder.on_packet({d->payload, d->capture_time_ns, d->dst_port}, sinks);
  }
  decoder.flush(sinks);
  bag.close();
}

std::string yaml_extrinsic(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d& R = T.linear();
  const Eigen::Vector3d& t = T.translation();
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "    extrinsic:\n      translation: [%.12g, %.12g, %.12g]\n"
                "      rotation: {matrix: [%.12g, %.12g, %.12g, %.12g, %.12g, %.12g, %.12g, %.12g, "
                "%.12g]}\n",
                t.x(), t.y(), t.z(), R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0),
                R(2, 1), R(2, 2));
  return buf;
}

// dataset_lidar + dataset_imu reading `bag`; `clock` empty = the default (auto: direct).
void write_bag_config(const std::filesystem::path& path, const std::string& bag,
                      const std::string& lidar_topic, const Eigen::Isometry3d& T_body_lidar,
                      const std::string& clock) {
  const std::string clock_line = clock.empty() ? "" : "    clock: {mode: " + clock + "}\n";
  std::ofstream out(path);
  out << "body_frame: imu\nsensors:\n"
      << "  - name: lidar\n    driver: dataset_lidar\n    model: MID-360\n"
      << "    source: {replay: {file: " << bag << ", topic: " << lidar_topic << "}}\n"
      << "    dataset: {time_field: t, time_unit: ns, stamp: start}\n"
      << clock_line << yaml_extrinsic(T_body_lidar) << "  - name: imu\n    driver: dataset_imu\n"
      << "    source: {replay: {file: " << bag << ", topic: /livox/imu}}\n"
      << clock_line;
}

struct Pose {
  Eigen::Vector3d p;
  Eigen::Quaterniond q;
};

// TUM file -> poses by integer-ns stamp.
std::map<std::int64_t, Pose> read_tum(const std::filesystem::path& path) {
  std::map<std::int64_t, Pose> out;
  std::ifstream in(path);
  std::string stamp;
  Pose pose;
  double x, y, z, qx, qy, qz, qw;
  while (in >> stamp >> x >> y >> z >> qx >> qy >> qz >> qw) {
    const auto dot = stamp.find('.');
    const std::int64_t ns =
        std::stoll(stamp.substr(0, dot)) * 1'000'000'000LL + std::stoll(stamp.substr(dot + 1));
    out[ns] = Pose{{x, y, z}, Eigen::Quaterniond(qw, qx, qy, qz)};
  }
  return out;
}

struct Comparison {
  std::size_t matched = 0;
  double max_dt_us = 0.0;  // once the clock models are fine (3 s after the first pose)
  double max_dp_m = 0.0;
  double max_dr_deg = 0.0;
};

// Pairs each pose of `a` with the pose of `b` nearest in time (within 1 ms).
Comparison compare(const std::map<std::int64_t, Pose>& a, const std::map<std::int64_t, Pose>& b) {
  Comparison c;
  for (const auto& [t, pa] : a) {
    auto it = b.lower_bound(t - 1'000'000);
    if (it == b.end() || it->first > t + 1'000'000) continue;
    const Pose& pb = it->second;
    ++c.matched;
    if (t - a.begin()->first > 3'000'000'000LL) {
      c.max_dt_us = std::max(c.max_dt_us, std::abs(static_cast<double>(it->first - t)) * 1e-3);
    }
    c.max_dp_m = std::max(c.max_dp_m, (pa.p - pb.p).norm());
    c.max_dr_deg = std::max(c.max_dr_deg, pa.q.angularDistance(pb.q) * 180.0 / M_PI);
  }
  return c;
}

// One simulated Mid-360 sequence (with the simulator's bag) and its pcap replay, shared by the
// tests below.
class ReplayBag : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scenario_ = new sim::Scenario(sim::make_scenario("room_handheld_mid360"));
    folder_ = new std::filesystem::path(test::temp_dir("bag-sim"));
    sim::SimRunOptions options;
    options.out_dir = *folder_;
    options.duration_s = 15.0;
    options.write_images = false;
    options.write_bag = true;
    sim::run_scenario(*scenario_, options);
    pcap_ = new daemon::replay::ReplayResult(
        test::replay(*folder_ / "config.yaml", test::temp_dir("bag-pcap")));
  }
  static void TearDownTestSuite() {
    delete pcap_;
    delete folder_;
    delete scenario_;
  }

  // Replays `config` and compares its trajectory with the pcap's.
  static Comparison replay_and_compare(const std::filesystem::path& config, const std::string& tag,
                                       daemon::replay::ReplayResult& out) {
    out = test::replay(config, test::temp_dir(tag));
    const auto ref = read_tum(pcap_->trajectory);
    const auto c = compare(ref, read_tum(out.trajectory));
    std::printf(
        "[bag] %s: %zu of %zu poses matched, max |dt| %.1f us, max |dp| %.3f mm, max rotation "
        "%.4f deg\n",
        out.summary.sensors.front().file.c_str(), c.matched, ref.size(), c.max_dt_us,
        c.max_dp_m * 1e3, c.max_dr_deg);
    EXPECT_GT(ref.size(), 100U);
    EXPECT_GE(c.matched + 1, ref.size());
    // The same scans and IMU samples reached the estimator.
    EXPECT_EQ(out.summary.sensors.front().scans, pcap_->summary.sensors.front().scans);
    EXPECT_EQ(out.summary.sensors.back().imu_samples, pcap_->summary.sensors.front().imu_samples);
    return c;
  }

  static sim::Scenario* scenario_;
  static std::filesystem::path* folder_;
  static daemon::replay::ReplayResult* pcap_;
};

sim::Scenario* ReplayBag::scenario_ = nullptr;
std::filesystem::path* ReplayBag::folder_ = nullptr;
daemon::replay::ReplayResult* ReplayBag::pcap_ = nullptr;

TEST_F(ReplayBag, SimulatorBagGivesTheTrajectoryOfItsPcap) {
  const auto& mount = scenario_->lidars.front();
  ASSERT_TRUE(std::filesystem::exists(*folder_ / "sequence.bag"));
  write_bag_config(*folder_ / "sim_bag.yaml", "sequence.bag", "/livox/lidar", mount.T_body_sensor,
                   "");
  daemon::replay::ReplayResult bag;
  const Comparison c = replay_and_compare(*folder_ / "sim_bag.yaml", "bag-sim-replay", bag);
  EXPECT_EQ(bag.summary.sensors.front().clock.mode, "direct");
  // The bag's stamps are the exact host times; the pcap's are mapped by the clock domain, which
  // sits on the link's minimum delay (~80 us).
  EXPECT_LT(c.max_dt_us, 200.0);
  EXPECT_LT(c.max_dp_m, 1e-3);
  EXPECT_LT(c.max_dr_deg, 0.02);
}

TEST_F(ReplayBag, SensorClockStampsCustomMsgAndPointCloud2) {
  const auto& mount = scenario_->lidars.front();
  record_bag(*folder_ / (mount.name + ".pcap"), *folder_ / "recorded.bag");
  write_bag_config(*folder_ / "bag_livox.yaml", "recorded.bag", "/livox/lidar", mount.T_body_sensor,
                   "free_running");
  write_bag_config(*folder_ / "bag_cloud.yaml", "recorded.bag", "/points", mount.T_body_sensor,
                   "free_running");
  daemon::replay::ReplayResult livox;
  daemon::replay::ReplayResult cloud;
  for (auto* r : {&livox, &cloud}) {
    const Comparison c =
        replay_and_compare(*folder_ / (r == &livox ? "bag_livox.yaml" : "bag_cloud.yaml"),
                           r == &livox ? "bag-livox" : "bag-cloud", *r);
    // The bag's LiDAR and IMU are two clock domains (the pcap's LiDAR and its IMU share one),
    // each fitted to its own receive stamps (the LiDAR's: record times, up to a packet late).
    EXPECT_EQ(r->summary.sensors.front().clock.mode, "free_running");
    EXPECT_LT(c.max_dt_us, 300.0);
    EXPECT_LT(c.max_dp_m, 1e-3);
    EXPECT_LT(c.max_dr_deg, 0.02);
  }
  // CustomMsg and PointCloud2 carry the same scans: identical replays.
  EXPECT_TRUE(test::read_file(livox.trajectory) == test::read_file(cloud.trajectory));
}

}  // namespace
}  // namespace livod
