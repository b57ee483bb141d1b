// The simulator's ROS1 bag: it holds exactly what livod's decoders read from the capture files
// (so a bag replay and a capture replay feed an estimator identical inputs), its header stamps are
// the true host time of the measurements, and the message layouts are what the ROS peers read.

#include "tools/sim/bag_output.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <set>

#include "drivers/imu/candump_frames.hpp"
#include "drivers/imu/sbg_can.hpp"
#include "drivers/livox/livox_decoder.hpp"
#include "io/candump.hpp"
#include "io/euroc.hpp"
#include "io/pcap.hpp"
#include "io/rosbag/bag_reader.hpp"
#include "io/rosbag/point_cloud.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/runner.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::sim {
namespace {

namespace ros = io::rosbag;

constexpr double kEpoch = 1'700'000'000.0;
constexpr std::int64_t kEpochNs = 1'700'000'000'000'000'000;
constexpr double kAviaPacketSpanNs = 96 * 4167;

bool simulated(const std::string& model) {
  for (const auto& [m, _] : simulated_lidar_models()) {
    if (m == model) return true;
  }
  return false;
}

// What livod decodes from one capture, with the stamps mapped as the bag maps them.
struct Decoded {
  std::vector<LidarScan> scans;  // with at least one valid point
  std::vector<std::int64_t> scan_stamps_ns;
  std::vector<ImuSample> imu;
  std::vector<std::int64_t> imu_stamps_ns;
};

Decoded decode_capture(const std::filesystem::path& dir, const LidarMount& mount) {
  std::optional<std::filesystem::path> metadata;
  if (std::filesystem::exists(dir / (mount.name + ".json")))
    metadata = dir / (mount.name + ".json");
  auto decoder = make_capture_decoder(mount.model, metadata);
  const SensorClockInverse clock(mount.clock, kEpochNs, lidar_stamp_wrap_ns(mount.model));
  Decoded out;
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) {
    if (std::count(s.valid.begin(), s.valid.end(), 1) == 0) return;
    out.scans.push_back(s);
    out.scan_stamps_ns.push_back(clock.host_ns(s.start.sensor.ns, s.start.host.ns));
  };
  sinks.on_imu = [&](const ImuSample& m) {
    out.imu.push_back(m);
    out.imu_stamps_ns.push_back(clock.host_ns(m.stamp.sensor.ns, m.stamp.host.ns));
  };
  io::PcapReader reader(dir / (mount.name + ".pcap"));
  while (const auto d = reader.next()) {
    decoder->on_packet({d->payload, d->capture_time_ns, d->dst_port}, sinks);
  }
  decoder->flush(sinks);
  EXPECT_EQ(decoder->counters().decode_errors, 0u);
  return out;
}

struct BagTopic {
  std::string type;
  std::vector<std::int64_t> record_ns;
  std::vector<std::vector<std::byte>> data;
};

std::map<std::string, BagTopic> read_bag(const std::filesystem::path& path) {
  ros::BagReader bag(path);
  std::map<std::string, BagTopic> topics;
  auto cursor = bag.read();
  while (const auto m = cursor.next()) {
    BagTopic& t = topics[m->connection->topic];
    t.type = m->connection->type;
    t.record_ns.push_back(m->time_ns);
    t.data.emplace_back(m->data.begin(), m->data.end());
  }
  return topics;
}

void expect_imu_equal(const BagTopic& topic, const std::vector<ImuSample>& imu,
                      const std::vector<std::int64_t>& stamps, const std::string& what) {
  ASSERT_EQ(topic.type, "sensor_msgs/Imu") << what;
  ASSERT_EQ(topic.data.size(), imu.size()) << what;
  ASSERT_GT(imu.size(), 0u) << what;
  for (std::size_t i = 0; i < imu.size(); ++i) {
    const auto msg = ros::deserialize<ros::sensor_msgs::Imu>(topic.data[i]);
    ASSERT_EQ(msg.header.seq, i) << what;
    ASSERT_EQ(msg.header.stamp.to_ns(), stamps[i]) << what << " sample " << i;
    // Received after it was measured.
    EXPECT_GE(topic.record_ns[i], stamps[i]) << what << " sample " << i;
    ASSERT_EQ(msg.angular_velocity.x, imu[i].gyro_rad_s.x()) << what;
    ASSERT_EQ(msg.angular_velocity.y, imu[i].gyro_rad_s.y()) << what;
    ASSERT_EQ(msg.angular_velocity.z, imu[i].gyro_rad_s.z()) << what;
    ASSERT_EQ(msg.linear_acceleration.x, imu[i].accel_m_s2.x()) << what;
    ASSERT_EQ(msg.linear_acceleration.y, imu[i].accel_m_s2.y()) << what;
    ASSERT_EQ(msg.linear_acceleration.z, imu[i].accel_m_s2.z()) << what;
    EXPECT_EQ(msg.orientation_covariance[0], -1.0);
  }
}

