// Decoding the simulator's Ouster captures with livod's Ouster decoder, configured only from the
// metadata JSON the simulator writes, gives back exactly the simulated points (after the wire's
// millimetre range quantisation, which the simulator applies; float32 in the decoder), each with
// its column's time, and the simulated IMU samples (within float32 and the g / deg/s units).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "drivers/ouster/imu_packet.hpp"
#include "drivers/ouster/lidar_packet.hpp"
#include "drivers/ouster/metadata.hpp"
#include "drivers/ouster/ouster_decoder.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::sim {
namespace {

namespace os = drivers::ouster;

constexpr double kColumnPeriodNs = 1e9 / (1024.0 * 10.0);  // 1024x10 on the sensor clock

World world_of(const Scenario& s) {
  return s.world == WorldKind::kStreet ? make_street_world(1, s.street_length_m)
                                       : make_room_world(1);
}

// Scenario time at which frame `frame` starts (column 0 of that frame): the motor follows the
// sensor's oscillator, which runs skew_ppm fast.
double frame_start_s(int frame, const ClockFaults& clock) {
  return frame * 0.1 / (1.0 + clock.skew_ppm * 1e-6);
}

struct Capture {
  std::vector<SimDatagram> datagrams;
  std::vector<SimPointTruth> points;
  std::vector<SimImuTruth> imu;
};

struct Decoded {
  std::vector<Eigen::Vector3f> points;
  std::vector<std::int64_t> point_stamps_ns;  // sensor clock
  std::vector<float> intensity;
  std::vector<std::uint16_t> ring;
  std::vector<std::int64_t> scan_starts_ns;
  std::vector<ImuSample> imu;
};

class OusterSimRun {
 public:
  // exact_range: no range noise and no dropouts.
  explicit OusterSimRun(const std::string& scenario_name, bool exact_range = false)
      : scenario_(make_scenario(scenario_name)),
        world_(world_of(scenario_)),
        trajectory_(scenario_.trajectory),
        mount_(scenario_.lidars.at(0)) {
    options_.clock = mount_.clock;
    options_.range = mount_.range;
    options_.link = mount_.link;
    options_.imu_noise = mount_.imu_noise;
    options_.seed = 99;
    if (exact_range) {
      // The basic model only: no divergence (mixed pixels), range walk or noise growth.
      options_.range = plain_range_model(options_.range);
      options_.range.sigma_m = 0.0;
      options_.range.dropout_probability = 0.0;
    }
    scene_ = SceneContext{&world_, &trajectory_, mount_.T_body_sensor};
  }

  [[nodiscard]] std::unique_ptr<SimLidar> make_lidar() const {
    return make_sim_lidar(mount_.model, options_);
  }

  // Simulates whole frames [first, first + count).
  Capture simulate(SimLidar& lidar, int first_frame, int frames) const {
    Capture c;
    SimOutputs out;
    out.on_datagram = [&](SimDatagram&& d) { c.datagrams.push_back(std::move(d)); };
    out.on_point = [&](const SimPointTruth& p) { c.points.push_back(p); };
    out.on_imu = [&](const SimImuTruth& m) { c.imu.push_back(m); };
    // 1 us before the frame boundaries: columns are 98 us apart, so exactly the frames' packets.
    lidar.run(frame_start_s(first_frame, mount_.clock) - 1e-6,
              frame_start_s(first_frame + frames, mount_.clock) - 1e-6, scene_, out);
    return c;
  }

  [[nodiscard]] const LidarMount& mount() const { return mount_; }
  [[nodiscard]] const SceneContext& scene() const { return scene_; }

 private:
  Scenario scenario_;
  World world_;
  Trajectory trajectory_;
  LidarMount mount_;
  SimLidarOptions options_;
  SceneContext scene_;
};

os::SensorMetadata write_and_load_metadata(const SimLidar& lidar, const std::string& dir_name) {
  const auto dir = test::temp_dir(dir_name);
  const auto files = lidar.write_side_files(dir, "os1");
  EXPECT_EQ(files.size(), 1u);
  EXPECT_EQ(files.at(0), dir / "os1.json");
  return os::load_metadata(files.at(0));
}

Decoded decode(os::OusterDecoder& decoder, const Capture& capture) {
  Decoded d;
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) {
    d.scan_starts_ns.push_back(s.start.sensor.ns);
    for (std::size_t i = 0; i < s.size(); ++i) {
      d.points.push_back(s.point(i));
      d.point_stamps_ns.push_back(s.start.sensor.ns + s.t_offset_ns[i]);
      d.intensity.push_back(s.intensity[i]);
      d.ring.push_back(s.ring[i]);
    }
  };
  sinks.on_imu = [&](const ImuSample& m) { d.imu.push_back(m); };
  for (const auto& g : capture.datagrams) {
    decoder.on_packet({g.payload, g.host_time_ns, g.dst_port}, sinks);
  }
  decoder.flush(sinks);
  return d;
}

