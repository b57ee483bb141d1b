// Position packets of the real HDL-32E capture (monterey): PPS status, $GPRMC time, the three
// gyro/temperature/accelerometer sensors; the decoder's IMU samples and GPS time anchor.

#include "drivers/velodyne/position_packet.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "drivers/velodyne/tests/capture.hpp"
#include "drivers/velodyne/top_of_hour.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"
#include "io/pcap.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::velodyne {
namespace {

constexpr double kG = 9.80665;
const char* const kMonterey = "velodyne/veloview/monterey-first-100-packets.pcap";

TEST(PositionPacket, MontereyPacketsCarryGpsTimeAndPlausibleMotionSensors) {
  io::PcapReader reader(livod::test::data_path(kMonterey));
  std::size_t count = 0;
  while (auto datagram = reader.next()) {
    if (datagram->payload.size() != 512) continue;
    ++count;
    const auto r = decode_position_packet(datagram->payload);
    ASSERT_EQ(r.status, PositionDecodeStatus::kOk);
    const PositionPacket& p = r.packet;
    // Firmware of 2012: no PPS input (status 0 = absent), NMEA from the GPS receiver.
    ASSERT_TRUE(p.pps);
    EXPECT_EQ(*p.pps, PpsStatus::kAbsent);
    ASSERT_TRUE(p.rmc) << p.nmea;
    EXPECT_TRUE(p.rmc->valid);
    EXPECT_EQ(p.nmea.substr(0, 7), "$GPRMC,");
    EXPECT_NEAR(*p.rmc->latitude_deg, 37.0 + 7.8324 / 60.0, 1e-9);  // Monterey Bay area
    EXPECT_NEAR(*p.rmc->longitude_deg, -(121.0 + 39.2864 / 60.0), 1e-9);
    // Absolute time: the GPRMC date and hour with the packet's microseconds (§4.6 rule). The
    // sentence is whole seconds, the capture's record time is the host clock: within 2 s.
    const std::int64_t absolute_ns = resolve_top_of_hour(p.toh_us, p.rmc->utc_ns);
    EXPECT_NEAR(static_cast<double>(absolute_ns - datagram->capture_time_ns), 0.0, 2e9);
    EXPECT_LE(p.rmc->utc_ns, absolute_ns);
    EXPECT_LT(absolute_ns - p.rmc->utc_ns, 2'000'000'000);
    for (const auto& m : p.motion) {
      EXPECT_GT(m.temperature_c, 20.0);  // a running sensor on a December evening
      EXPECT_LT(m.temperature_c, 60.0);
      EXPECT_LT(std::abs(m.gyro_deg_s), 200.0);
    }
    const ImuVectors imu = hdl32e_imu_in_lidar_frame(p);
    const double g = imu.accel_m_s2.norm() / kG;
    EXPECT_GT(g, 0.85);
    EXPECT_LT(g, 1.10);
    EXPECT_GT(imu.accel_m_s2.z(), 0.9 * g * kG);  // upright: gravity along +z
  }
  EXPECT_EQ(count, 299U);
}

TEST(PositionPacket, DecoderEmitsImuSamplesOnTheScanTimeline) {
  VelodyneOptions options;
  options.model = Model::kHdl32e;
  VelodyneDecoder decoder(options);
  const auto decoded = capture::decode_capture(livod::test::data_path(kMonterey), decoder);
  EXPECT_EQ(decoder.counters().imu_packets, 299U);
  EXPECT_EQ(decoder.velodyne_counters().position_packets, 299U);
  EXPECT_EQ(decoder.velodyne_counters().gps_fixes, 299U);
  EXPECT_EQ(decoder.velodyne_counters().time_rebases, 0U);  // the capture's host clock is UTC
  ASSERT_TRUE(decoder.last_pps());
  EXPECT_EQ(*decoder.last_pps(), PpsStatus::kAbsent);
  ASSERT_EQ(decoded.imu.size(), 299U);
  for (std::size_t i = 1; i < decoded.imu.size(); ++i) {
    const auto dt = decoded.imu[i].stamp.sensor - decoded.imu[i - 1].stamp.sensor;
    EXPECT_GT(dt.count(), 0);
    EXPECT_LT(dt.count(), 20'000'000);
  }
  // IMU and scans share the sensor clock: the IMU samples cover the scans' time span.
  const auto& first_scan = decoded.scans.front();
  const auto& last_scan = decoded.scans.back();
  EXPECT_LT(decoded.imu.front().stamp.sensor.ns - first_scan.start.sensor.ns, 20'000'000);
  EXPECT_LT(
      last_scan.start.sensor.ns + last_scan.t_offset_ns.back() - decoded.imu.back().stamp.sensor.ns,
      20'000'000);
  for (const auto& s : decoded.imu) {
    EXPECT_NEAR(s.accel_m_s2.norm(), kG, 0.15 * kG);
    EXPECT_EQ(s.stamp.mapped.ns, s.stamp.host.ns);  // placeholder until the clock domain
  }
}

TEST(PositionPacket, GpsFixReanchorsAHostClockThatIsHoursOff) {
  // Replay with receive times three hours late (a host clock that is not UTC): the first scans
  // get the wrong hour from the §4.6 rule, the first GPS fix moves the timeline back.
  VelodyneOptions options;
  options.model = Model::kHdl32e;
  VelodyneDecoder decoder(options);
  constexpr std::int64_t kOffsetNs = 3 * kHourNs;
  std::vector<std::int64_t> true_times;
  const auto decoded = capture::decode_capture(livod::test::data_path(kMonterey), decoder,
                                               [](std::vector<std::byte>&, io::UdpDatagram& d) {
                                                 d.capture_time_ns += kOffsetNs;
                                                 return true;
                                               });
  EXPECT_EQ(decoder.velodyne_counters().time_rebases, 1U);
  constexpr std::int64_t kCaptureStartNs = 1'355'263'594'123'168'000;
  ASSERT_FALSE(decoded.scans.empty());
  // Every scan, including the one in progress when the fix arrived, is on UTC.
  for (const auto& scan : decoded.scans) {
    // The capture lasts 1.5 s; the sensor clock runs ~0.9 s behind the capture host's.
    EXPECT_NEAR(static_cast<double>(scan.start.sensor.ns - kCaptureStartNs), 0.0, 1.5e9);
    EXPECT_NEAR(static_cast<double>(scan.start.host.ns - scan.start.sensor.ns), 3.0 * 3600e9, 2e9);
  }
}

TEST(PositionPacket, RejectsWrongSizesAndImpossibleTimestamps) {
  std::vector<std::byte> packet(512, std::byte{0});
  EXPECT_EQ(decode_position_packet(packet).status, PositionDecodeStatus::kOk);
  EXPECT_FALSE(decode_position_packet(packet).packet.rmc);
  packet[198] = std::byte{0xFF};
  packet[199] = std::byte{0xFF};
  packet[200] = std::byte{0xFF};
  packet[201] = std::byte{0xFF};  // 4294 s > one hour
  EXPECT_EQ(decode_position_packet(packet).status, PositionDecodeStatus::kBadTimestamp);
  EXPECT_EQ(decode_position_packet(std::span(packet).first(511)).status,
            PositionDecodeStatus::kBadLength);
  // A sentence without a terminating NUL runs to the end of the packet and is not an RMC.
  std::vector<std::byte> full(512, std::byte{'A'});
  full[198] = full[199] = full[200] = full[201] = std::byte{0};
  const auto r = decode_position_packet(full);
  EXPECT_EQ(r.status, PositionDecodeStatus::kOk);
  EXPECT_EQ(r.packet.nmea.size(), 512U - 206U);
  EXPECT_FALSE(r.packet.rmc);
  EXPECT_FALSE(r.packet.pps);  // byte 202 = 'A' is not a PPS status
}

}  // namespace
}  // namespace livod::drivers::velodyne