// The valid points of a decoded scan as the bag should carry them.
struct WirePoint {
  float x, y, z, intensity;
  std::uint32_t offset_ns;
  std::uint16_t ring;
  friend bool operator==(const WirePoint&, const WirePoint&) = default;
};

std::vector<WirePoint> valid_points(const LidarScan& s) {
  std::vector<WirePoint> out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s.valid[i] == 0) continue;
    EXPECT_GE(s.t_offset_ns[i], 0);
    out.push_back({s.x[i], s.y[i], s.z[i], s.intensity[i],
                   static_cast<std::uint32_t>(s.t_offset_ns[i]), s.ring[i]});
  }
  return out;
}

void expect_scans_equal(const BagTopic& topic, const Decoded& decoded, bool livox,
                        const std::string& what) {
  ASSERT_EQ(topic.data.size(), decoded.scans.size()) << what;
  ASSERT_GT(decoded.scans.size(), 0u) << what;
  for (std::size_t k = 0; k < decoded.scans.size(); ++k) {
    const auto expected = valid_points(decoded.scans[k]);
    std::vector<WirePoint> got;
    std::int64_t stamp = 0;
    if (livox) {
      ASSERT_EQ(topic.type, "livox_ros_driver/CustomMsg");
      const auto msg = ros::deserialize<ros::livox_ros_driver::CustomMsg>(topic.data[k]);
      EXPECT_EQ(msg.header.seq, k);
      stamp = msg.header.stamp.to_ns();
      EXPECT_EQ(msg.timebase, static_cast<std::uint64_t>(stamp));
      EXPECT_EQ(msg.point_num, msg.points.size());
      for (const auto& p : msg.points) {
        EXPECT_EQ(p.tag, 0);
        got.push_back({p.x, p.y, p.z, static_cast<float>(p.reflectivity), p.offset_time, p.line});
      }
    } else {
      ASSERT_EQ(topic.type, "sensor_msgs/PointCloud2");
      const auto msg = ros::deserialize<ros::sensor_msgs::PointCloud2>(topic.data[k]);
      EXPECT_EQ(msg.header.seq, k);
      stamp = msg.header.stamp.to_ns();
      std::vector<ros::CloudPoint> pts;
      ros::extract_points(msg, {.time = "t"}, pts);
      const auto ring = std::find_if(msg.fields.begin(), msg.fields.end(),
                                     [](const auto& f) { return f.name == "ring"; });
      ASSERT_NE(ring, msg.fields.end());
      for (std::size_t i = 0; i < pts.size(); ++i) {
        const std::span<const std::uint8_t> point(msg.data.data() + i * msg.point_step,
                                                  msg.point_step);
        got.push_back({pts[i].x, pts[i].y, pts[i].z, pts[i].intensity,
                       static_cast<std::uint32_t>(pts[i].time),
                       static_cast<std::uint16_t>(ros::read_point_field(point, *ring, false))});
      }
    }
    ASSERT_EQ(stamp, decoded.scan_stamps_ns[k]) << what << " scan " << k;
    // Recorded once the scan was complete, i.e. after its last point.
    const auto& s = decoded.scans[k];
    const std::int32_t last = *std::max_element(s.t_offset_ns.begin(), s.t_offset_ns.end());
    EXPECT_GT(topic.record_ns[k], stamp + last) << what << " scan " << k;
    ASSERT_EQ(got.size(), expected.size()) << what << " scan " << k;
    for (std::size_t i = 0; i < got.size(); ++i) {
      ASSERT_EQ(got[i], expected[i]) << what << " scan " << k << " point " << i;
    }
  }
}