void round_trip(const std::string& scenario_name, int first_frame, int frames, std::size_t rows) {
  const OusterSimRun run(scenario_name);
  auto lidar = run.make_lidar();
  EXPECT_EQ(lidar->model(), "OS");
  const Capture capture = run.simulate(*lidar, first_frame, frames);
  ASSERT_FALSE(capture.datagrams.empty());
  ASSERT_EQ(capture.points.size(), static_cast<std::size_t>(frames) * 1024 * rows);

  os::OusterDecoder decoder(write_and_load_metadata(*lidar, "ouster_sim_" + scenario_name));
  ASSERT_TRUE(decoder.packet_format().lidar_crc) << "the CRC-64 footer must be checked";
  const Decoded decoded = decode(decoder, capture);
  const auto& counters = decoder.counters();
  EXPECT_EQ(counters.decode_errors, 0u);
  EXPECT_EQ(counters.sequence_gaps, 0u);
  EXPECT_EQ(counters.incomplete_scans, 0u);
  EXPECT_EQ(counters.scans, static_cast<std::uint64_t>(frames));
  EXPECT_EQ(counters.lidar_packets, static_cast<std::uint64_t>(frames) * 1024 / 16);
  EXPECT_EQ(decoder.ouster_counters().frame_id_gaps, 0u);
  EXPECT_EQ(decoder.ouster_counters().late_packets, 0u);
  EXPECT_FALSE(decoder.metadata_init_id_mismatch());

  // Points: same count, order, coordinates, ring, reflectivity and time.
  SensorClock reference_clock(run.mount().clock, 0);  // no jitter in these mounts: exact stamps
  ASSERT_EQ(run.mount().clock.jitter_s, 0.0);
  const auto first_column = static_cast<std::int64_t>(first_frame) * 1024;
  const double offset_ns = run.mount().clock.offset_s * 1e9;
  std::size_t k = 0;
  for (std::size_t i = 0; i < capture.points.size(); ++i) {
    const SimPointTruth& t = capture.points[i];
    if (!t.valid) continue;
    ASSERT_LT(k, decoded.points.size());
    ASSERT_LT((decoded.points[k] - t.p_sensor.cast<float>()).norm(), 1e-4F) << "point " << k;
    ASSERT_EQ(decoded.ring[k], t.ring) << "point " << k;
    ASSERT_EQ(decoded.intensity[k], t.reflectivity) << "point " << k;
    ASSERT_EQ(decoded.point_stamps_ns[k], reference_clock.stamp_ns(t.t)) << "point " << k;
    // The column grid on the sensor clock: column n at offset + n * 1e9 / 10240 ns.
    const auto column = first_column + static_cast<std::int64_t>(i / rows);
    ASSERT_NEAR(static_cast<double>(decoded.point_stamps_ns[k]),
                offset_ns + static_cast<double>(column) * kColumnPeriodNs, 1.0)
        << "point " << k;
    ++k;
  }
  EXPECT_EQ(k, decoded.points.size());
  EXPECT_GT(k, capture.points.size() / 2) << "too few returns";
  ASSERT_EQ(decoded.scan_starts_ns.size(), static_cast<std::size_t>(frames));
  for (std::size_t f = 1; f < decoded.scan_starts_ns.size(); ++f) {
    EXPECT_NEAR(static_cast<double>(decoded.scan_starts_ns[f] - decoded.scan_starts_ns[f - 1]), 1e8,
                1.0);
  }

  // IMU: every sample, on the LiDAR clock, SI after the decoder's g and deg/s conversion.
  ASSERT_FALSE(capture.imu.empty());
  ASSERT_EQ(decoded.imu.size(), capture.imu.size());
  for (std::size_t i = 0; i < decoded.imu.size(); ++i) {
    EXPECT_EQ(decoded.imu[i].stamp.sensor.ns, reference_clock.stamp_ns(capture.imu[i].t));
    EXPECT_LT((decoded.imu[i].gyro_rad_s - capture.imu[i].gyro_rad_s).norm(), 1e-6);
    EXPECT_LT((decoded.imu[i].accel_m_s2 - capture.imu[i].accel_m_s2).norm(), 1e-5);
  }
}

