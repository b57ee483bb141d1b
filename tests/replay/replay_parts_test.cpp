// The replay engine's parts on their own: exact time printing, percentiles, the bounded map
// filter and its PCD file, recorded clouds -> scans (every stamp convention), command-line input
// assignment and the per-sensor clock mapping.

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/error.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/replay/cloud_conversion.hpp"
#include "daemon/replay/input_assignment.hpp"
#include "daemon/replay/map_accumulator.hpp"
#include "daemon/replay/sources.hpp"
#include "daemon/replay/timing_report.hpp"
#include "daemon/replay/trajectory_writer.hpp"
#include "daemon/runtime/sensor_clock.hpp"
#include "tests/support/data_dir.hpp"

namespace livod {
namespace {

using daemon::replay::CloudConversionStats;
namespace rb = io::rosbag;

TEST(ReplayParts, FormatSecondsIsExact) {
  EXPECT_EQ(daemon::replay::format_seconds(1'700'000'000'123'456'789), "1700000000.123456789");
  EXPECT_EQ(daemon::replay::format_seconds(5), "0.000000005");
  EXPECT_EQ(daemon::replay::format_seconds(-1'500'000'000), "-1.500000000");
  EXPECT_EQ(daemon::replay::format_seconds(0), "0.000000000");
}

TEST(ReplayParts, NearestRankPercentiles) {
  std::vector<float> v;
  for (int i = 100; i >= 1; --i) v.push_back(static_cast<float>(i));  // 1..100, unsorted
  const auto d = daemon::replay::distribution(v);
  EXPECT_EQ(d.count, 100U);
  EXPECT_DOUBLE_EQ(d.p50, 50.0);
  EXPECT_DOUBLE_EQ(d.p95, 95.0);
  EXPECT_DOUBLE_EQ(d.p99, 99.0);
  EXPECT_DOUBLE_EQ(d.max, 100.0);
  EXPECT_DOUBLE_EQ(d.mean, 50.5);
  const auto one = daemon::replay::distribution({7.0F});
  EXPECT_DOUBLE_EQ(one.p50, 7.0);
  EXPECT_DOUBLE_EQ(one.p99, 7.0);
  EXPECT_EQ(daemon::replay::distribution({}).count, 0U);
}

TEST(ReplayParts, MapKeepsOnePointPerCellWithinBudget) {
  daemon::replay::MapAccumulator map(0.2, 1000);
  EXPECT_TRUE(map.add({0.05, 0.05, 0.05}));
  EXPECT_FALSE(map.add({0.15, 0.01, 0.19}));  // same cell
  EXPECT_TRUE(map.add({-0.05, 0.05, 0.05}));  // floor, not truncation: cell -1
  EXPECT_TRUE(map.add({0.25, 0.05, 0.05}));
  EXPECT_FALSE(map.add({std::nan(""), 0.0, 0.0}));
  EXPECT_EQ(map.size(), 3U);
  // A grid of distinct cells: growth of the table keeps every key.
  for (int i = 0; i < 30; ++i) {
    for (int j = 0; j < 30; ++j) map.add({1.0 + 0.2 * i + 0.1, 1.0 + 0.2 * j + 0.1, -7.3});
  }
  EXPECT_EQ(map.size(), 903U);
  for (int i = 0; i < 30; ++i) {
    for (int j = 0; j < 30; ++j)
      EXPECT_FALSE(map.add({1.0 + 0.2 * i + 0.15, 1.0 + 0.2 * j + 0.15, -7.25}));
  }
  // The budget: 97 more cells fit, the rest are counted.
  for (int i = 0; i < 200; ++i) map.add({50.0 + 0.2 * i + 0.1, 0.1, 0.1});
  EXPECT_EQ(map.size(), 1000U);
  EXPECT_EQ(map.dropped_full(), 103U);
  EXPECT_GT(map.bytes(), 1000U * 12U);
  EXPECT_LE(map.bytes(), 1000U * 44U + 4096U * 8U);
}

TEST(ReplayParts, PcdFileIsBinaryXyzFloat) {
  const auto dir = test::temp_dir("replay_pcd");
  const std::vector<float> xyz = {1.0F, 2.0F, 3.0F, -4.5F, 0.25F, 1e6F};
  daemon::replay::write_pcd(dir / "m.pcd", xyz);
  std::ifstream in(dir / "m.pcd", std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string bytes = ss.str();
  const std::string header =
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
      "TYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\n"
      "DATA binary\n";
  ASSERT_EQ(bytes.size(), header.size() + 24);
  EXPECT_EQ(bytes.substr(0, header.size()), header);
  std::vector<float> back(6);
  std::memcpy(back.data(), bytes.data() + header.size(), 24);
  EXPECT_EQ(back, xyz);
}

rb::livox_ros_driver::CustomMsg custom_msg() {
  rb::livox_ros_driver::CustomMsg m;
  m.header.stamp = rb::RosTime{100, 5};
  m.timebase = 52'250'000'000;
  for (std::uint32_t k = 0; k < 5; ++k) {
    rb::livox_ros_driver::CustomPoint p;
    p.offset_time = 1000 + k * 20'000'000;
    p.x = 1.0F + static_cast<float>(k);
    p.y = -2.0F;
    p.z = 0.5F;
    p.reflectivity = static_cast<std::uint8_t>(10 * k);
    p.line = static_cast<std::uint8_t>(k % 4);
    m.points.push_back(p);
  }
  m.points[2].x = m.points[2].y = m.points[2].z = 0.0F;  // Livox "no return"
  m.point_num = 5;
  return m;
}

TEST(ReplayParts, CustomMsgPointTimesAreTimebasePlusOffset) {
  LidarScan scan;
  CloudConversionStats stats;
  auto m = custom_msg();
  ASSERT_TRUE(daemon::replay::custom_msg_to_scan(m, scan, stats));
  ASSERT_EQ(scan.size(), 5U);
  EXPECT_EQ(scan.start.sensor.ns, 52'250'001'000);  // the first point
  EXPECT_EQ(scan.t_offset_ns[0], 0);
  EXPECT_EQ(scan.t_offset_ns[4], 80'000'000);
  EXPECT_FLOAT_EQ(scan.x[1], 2.0F);
  EXPECT_EQ(scan.ring[3], 3);
  EXPECT_EQ(scan.valid[2], 0);
  EXPECT_EQ(scan.valid[1], 1);
  EXPECT_EQ(stats.invalid_points, 1U);
  // timebase 0: the header stamp is the base.
  m.timebase = 0;
  ASSERT_TRUE(daemon::replay::custom_msg_to_scan(m, scan, stats));
  EXPECT_EQ(scan.start.sensor.ns, 100'000'000'005 + 1000);
  // No points: no scan.
  m.points.clear();
  EXPECT_FALSE(daemon::replay::custom_msg_to_scan(m, scan, stats));
  EXPECT_EQ(stats.empty_messages, 1U);
}

// A PointCloud2 with x y z float32 and a time field of the given datatype.
template <class T>
rb::sensor_msgs::PointCloud2 cloud_with_times(const std::vector<T>& times, std::uint8_t datatype) {
  rb::sensor_msgs::PointCloud2 c;
  c.header.stamp = rb::RosTime{1'700'000'000, 500'000'000};
  c.height = 1;
  c.width = static_cast<std::uint32_t>(times.size());
  const std::uint32_t step = 12 + sizeof(T);
  c.point_step = step;
  c.row_step = step * c.width;
  for (const char* n : {"x", "y", "z"}) {
    c.fields.push_back({n, static_cast<std::uint32_t>(4 * (n[0] - 'x')), 7, 1});
  }
  c.fields.push_back({"t", 12, datatype, 1});
  c.data.resize(static_cast<std::size_t>(c.row_step));
  for (std::size_t i = 0; i < times.size(); ++i) {
    const float xyz[3] = {static_cast<float>(i) + 1.0F, 0.5F, -0.25F};
    std::memcpy(&c.data[i * step], xyz, 12);
    std::memcpy(&c.data[i * step + 12], &times[i], sizeof(T));
  }
  return c;
}

TEST(ReplayParts, PointCloudStampConventions) {
  std::vector<rb::CloudPoint> scratch;
  LidarScan scan;
  CloudConversionStats stats;
  const std::int64_t stamp = 1'700'000'000'500'000'000;
  daemon::DatasetConfig d;  // t, ns, relative, stamp: start

  // Ouster-style uint32 ns offsets from the scan start, header = start.
  auto c = cloud_with_times<std::uint32_t>({0, 25'000'000, 99'000'000}, 6);
  ASSERT_TRUE(daemon::replay::point_cloud_to_scan(c, d, scratch, scan, stats));
  EXPECT_EQ(scan.start.sensor.ns, stamp);
  EXPECT_EQ(scan.t_offset_ns[2], 99'000'000);
  EXPECT_FLOAT_EQ(scan.x[1], 2.0F);

  // The same with header = end (NTU-VIRAL): the scan starts 99 ms before the stamp.
  d.stamp = daemon::ScanStamp::end;
  ASSERT_TRUE(daemon::replay::point_cloud_to_scan(c, d, scratch, scan, stats));
  EXPECT_EQ(scan.start.sensor.ns, stamp - 99'000'000);
  EXPECT_EQ(scan.t_offset_ns[1], 25'000'000);

  // Velodyne-style float32 seconds, negative: relative to the stamp whatever it marks.
  d.time_unit = daemon::TimeUnit::s;
  auto v = cloud_with_times<float>({-0.1F, -0.05F, 0.0F}, 7);
  ASSERT_TRUE(daemon::replay::point_cloud_to_scan(v, d, scratch, scan, stats));
  EXPECT_NEAR(static_cast<double>(scan.start.sensor.ns - stamp), -1e8, 10.0);
  EXPECT_NEAR(scan.t_offset_ns[2], 1e8, 10.0);

  // Absolute float64 seconds: the header is ignored.
  d.time_reference = daemon::TimeReference::absolute;
  auto a = cloud_with_times<double>({1'600'000'000.25, 1'600'000'000.30}, 8);
  ASSERT_TRUE(daemon::replay::point_cloud_to_scan(a, d, scratch, scan, stats));
  EXPECT_NEAR(static_cast<double>(scan.start.sensor.ns), 1.60000000025e18, 500.0);
  EXPECT_NEAR(scan.t_offset_ns[1], 5e7, 500.0);

  // A point 3 s after the start does not fit the int32 offsets: dropped and counted.
  d = daemon::DatasetConfig{};
  auto far = cloud_with_times<std::uint32_t>({0, 3'000'000'000U}, 6);
  const auto dropped = stats.dropped_points;
  ASSERT_TRUE(daemon::replay::point_cloud_to_scan(far, d, scratch, scan, stats));
  EXPECT_EQ(scan.size(), 1U);
  EXPECT_EQ(stats.dropped_points, dropped + 1);

  // A missing time field is a clear error naming the fields.
  d.time_field = "timestamp";
  try {
    daemon::replay::point_cloud_to_scan(c, d, scratch, scan, stats);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no field 'timestamp' (fields: x,y,z,t)"),
              std::string::npos)
        << e.what();
  }
}

TEST(ReplayParts, GarbageTimesAreDroppedNotOverflowed) {
  std::vector<rb::CloudPoint> scratch;
  LidarScan scan;
  CloudConversionStats stats;
  daemon::DatasetConfig d;
  d.time_unit = daemon::TimeUnit::s;
  // NaN, infinite and absurd times among good ones: only the good points remain, stamps sane.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  auto c = cloud_with_times<double>({0.01, nan, inf, -inf, 1e300, 0.02}, 8);
  ASSERT_TRUE(daemon::replay::point_cloud_to_scan(c, d, scratch, scan, stats));
  EXPECT_EQ(scan.size(), 2U);
  EXPECT_EQ(stats.dropped_points, 4U);
  EXPECT_EQ(scan.t_offset_ns[1], 10'000'000);
  // Every time unusable: no scan, counted.
  auto bad = cloud_with_times<double>({nan, 1e300}, 8);
  EXPECT_FALSE(daemon::replay::point_cloud_to_scan(bad, d, scratch, scan, stats));
  EXPECT_EQ(stats.bad_time_messages, 1U);
  // A CustomMsg timebase near 2^64 ns (uninitialised memory in a recorder) is skipped.
  auto m = custom_msg();
  m.timebase = std::numeric_limits<std::uint64_t>::max() - 5;
  EXPECT_FALSE(daemon::replay::custom_msg_to_scan(m, scan, stats));
  EXPECT_EQ(stats.bad_time_messages, 2U);
}

TEST(ReplayParts, PointCloudRingsComeFromTheRingFieldOrTheRow) {
  std::vector<rb::CloudPoint> scratch;
  LidarScan scan;
  CloudConversionStats stats;
  const daemon::DatasetConfig d;
  // Organised 2 x 3 cloud without a ring field: the row is the ring (Ouster's ROS driver).
  auto c = cloud_with_times<std::uint32_t>({0, 1, 2, 3, 4, 5}, 6);
  c.height = 2;
  c.width = 3;
  c.row_step = 3 * c.point_step;
  ASSERT_TRUE(daemon::replay::point_cloud_to_scan(c, d, scratch, scan, stats));
  EXPECT_EQ(scan.ring, (std::vector<std::uint16_t>{0, 0, 0, 1, 1, 1}));
  // A uint16 "ring" field (Velodyne) wins; a value that is no ring number reads 0.
  auto r = cloud_with_times<std::uint32_t>({0, 1, 2}, 6);
  r.point_step += 4;
  r.row_step = r.point_step * r.width;
  std::vector<std::uint8_t> data(r.row_step);
  const std::vector<float> rings = {7.0F, 31.0F, -1.0F};
  for (std::size_t i = 0; i < 3; ++i) {
    std::memcpy(&data[i * r.point_step], &r.data[i * 16], 16);
    std::memcpy(&data[i * r.point_step + 16], &rings[i], 4);
  }
  r.data = data;
  r.fields.push_back({"ring", 16, rb::sensor_msgs::PointField::kFloat32, 1});
  ASSERT_TRUE(daemon::replay::point_cloud_to_scan(r, d, scratch, scan, stats));
  EXPECT_EQ(scan.ring, (std::vector<std::uint16_t>{7, 31, 0}));
}

// A live two-LiDAR configuration with a CAN IMU (and a disabled bag sensor), for input
// assignment.
daemon::ConfigResult assignment_config(const std::filesystem::path& dir) {
  const std::string yaml = R"(
body_frame: imu
sensors:
  - name: left
    driver: livox_sdk2
    model: MID-360
    source: {udp: {ports: {lidar: 56301, imu: 56401}}}
    imu: {enabled: false}
    extrinsic: {translation: [0, 0.1, 0], rotation: {rpy_deg: [0, 0, 0]}}
  - name: right
    driver: livox_sdk2
    model: MID-360
    source: {udp: {ports: {lidar: 56311, imu: 56411, command: 56111, push: 56211}}}
    imu: {enabled: false}
    extrinsic: {translation: [0, -0.1, 0], rotation: {rpy_deg: [0, 0, 0]}}
  - name: imu
    driver: can_imu
    source: {device: {interface: can0}}
    can: {decoder: sbg}
  - name: cloud
    driver: dataset_lidar
    model: OS1-64
    enabled: false
    source: {replay: {file: old.bag, topic: /points}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  return daemon::load_config_from_string(yaml, "assign.yaml", dir);
}

TEST(ReplayParts, InputsAreAssignedByNameOrFormat) {
  const auto dir = test::temp_dir("replay_assign");
  for (const char* f : {"a.pcap", "b.pcap", "imu.log", "new.bag"}) std::ofstream(dir / f) << "x";
  const auto loaded = assignment_config(dir);
  // The rig (two LiDARs and a live CAN IMU) is a valid configuration for a run.
  for (const auto& p : loaded.problems) {
    if (p.severity == daemon::Severity::error)
      ADD_FAILURE() << daemon::format_problem(loaded.source, p);
  }
  const auto& config = loaded.config;
  using daemon::replay::assign_recordings;

  // Nothing on the command line: only the configured replay (of the disabled sensor).
  auto r = assign_recordings(config, {});
  ASSERT_EQ(r.size(), 4U);
  EXPECT_FALSE(r[0] || r[1] || r[2]);
  ASSERT_TRUE(r[3]);
  EXPECT_EQ(r[3]->replay.file, dir / "old.bag");
  EXPECT_EQ(r[3]->replay.topic, "/points");

  // One bare pcap goes to both LiDARs, each keeping its configured ports as the filter.
  r = assign_recordings(config, {(dir / "a.pcap").string(), (dir / "imu.log").string()});
  ASSERT_TRUE(r[0] && r[1] && r[2]);
  EXPECT_EQ(r[0]->replay.file, dir / "a.pcap");
  EXPECT_EQ(r[1]->replay.file, dir / "a.pcap");
  EXPECT_EQ(r[0]->ports, (std::vector<std::uint16_t>{56301, 56401}));
  EXPECT_EQ(r[1]->ports, (std::vector<std::uint16_t>{56311, 56411}));
  EXPECT_EQ(r[2]->replay.format, daemon::ReplayFormat::candump);
  EXPECT_TRUE(r[2]->from_command_line);

  // Named inputs win over bare ones of the same format.
  r = assign_recordings(config, {"left=" + (dir / "b.pcap").string(), (dir / "a.pcap").string()});
  EXPECT_EQ(r[0]->replay.file, dir / "b.pcap");
  EXPECT_EQ(r[1]->replay.file, dir / "a.pcap");

  // Two bare pcaps are ambiguous; unknown names, missing files and orphan formats are errors.
  EXPECT_THROW(assign_recordings(config, {(dir / "a.pcap").string(), (dir / "b.pcap").string()}),
               Error);
  EXPECT_THROW(assign_recordings(config, {"centre=" + (dir / "a.pcap").string()}), Error);
  EXPECT_THROW(assign_recordings(config, {(dir / "missing.pcap").string()}), Error);
  // The only bag sensor is disabled: no sensor takes a bare bag.
  EXPECT_THROW(assign_recordings(config, {(dir / "new.bag").string()}), Error);
  // A bag for a sensor without a configured topic.
  EXPECT_THROW(assign_recordings(config, {"imu=" + (dir / "new.bag").string()}), Error);
  // No serial IMU here: a bare serial capture has no sensor to go to.
  std::ofstream(dir / "vn.serial") << "x";
  EXPECT_THROW(assign_recordings(config, {(dir / "vn.serial").string()}), Error);
}

// A bare .serial goes to the serial IMU, whose source may be its live device.
TEST(ReplayParts, SerialCapturesGoToTheSerialImu) {
  const auto dir = test::temp_dir("replay_assign_serial");
  std::ofstream(dir / "vn.serial") << "x";
  const auto loaded = daemon::load_config_from_string(R"(
body_frame: vn
sensors:
  - {name: vlp, driver: velodyne, model: VLP-16, source: {udp: {}},
     extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}}
  - {name: vn, driver: serial_imu, source: {device: {path: /dev/ttyUSB0}},
     serial: {protocol: vectornav_binary}}
)",
                                                      "serial.yaml", dir);
  const auto r = daemon::replay::assign_recordings(loaded.config, {(dir / "vn.serial").string()});
  ASSERT_EQ(r.size(), 2U);
  EXPECT_FALSE(r[0]);
  ASSERT_TRUE(r[1]);
  EXPECT_EQ(r[1]->replay.format, daemon::ReplayFormat::serial);
  EXPECT_EQ(r[1]->replay.file, dir / "vn.serial");
  EXPECT_TRUE(r[1]->from_command_line);
  // The capture is read through the configured protocol's decoder; this one is not a capture.
  EXPECT_THROW(daemon::replay::make_source(loaded.config.sensors[1], r[1]->replay, {}), Error);
  // A serial capture configured for a LiDAR is refused by the loader.
  const auto wrong = daemon::load_config_from_string(R"(
body_frame: vn
sensors:
  - {name: vlp, driver: velodyne, model: VLP-16, source: {replay: {file: vn.serial}},
     extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}}
  - {name: vn, driver: serial_imu, source: {replay: {file: vn.serial}},
     serial: {protocol: vectornav_binary}}
)",
                                                     "wrong.yaml", dir);
  ASSERT_EQ(wrong.problems.size(), 1U);
  EXPECT_EQ(wrong.problems[0].path, "sensors[0].source.replay.format");
}

TEST(ReplayParts, ClockMappingAddsTheOffsetOnceAndPrefersImu) {
  daemon::SensorConfig sensor;
  sensor.name = "l";
  sensor.driver = daemon::Driver::livox_sdk2;
  sensor.time_offset_s = 0.002;
  daemon::runtime::SensorClockMapper mapper(sensor);
  EXPECT_EQ(mapper.domain().config().mode, ClockMode::free_running);
  // A sensor clock 52.25 s behind the host, IMU at 200 Hz with a constant 100 us delay.
  const std::int64_t host0 = 1'700'000'000'000'000'000;
  const std::int64_t sensor0 = 52'250'000'000;
  const std::int64_t delay = 100'000;
  MappedTime last;
  for (int k = 0; k < 1000; ++k) {
    ImuSample s;
    s.stamp.sensor = SensorTime(sensor0 + k * 5'000'000LL);
    s.stamp.host = HostTime(host0 + k * 5'000'000LL + delay);
    mapper.map_imu(s);
    last = s.stamp.mapped;
  }
  // The hull line sits at the delay floor, which one-way stamps cannot see (min_transport_delay
  // is 0): mapped = receive time, plus the configured 2 ms, added once.
  EXPECT_NEAR(static_cast<double>(last.ns - (host0 + 999 * 5'000'000LL + delay + 2'000'000)), 0.0,
              100.0);
  // A scan 50 ms before the newest IMU sample, with a back-dated receive stamp 3 ms late: mapped
  // through the IMU-fed model, not its own receive stamp.
  LidarScan scan;
  scan.start.sensor = SensorTime(sensor0 + 4'945'000'000LL);
  scan.start.host = HostTime(host0 + 4'948'000'000LL);
  mapper.map_scan(scan);
  EXPECT_NEAR(
      static_cast<double>(scan.start.mapped.ns - (host0 + 4'945'000'000LL + delay + 2'000'000)),
      0.0, 100.0);
  EXPECT_EQ(mapper.domain().stats().observations, 1000U);

  // dataset_* sensors default to direct: header stamps are the timeline.
  sensor.driver = daemon::Driver::dataset_imu;
  sensor.time_offset_s = 0.0;
  daemon::runtime::SensorClockMapper direct(sensor);
  ImuSample s;
  s.stamp.sensor = SensorTime(123'456'789);
  s.stamp.host = HostTime(host0);
  direct.map_imu(s);
  EXPECT_EQ(s.stamp.mapped.ns, 123'456'789);
}

}  // namespace
}  // namespace livod