void check_bag_equals_outputs(const std::string& name, double duration, bool images) {
  Scenario scenario = make_scenario(name);
  std::erase_if(scenario.lidars, [](const LidarMount& l) { return !simulated(l.model); });
  SimRunOptions o;
  o.out_dir = test::temp_dir("bag_" + name);
  o.seed = 11;
  o.duration_s = duration;
  o.host_epoch_s = kEpoch;
  o.write_images = images;
  o.write_bag = true;
  const SimRunReport report = run_scenario(scenario, o);
  ASSERT_EQ(report.sensors.back().kind, "bag");
  const auto topics = read_bag(o.out_dir / "sequence.bag");
  std::uint64_t total = 0;
  for (const auto& [_, t] : topics) total += t.data.size();
  EXPECT_EQ(total, report.sensors.back().messages);

  std::set<std::string> expected_topics;
  for (const auto& mount : scenario.lidars) {
    const Decoded decoded = decode_capture(o.out_dir, mount);
    const bool livox = livox::livox_model(mount.model).has_value();
    const bool ouster = mount.model.rfind("OS", 0) == 0;
    const std::string points = livox    ? "/livox/lidar"
                               : ouster ? "/os_cloud_node/points"
                                        : "/velodyne_points";
    ASSERT_TRUE(topics.contains(points)) << name << ": no " << points;
    expected_topics.insert(points);
    expect_scans_equal(topics.at(points), decoded, livox, name + " " + points);
    if (mount.imu && !decoded.imu.empty()) {
      const std::string imu = livox    ? "/livox/imu"
                              : ouster ? "/os_cloud_node/imu"
                                       : "/imu/data";  // the HDL-32E's
      ASSERT_TRUE(topics.contains(imu)) << name << ": no " << imu;
      expected_topics.insert(imu);
      expect_imu_equal(topics.at(imu), decoded.imu, decoded.imu_stamps_ns, name + " " + imu);
    }
  }
  if (scenario.can_imu) {
    const auto& mount = *scenario.can_imu;
    io::CandumpReader reader(o.out_dir / (mount.name + ".log"));
    imu::SbgCanDecoder decoder;
    const SensorClockInverse clock(mount.clock, kEpochNs, kSbgCounterWrapNs);
    std::vector<ImuSample> imu;
    std::vector<std::int64_t> stamps;
    io::CanFrame frame;
    while (reader.next(frame)) {
      decoder.on_frame(imu::to_can_record(frame), [&](const ImuSample& s) {
        imu.push_back(s);
        stamps.push_back(clock.host_ns(s.stamp.sensor.ns, s.stamp.host.ns));
      });
    }
    ASSERT_TRUE(topics.contains("/imu"));
    expected_topics.insert("/imu");
    expect_imu_equal(topics.at("/imu"), imu, stamps, name + " /imu");
  }
  for (const auto& cam : scenario.cameras) {
    const auto records = io::read_euroc_camera_csv(o.out_dir / "mav0" / cam.name / "data.csv");
    if (!images) {
      EXPECT_FALSE(topics.contains("/left_camera/image")) << "images without PNG files";
      continue;
    }
    expected_topics.insert("/left_camera/image");
    const BagTopic& topic = topics.at("/left_camera/image");
    ASSERT_EQ(topic.type, "sensor_msgs/Image");
    ASSERT_EQ(topic.data.size(), records.size());
    for (std::size_t i = 0; i < records.size(); ++i) {
      const auto msg = ros::deserialize<ros::sensor_msgs::Image>(topic.data[i]);
      EXPECT_EQ(msg.header.stamp.to_ns(), records[i].timestamp.ns);
      EXPECT_EQ(topic.record_ns[i], records[i].timestamp.ns);
      EXPECT_EQ(msg.encoding, "mono8");
      const auto png = load_image_message(records[i], cam.name, static_cast<std::uint32_t>(i));
      EXPECT_EQ(msg, png);
    }
  }
  std::set<std::string> got_topics;
  for (const auto& [t, _] : topics) got_topics.insert(t);
  EXPECT_EQ(got_topics, expected_topics);
}

TEST(BagOutput, AviaBagHoldsExactlyTheDecodedCaptureAndImages) {
  check_bag_equals_outputs("room_handheld_avia", 0.6, true);
}

TEST(BagOutput, Mid360BagHoldsExactlyTheDecodedCapture) {
  check_bag_equals_outputs("room_handheld_mid360", 0.6, false);
}

