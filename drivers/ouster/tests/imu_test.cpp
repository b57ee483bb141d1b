// IMU packets to SI: LEGACY (g, deg/s) from a FW 2.0 capture and ACCEL32_GYRO32_NMEA (FW 3.2).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <numbers>

#include "drivers/ouster/imu_packet.hpp"
#include "drivers/ouster/lidar_packet.hpp"
#include "drivers/ouster/ouster_decoder.hpp"
#include "drivers/ouster/tests/ouster_test_util.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::ouster {
namespace {

float raw_float(const std::vector<std::byte>& b, std::size_t offset) {
  float f = 0;
  std::memcpy(&f, b.data() + offset, 4);
  return f;
}

TEST(OusterImu, LegacyPacketsConvertToSi) {
  // OS-1-64 FW 2.0: 64 lidar packets and 11 LEGACY IMU packets at 100 Hz, sensor at rest. The
  // configuration recorded with it has beam angles and lidar_mode only (LEGACY defaults).
  const SensorMetadata meta =
      load_metadata(test::data_path("ouster/pcaps/OS-1-64_sensor_config_reduced.json"));
  const PacketFormat format = PacketFormat::from_metadata(meta);
  const auto packets =
      testutil::read_capture(test::data_path("ouster/pcaps/OS-1-64_1024x10_fw20.pcap"));
  std::vector<ImuMeasurement> samples;
  std::uint64_t lidar_min = ~0ULL, lidar_max = 0;
  for (const auto& p : packets) {
    if (classify_packet(p.payload, format) == PacketKind::kLidar) {
      LidarPacket lp;
      ASSERT_EQ(LidarPacket::parse(p.payload, format, lp), PacketError::kNone);
      for (std::uint32_t c = 0; c < lp.columns(); ++c) {
        lidar_min = std::min(lidar_min, lp.column_timestamp_ns(c));
        lidar_max = std::max(lidar_max, lp.column_timestamp_ns(c));
      }
      continue;
    }
    ImuPacket ip;
    ASSERT_EQ(parse_imu_packet(p.payload, format, ip), PacketError::kNone);
    ASSERT_EQ(ip.count, 1U);
    const ImuMeasurement& m = ip.measurements[0];
    EXPECT_TRUE(m.valid);
    // Exact unit conversion of the wire floats (accel at byte 24, gyro at byte 36).
    for (int k = 0; k < 3; ++k) {
      EXPECT_DOUBLE_EQ(m.accel_m_s2[k], raw_float(p.payload, 24 + 4 * k) * 9.80665);
      EXPECT_DOUBLE_EQ(m.gyro_rad_s[k],
                       raw_float(p.payload, 36 + 4 * k) * std::numbers::pi / 180.0);
    }
    samples.push_back(m);
  }
  ASSERT_EQ(samples.size(), 11U);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_NEAR(samples[i].accel_m_s2.norm(), 9.81, 0.3);  // at rest: gravity only
    EXPECT_LT(samples[i].gyro_rad_s.norm(), 0.05);
    EXPECT_GT(samples[i].accel_m_s2.z(), 9.0);  // z up
    // gyro_ts runs on the lidar clock: inside the span of the column timestamps (+- 20 ms).
    EXPECT_GT(samples[i].timestamp_ns + 20'000'000, lidar_min);
    EXPECT_LT(samples[i].timestamp_ns, lidar_max + 20'000'000);
    EXPECT_NEAR(static_cast<double>(samples[i].accel_timestamp_ns),
                static_cast<double>(samples[i].timestamp_ns), 1e6);
    if (i > 0) {
      const double dt = static_cast<double>(samples[i].timestamp_ns - samples[i - 1].timestamp_ns);
      EXPECT_NEAR(dt, 10e6, 0.5e6);  // 100 Hz
    }
  }
}