TEST(OusterSim, Os1_64CaptureDecodesToTheSimulatedPoints) {
  // Frames 40-43 (4.0-4.4 s, walking) carry frame ids 65534, 65535, 0, 1.
  round_trip("room_handheld_os1_64", 40, 4, 64);
}

TEST(OusterSim, Os1_128CaptureDecodesToTheSimulatedPoints) {
  round_trip("street_vehicle_os1_128", 40, 2, 128);
}

TEST(OusterSim, DecodedPointsLieOnTheRoomSurfacesWherePoseAndMountPutThem) {
  // Independent of the ray caster: with an exact range, decoded points moved to the world with
  // the ground-truth pose at their column time lie inside the 12 x 9 x 3 m room, and those on its
  // six faces lie on them to the wire's millimetre quantisation. A wrong beam origin (15.8 mm),
  // mount, direction or column time would move them off.
  const OusterSimRun run("room_handheld_os1_64", /*exact_range=*/true);
  auto lidar = run.make_lidar();
  const Capture capture = run.simulate(*lidar, 45, 1);
  os::OusterDecoder decoder(write_and_load_metadata(*lidar, "ouster_sim_room_geometry"));
  const Decoded decoded = decode(decoder, capture);
  ASSERT_GT(decoded.points.size(), 50000u);
  std::size_t k = 0;
  std::vector<double> face_distances;
  constexpr double kInside = 1e-3;
  for (const auto& t : capture.points) {
    if (!t.valid) continue;
    const Eigen::Vector3d p = run.scene().T_world_sensor(t.t) * decoded.points[k++].cast<double>();
    ASSERT_LT(std::abs(p.x()), 6.0 + kInside) << p.transpose();
    ASSERT_LT(std::abs(p.y()), 4.5 + kInside) << p.transpose();
    ASSERT_GT(p.z(), -kInside) << p.transpose();
    ASSERT_LT(p.z(), 3.0 + kInside) << p.transpose();
    const double d = std::min({std::abs(std::abs(p.x()) - 6.0), std::abs(std::abs(p.y()) - 4.5),
                               std::abs(p.z()), std::abs(p.z() - 3.0)});
    if (d < 0.05) face_distances.push_back(d);
  }
  ASSERT_GT(face_distances.size(), decoded.points.size() / 2);
  std::sort(face_distances.begin(), face_distances.end());
  const auto quantile = [&](double q) {
    return face_distances[static_cast<std::size_t>(q * static_cast<double>(face_distances.size()))];
  };
  // Millimetre ranges: at most 0.5 mm off along the ray, less along the face normal.
  EXPECT_LT(quantile(0.5), 0.3e-3);
  EXPECT_LT(quantile(0.95), 0.5e-3);
}

TEST(OusterSim, MetadataDescribesAnOs1LikeTheRealOnes) {
  const OusterSimRun run("room_handheld_os1_64");
  auto lidar = run.make_lidar();
  const os::SensorMetadata m = write_and_load_metadata(*lidar, "ouster_sim_metadata");
  EXPECT_FALSE(m.legacy_layout);
  EXPECT_EQ(m.prod_line, "OS-1-64");
  ASSERT_TRUE(m.prod_sn_number.has_value());
  ASSERT_TRUE(m.initialization_id.has_value());
  EXPECT_EQ(m.firmware, (os::FirmwareVersion{2, 5, 2}));
  EXPECT_TRUE(m.lidar_packets_have_crc());
  EXPECT_FALSE(m.imu_packets_have_crc());
  EXPECT_EQ(m.lidar_mode, "1024x10");
  EXPECT_EQ(m.timestamp_mode, os::TimestampMode::kInternalOsc);
  EXPECT_EQ(m.udp_port_lidar, 7502);
  EXPECT_EQ(m.udp_port_imu, 7503);
  EXPECT_EQ(m.format.udp_profile_lidar, os::LidarProfile::kRng19Rfl8Sig16Nir16);
  EXPECT_EQ(m.format.udp_profile_imu, os::ImuProfile::kLegacy);
  EXPECT_EQ(m.format.pixels_per_column, 64u);
  EXPECT_EQ(m.format.columns_per_frame, 1024u);
  EXPECT_EQ(m.format.columns_per_packet, 16u);
  EXPECT_EQ(m.format.column_window, (os::ColumnWindow{0, 1023}));
  EXPECT_DOUBLE_EQ(m.lidar_origin_to_beam_origin_mm, 15.806);
  EXPECT_DOUBLE_EQ(m.T_lidar_beam_mm(0, 3), 15.806);
  // 180 degrees about z and 36.18 mm up; the IMU where the scenario's body frame is.
  Eigen::Matrix4d lidar_to_sensor = Eigen::Matrix4d::Identity();
  lidar_to_sensor(0, 0) = -1;
  lidar_to_sensor(1, 1) = -1;
  lidar_to_sensor(2, 3) = 36.18;
  EXPECT_EQ(m.T_sensor_lidar_mm, lidar_to_sensor);
  const Eigen::Matrix4d T_sensor_imu = m.T_sensor_imu_m();
  const Eigen::Matrix4d T_imu_sensor = run.mount().T_body_sensor.matrix();
  EXPECT_LT((T_sensor_imu * T_imu_sensor - Eigen::Matrix4d::Identity()).norm(), 1e-12);

  // Altitudes: +-22.5 deg, strictly decreasing, nearly uniform; azimuth staggers within +-4.5.
  const auto& alt = m.beam_altitude_angles_deg;
  ASSERT_EQ(alt.size(), 64u);
  EXPECT_NEAR(alt.front(), 22.5, 0.05);
  EXPECT_NEAR(alt.back(), -22.5, 0.05);
  for (std::size_t u = 1; u < alt.size(); ++u) {
    EXPECT_NEAR(alt[u - 1] - alt[u], 45.0 / 63.0, 0.1) << "row " << u;
  }
  for (const double az : m.beam_azimuth_angles_deg) EXPECT_LT(std::abs(az), 4.5);
}