TEST(BagOutput, OusterBagHoldsExactlyTheDecodedCapture) {
  ASSERT_TRUE(simulated("OS1-64")) << "the simulator has no OS1-64 model";
  check_bag_equals_outputs("room_handheld_os1_64", 0.6, false);
}

// The VLP-16 cloud when the model is simulated, the CAN IMU in any case.
TEST(BagOutput, StreetVehicleBagHoldsTheCanImuAndTheVelodyneCloud) {
  check_bag_equals_outputs("street_vehicle_vlp16", 0.6, false);
}

// The HDL-32E's cloud and its internal IMU (from the position packets).
TEST(BagOutput, Hdl32eBagHoldsTheCloudAndTheInternalImu) {
  ASSERT_TRUE(simulated("HDL-32E")) << "the simulator has no HDL-32E model";
  check_bag_equals_outputs("street_vehicle_hdl32e", 0.6, false);
}

// Header stamps are the true host time of each measurement: the sensor clock (offset, skew, a
// reset that makes readings ambiguous) is undone exactly.
TEST(BagOutput, StampsAreTheTrueHostTimeOfTheMeasurements) {
  const Scenario scenario = make_scenario("room_handheld_avia");
  const World world = make_room_world(1);
  const Trajectory trajectory(scenario.trajectory);
  for (const ClockFaults& faults :
       {scenario.lidars[0].clock,
        ClockFaults{.offset_s = 0.2, .skew_ppm = 30.0, .jitter_s = 0.0, .reset_at_s = 4.55}}) {
    SimLidarOptions lo;
    lo.clock = faults;
    lo.range = scenario.lidars[0].range;
    lo.imu_noise = scenario.lidars[0].imu_noise;
    lo.host_epoch_s = kEpoch;
    auto lidar = make_sim_lidar("AVIA", lo);
    SceneContext scene{&world, &trajectory, scenario.lidars[0].T_body_sensor};
    std::vector<SimDatagram> datagrams;
    std::vector<double> point_t;  // true times of the valid points, emission order
    std::vector<double> imu_t;
    SimOutputs out;
    out.on_datagram = [&](SimDatagram&& d) { datagrams.push_back(std::move(d)); };
    out.on_point = [&](const SimPointTruth& p) {
      if (p.valid) point_t.push_back(p.t);
    };
    out.on_imu = [&](const SimImuTruth& m) { imu_t.push_back(m.t); };
    lidar->run(4.0, 5.0, scene, out);  // moving, and across the reset

    livox::LivoxDecoder decoder(*livox::livox_model("AVIA"), livox::LivoxDecoderOptions{});
    const SensorClockInverse clock(faults, kEpochNs);
    std::size_t p = 0;
    std::size_t m = 0;
    std::size_t scans = 0;
    double max_point_error = 0.0;
    double max_imu_error = 0.0;
    drivers::DecoderSinks sinks;
    sinks.on_scan = [&](const LidarScan& s) {
      const auto msg = to_custom_msg(s, clock.host_ns(s.start.sensor.ns, s.start.host.ns), "avia",
                                     static_cast<std::uint32_t>(scans++));
      for (const auto& q : msg.points) {
        ASSERT_LT(p, point_t.size());
        // A bag reader's point time: stamp + offset. Offsets are sensor clock durations since
        // the packet's stamp, which can precede the scan start by one packet: they are off by
        // the skew over that span.
        const auto t_ns =
            static_cast<double>(static_cast<std::int64_t>(msg.timebase) + q.offset_time - kEpochNs);
        const double tolerance =
            2.0 + std::abs(faults.skew_ppm) * 1e-6 * (q.offset_time + kAviaPacketSpanNs);
        max_point_error = std::max(max_point_error, std::abs(t_ns - point_t[p] * 1e9) - tolerance);
        ++p;
      }
    };
    sinks.on_imu = [&](const ImuSample& s) {
      ASSERT_LT(m, imu_t.size());
      const auto t_ns =
          static_cast<double>(clock.host_ns(s.stamp.sensor.ns, s.stamp.host.ns) - kEpochNs);
      max_imu_error = std::max(max_imu_error, std::abs(t_ns - imu_t[m] * 1e9));
      ++m;
    };
    // In emission order: this checks stamps, not the link's reordering.
    for (const auto& d : datagrams)
      decoder.on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
    decoder.flush(sinks);
    EXPECT_EQ(p, point_t.size());
    EXPECT_EQ(m, imu_t.size());
    EXPECT_GE(scans, faults.reset_at_s > 0 ? 11u : 10u);
    EXPECT_LE(max_point_error, 0.0) << "reset at " << faults.reset_at_s;
    EXPECT_LE(max_imu_error, 2.0) << "reset at " << faults.reset_at_s;
  }
}