TEST(OusterImu, Accel32Gyro32NmeaPackets) {
  const SensorMetadata meta = load_metadata(test::data_path("ouster/pcaps/imu_zm_no_lidar_0.json"));
  const PacketFormat format = PacketFormat::from_metadata(meta);
  ASSERT_EQ(format.imu_packet_size, 452U);
  const auto packets = testutil::read_capture(test::data_path("ouster/pcaps/imu_zm_no_lidar.pcap"));
  std::vector<ImuMeasurement> samples;
  for (const auto& p : packets) {
    if (classify_packet(p.payload, format) != PacketKind::kImu) continue;
    ImuPacket ip;
    ASSERT_EQ(parse_imu_packet(p.payload, format, ip), PacketError::kNone);
    EXPECT_EQ(ip.header.packet_type, 2);
    EXPECT_EQ(ip.header.init_id, *meta.initialization_id);
    EXPECT_EQ(ip.header.prod_sn, *meta.prod_sn_number);
    ASSERT_EQ(ip.count, 8U);
    for (std::size_t i = 0; i < ip.count; ++i) samples.push_back(ip.measurements[i]);
  }
  ASSERT_EQ(samples.size(), 64U);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_TRUE(samples[i].valid);
    EXPECT_NEAR(samples[i].accel_m_s2.norm(), 9.85, 0.3);  // m/s^2 on the wire already
    EXPECT_LT(samples[i].gyro_rad_s.norm(), 0.05);
    if (i > 0) {
      EXPECT_GT(samples[i].timestamp_ns, samples[i - 1].timestamp_ns);
    }
  }
  // 8 packets x 8 samples per 10 Hz frame: 640 Hz, 1.5625 ms apart.
  const double mean_dt =
      static_cast<double>(samples.back().timestamp_ns - samples.front().timestamp_ns) /
      static_cast<double>(samples.size() - 1);
  EXPECT_NEAR(mean_dt, 1e9 / 640.0, 0.01 * 1e9 / 640.0);

  // The decoder emits them as ImuSamples and counts the zone packet as auxiliary.
  OusterDecoder decoder(meta);
  std::vector<ImuSample> emitted;
  DecoderSinks sinks;
  sinks.on_imu = [&](const ImuSample& s) { emitted.push_back(s); };
  for (const auto& p : packets) decoder.on_packet(p.view(), sinks);
  decoder.flush(sinks);
  EXPECT_EQ(decoder.counters().imu_packets, 8U);
  EXPECT_EQ(decoder.counters().aux_packets, 1U);
  EXPECT_EQ(decoder.ouster_counters().zone_packets, 1U);
  EXPECT_EQ(decoder.counters().decode_errors, 0U);
  EXPECT_EQ(decoder.counters().scans, 0U);
  ASSERT_EQ(emitted.size(), 64U);
  EXPECT_EQ(emitted[3].stamp.sensor.ns, static_cast<std::int64_t>(samples[3].timestamp_ns));
  EXPECT_EQ(emitted[3].accel_m_s2, samples[3].accel_m_s2);
  EXPECT_EQ(emitted[0].stamp.host.ns, packets[0].time_ns);
  EXPECT_EQ(decoder.default_ports(), (std::vector<std::uint16_t>{7513}));  // lidar port 0 = off
}

TEST(OusterImu, MalformedImuPacketsAreRejected) {
  const SensorMetadata meta = load_metadata(test::data_path("ouster/pcaps/imu_zm_no_lidar_0.json"));
  const PacketFormat format = PacketFormat::from_metadata(meta);
  const auto packets = testutil::read_capture(test::data_path("ouster/pcaps/imu_zm_no_lidar.pcap"));
  const std::vector<std::byte>& good = packets.front().payload;
  ImuPacket ip;
  for (std::size_t n = 0; n < good.size(); n += 13) {
    EXPECT_EQ(parse_imu_packet(std::span(good).first(n), format, ip), PacketError::kWrongSize);
  }
  std::vector<std::byte> bad = good;
  bad[200] ^= std::byte{4};
  EXPECT_EQ(parse_imu_packet(bad, format, ip), PacketError::kCrcMismatch);
  // With n unknown, any whole number of measurements is accepted, a partial one is not.
  SensorMetadata unknown_n = meta;
  unknown_n.format.imu_measurements_per_packet = 0;
  const PacketFormat loose = PacketFormat::from_metadata(unknown_n);
  EXPECT_EQ(parse_imu_packet(good, loose, ip), PacketError::kNone);
  EXPECT_EQ(ip.count, 8U);
  EXPECT_EQ(parse_imu_packet(std::span(good).first(good.size() - 1), loose, ip),
            PacketError::kWrongSize);
  // LEGACY: exactly 48 bytes.
  const SensorMetadata legacy = load_metadata(test::data_path("ouster/pcaps/crc_test.json"));
  const PacketFormat lf = PacketFormat::from_metadata(legacy);
  std::vector<std::byte> imu48(48, std::byte{0});
  EXPECT_EQ(parse_imu_packet(imu48, lf, ip), PacketError::kNone);
  EXPECT_EQ(parse_imu_packet(std::span(imu48).first(47), lf, ip), PacketError::kWrongSize);
}

}  // namespace
}  // namespace livod::drivers::ouster