TEST(OusterSim, PixelShiftFollowsTheAzimuthsAsInRealMetadata) {
  // The convention of real files: pixel_shift_by_row[u] = round(azimuth[u] * W / 360).
  const auto check = [](const os::SensorMetadata& m) {
    const double w = m.format.columns_per_frame;
    for (std::size_t u = 0; u < m.format.pixels_per_column; ++u) {
      EXPECT_EQ(m.format.pixel_shift_by_row[u],
                static_cast<int>(std::lround(m.beam_azimuth_angles_deg[u] * w / 360.0)))
          << "row " << u;
    }
  };
  check(os::load_metadata(test::data_path("ouster/metadata/2_5_0_os-992146000760-128.json")));
  const OusterSimRun run("street_vehicle_os1_128");
  auto lidar = run.make_lidar();
  const os::SensorMetadata m = write_and_load_metadata(*lidar, "ouster_sim_shift");
  ASSERT_EQ(m.format.pixels_per_column, 128u);
  check(m);
  // The four-column stagger of the OS1 detector, like the real 12, 4, -4, -12.
  EXPECT_EQ(std::vector<int>(m.format.pixel_shift_by_row.begin(),
                             m.format.pixel_shift_by_row.begin() + 4),
            (std::vector<int>{12, 4, -4, -12}));
}

TEST(OusterSim, MetadataHasTheNestedSectionsOfAFirmware25Sensor) {
  const OusterSimRun run("room_handheld_os1_64");
  auto lidar = run.make_lidar();
  const auto dir = test::temp_dir("ouster_sim_sections");
  const auto path = lidar->write_side_files(dir, "os1").at(0);
  std::ifstream in(path);
  const auto json = nlohmann::json::parse(in);
  const auto real = nlohmann::json::parse(
      std::ifstream(test::data_path("ouster/metadata/2_5_0_os-992146000760-128.json")));
  // Every section and key the real file has, except what only exists on real hardware.
  for (const auto& [section, value] : real.items()) {
    ASSERT_TRUE(json.contains(section)) << section;
    if (!value.is_object()) continue;
    for (const auto& [key, unused] : value.items()) {
      EXPECT_TRUE(json[section].contains(key)) << section << "/" << key;
    }
  }
}