// Stamps that only give the reading modulo a period (Velodyne: microseconds past the hour, with
// the hour from the host clock; SBG: a 32-bit microsecond counter) map back through the receive
// time.
TEST(BagOutput, ClockInverseUnwrapsPeriodicStamps) {
  constexpr std::int64_t kHourNs = std::int64_t{3600} * 1'000'000'000;
  EXPECT_EQ(lidar_stamp_wrap_ns("VLP-16"), kHourNs);
  EXPECT_EQ(lidar_stamp_wrap_ns("AVIA"), 0);
  EXPECT_EQ(lidar_stamp_wrap_ns("OS1-64"), 0);
  struct Case {
    ClockFaults faults;
    std::int64_t wrap_ns;
    std::int64_t decoder_base_ns;  // what the decoder puts above the wrapped part
  };
  for (const Case& c :
       {Case{{.offset_s = 1500.0, .skew_ppm = 15.0}, kHourNs, 472'222 * kHourNs},
        Case{{.offset_s = 4200.0, .skew_ppm = -40.0}, kSbgCounterWrapNs, 0},
        Case{{.offset_s = 3000.0, .skew_ppm = 10.0, .reset_at_s = 700.0}, kHourNs, 3 * kHourNs}}) {
    SensorClock sensor(c.faults, 1);
    const SensorClockInverse inverse(c.faults, kEpochNs, c.wrap_ns);
    for (const double t : {0.0, 12.5, 599.9, 600.1, 699.0, 701.0, 2100.0, 4000.0}) {
      const std::int64_t reading = sensor.stamp_ns(t);
      const std::int64_t wire = ((reading % c.wrap_ns) + c.wrap_ns) % c.wrap_ns;
      const std::int64_t rx = kEpochNs + std::llround(t * 1e9) + 250'000;
      EXPECT_NEAR(inverse.scenario_time(c.decoder_base_ns + wire, rx), t, 1e-9)
          << "t " << t << " wrap " << c.wrap_ns << " offset " << c.faults.offset_s;
    }
  }
}

TEST(BagOutput, ClockInverseUndoesOffsetSkewAndReset) {
  constexpr std::int64_t kDelayNs = 150'000;
  for (const ClockFaults& faults :
       {ClockFaults{.offset_s = 1234.5, .skew_ppm = 30.0, .jitter_s = 0.0, .reset_at_s = -1},
        ClockFaults{.offset_s = 100.0, .skew_ppm = -50.0, .jitter_s = 0.0, .reset_at_s = 10.0},
        // Readings 0..10 s before the reset and 0.. s after it: ambiguous without the receive time.
        ClockFaults{.offset_s = 0.0, .skew_ppm = 40.0, .jitter_s = 0.0, .reset_at_s = 10.0}}) {
    SensorClock sensor(faults, 1);
    const SensorClockInverse inverse(faults, kEpochNs);
    for (const double t : {0.0, 0.25, 3.0, 9.999, 10.0, 10.001, 13.0, 19.5, 400.0}) {
      const std::int64_t reading = sensor.stamp_ns(t);
      const std::int64_t rx = kEpochNs + std::llround(t * 1e9) + kDelayNs;
      EXPECT_NEAR(inverse.scenario_time(reading, rx), t, 1e-9)
          << "t " << t << " reset " << faults.reset_at_s << " offset " << faults.offset_s;
      EXPECT_NEAR(static_cast<double>(inverse.host_ns(reading, rx) - kEpochNs), t * 1e9, 1.0);
    }
  }
}

LidarScan synthetic_scan() {
  LidarScan s;
  s.push_back(1.5F, -2.25F, 0.125F, 17.0F, 3, 0, 1'000, true);
  s.push_back(0.0F, 0.0F, 0.0F, 0.0F, 4, 0, 2'000, false);  // no return: not written
  s.push_back(-4.0F, 8.5F, -0.5F, 250.0F, 63, 0, -500, true);
  s.push_back(7.0F, 0.5F, 2.0F, 3.0F, 300, 0, 99'999'000, true);
  return s;
}

TEST(BagOutput, PointCloudLayoutsReadBackWithTheirFieldTypes) {
  const LidarScan scan = synthetic_scan();
  constexpr std::int64_t kStart = 1'700'000'000'250'000'000;
  for (const CloudLayout layout : {CloudLayout::kOuster, CloudLayout::kVelodyne}) {
    const bool velodyne = layout == CloudLayout::kVelodyne;
    const auto cloud = to_point_cloud2(scan, layout, kStart, "lidar", 7);
    // The point before the scan start moves the stamp back so that every offset is >= 0.
    EXPECT_EQ(cloud.header.stamp.to_ns(), kStart - 500);
    EXPECT_EQ(cloud.header.seq, 7u);
    EXPECT_EQ(cloud.header.frame_id, "lidar");
    EXPECT_EQ(cloud.height, 1u);
    EXPECT_EQ(cloud.width, 3u);
    EXPECT_TRUE(cloud.is_dense);
    EXPECT_EQ(cloud.row_step, cloud.width * cloud.point_step);
    std::map<std::string, std::uint8_t> types;
    for (const auto& f : cloud.fields) types[f.name] = f.datatype;
    using F = ros::sensor_msgs::PointField;
    EXPECT_EQ(types["t"], F::kUint32);
    EXPECT_EQ(types["ring"], velodyne ? F::kUint16 : F::kUint8);
    EXPECT_EQ(types.contains("time"), velodyne);
    // Through the wire format and the generic reader.
    const auto back = ros::deserialize<ros::sensor_msgs::PointCloud2>(ros::serialize(cloud));
    std::vector<ros::CloudPoint> pts;
    ros::extract_points(back, {.time = "t"}, pts);
    ASSERT_EQ(pts.size(), 3u);
    const std::array<std::size_t, 3> source = {0, 2, 3};
    for (std::size_t i = 0; i < 3; ++i) {
      const std::size_t j = source[i];
      EXPECT_EQ(pts[i].x, scan.x[j]);
      EXPECT_EQ(pts[i].y, scan.y[j]);
      EXPECT_EQ(pts[i].z, scan.z[j]);
      EXPECT_EQ(pts[i].intensity, scan.intensity[j]);
      EXPECT_EQ(pts[i].time, static_cast<double>(scan.t_offset_ns[j] + 500));
    }
    const auto ring = std::find_if(back.fields.begin(), back.fields.end(),
                                   [](const auto& f) { return f.name == "ring"; });
    const std::span<const std::uint8_t> third(back.data.data() + 2 * back.point_step,
                                              back.point_step);
    EXPECT_EQ(ros::read_point_field(third, *ring, false), velodyne ? 300.0 : 300.0 - 256.0);
    if (velodyne) {
      ros::extract_points(back, {.time = "time"}, pts);
      EXPECT_FLOAT_EQ(static_cast<float>(pts[2].time), 99'999'500e-9F);
    }
  }
}

TEST(BagOutput, CustomMsgCarriesTheValidPointsAfterTheTimebase) {
  const auto msg = to_custom_msg(synthetic_scan(), 5'000'000'000, "avia", 2);
  EXPECT_EQ(msg.header.stamp.to_ns(), 5'000'000'000 - 500);
  EXPECT_EQ(msg.timebase, 5'000'000'000u - 500u);
  EXPECT_EQ(msg.header.frame_id, "avia");
  ASSERT_EQ(msg.point_num, 3u);
  ASSERT_EQ(msg.points.size(), 3u);
  EXPECT_EQ(msg.points[0].offset_time, 1'500u);
  EXPECT_EQ(msg.points[1].offset_time, 0u);
  EXPECT_EQ(msg.points[2].offset_time, 99'999'500u);
  EXPECT_EQ(msg.points[1].reflectivity, 250);
  EXPECT_EQ(msg.points[1].line, 63);
  EXPECT_EQ(msg.points[0].x, 1.5F);
  // Round trip through the ROS wire format.
  EXPECT_EQ(ros::deserialize<ros::livox_ros_driver::CustomMsg>(ros::serialize(msg)), msg);
}

}  // namespace
}  // namespace livod::sim