TEST(OusterSim, PacketsCarryTheSensorIdentityAndConsecutiveStamps) {
  const OusterSimRun run("room_handheld_os1_64");
  auto lidar = run.make_lidar();
  const os::SensorMetadata m = write_and_load_metadata(*lidar, "ouster_sim_packets");
  const auto format = os::PacketFormat::from_metadata(m);
  const Capture capture = run.simulate(*lidar, 41, 2);  // frame ids 65535 and 0
  std::vector<std::uint32_t> frame_ids;
  std::vector<std::uint64_t> imu_sys_ts;
  std::int64_t previous_column_ts = -1;
  for (const auto& d : capture.datagrams) {
    if (d.dst_port == 7503) {
      EXPECT_EQ(d.src_port, 7503);
      os::ImuPacket imu;
      ASSERT_EQ(os::parse_imu_packet(d.payload, format, imu), os::PacketError::kNone);
      const auto& s = imu.measurements[0];
      EXPECT_EQ(s.accel_timestamp_ns - s.sys_timestamp_ns, 213'920u);
      EXPECT_EQ(s.timestamp_ns - s.sys_timestamp_ns, 435'300u);
      imu_sys_ts.push_back(s.sys_timestamp_ns);
      continue;
    }
    ASSERT_EQ(d.dst_port, 7502);
    EXPECT_EQ(d.src_port, 7502);
    ASSERT_EQ(d.payload.size(), 12'544u);  // 32 + 16 * (12 + 64 * 12) + 32
    os::LidarPacket p;
    ASSERT_EQ(os::LidarPacket::parse(d.payload, format, p), os::PacketError::kNone);
    EXPECT_EQ(p.header().packet_type, 1);
    EXPECT_EQ(p.header().init_id, *m.initialization_id);
    EXPECT_EQ(p.header().prod_sn, *m.prod_sn_number);
    if (frame_ids.empty() || frame_ids.back() != p.header().frame_id) {
      frame_ids.push_back(p.header().frame_id);
    }
    for (std::uint32_t c = 0; c < p.columns(); ++c) {
      EXPECT_TRUE(p.column_valid(c));
      const auto ts = static_cast<std::int64_t>(p.column_timestamp_ns(c));
      if (previous_column_ts >= 0) {
        EXPECT_NEAR(static_cast<double>(ts - previous_column_ts), kColumnPeriodNs, 1.0);
      }
      previous_column_ts = ts;
      for (std::uint32_t u = 0; u < format.pixels_per_column; ++u) {
        if (p.field(c, u, os::ChannelField::kRange) == 0) continue;
        EXPECT_GT(p.field(c, u, os::ChannelField::kSignal), 0u);
        EXPECT_GT(p.field(c, u, os::ChannelField::kNearIr), 0u);
      }
    }
  }
  EXPECT_EQ(frame_ids, (std::vector<std::uint32_t>{65535, 0}));
  // 100 Hz IMU, sys_ts exactly every 10 ms on the sensor clock (like a real OS1).
  ASSERT_EQ(imu_sys_ts.size(), 20u);
  for (std::size_t i = 1; i < imu_sys_ts.size(); ++i) {
    EXPECT_NEAR(static_cast<double>(imu_sys_ts[i] - imu_sys_ts[i - 1]), 1e7, 1.0);
  }
}

TEST(OusterSim, ChunkedRunFromZeroWritesTheSameWholeFrames) {
  // The runner simulates [0, duration) in chunks; where they fall must not change the output, and
  // a duration of whole frames gives whole frames (a packet goes with the chunk that sends it).
  const OusterSimRun run("room_handheld_os1_64");
  auto whole = run.make_lidar();
  auto chunked = run.make_lidar();
  Capture a;
  Capture b;
  SimOutputs out_a;
  out_a.on_datagram = [&](SimDatagram&& d) { a.datagrams.push_back(std::move(d)); };
  SimOutputs out_b;
  out_b.on_datagram = [&](SimDatagram&& d) { b.datagrams.push_back(std::move(d)); };
  whole->run(0.0, 0.3, run.scene(), out_a);
  chunked->run(0.0, 0.1234, run.scene(), out_b);
  chunked->run(0.1234, 0.3, run.scene(), out_b);
  const auto by_time = [](const SimDatagram& x, const SimDatagram& y) {
    return x.host_time_ns < y.host_time_ns;
  };
  std::stable_sort(a.datagrams.begin(), a.datagrams.end(), by_time);
  std::stable_sort(b.datagrams.begin(), b.datagrams.end(), by_time);
  ASSERT_EQ(a.datagrams.size(), b.datagrams.size());
  for (std::size_t i = 0; i < a.datagrams.size(); ++i) {
    ASSERT_EQ(a.datagrams[i].host_time_ns, b.datagrams[i].host_time_ns) << i;
    ASSERT_EQ(a.datagrams[i].dst_port, b.datagrams[i].dst_port) << i;
    ASSERT_TRUE(a.datagrams[i].payload == b.datagrams[i].payload) << i;
  }
  os::OusterDecoder decoder(write_and_load_metadata(*chunked, "ouster_sim_chunked"));
  const Decoded decoded = decode(decoder, b);
  EXPECT_EQ(decoder.counters().scans, 3u);
  EXPECT_EQ(decoder.counters().lidar_packets, 3u * 64u);
  EXPECT_EQ(decoder.counters().imu_packets, 30u);
  EXPECT_EQ(decoder.counters().incomplete_scans, 0u);
  EXPECT_EQ(decoder.counters().sequence_gaps, 0u);
  EXPECT_EQ(decoder.counters().decode_errors, 0u);
}

}  // namespace
}  // namespace livod::sim
