// Lidar packet headers, CRC-64 footers and length/consistency checks on real packets.

#include <gtest/gtest.h>

#include <cstring>
#include <string_view>

#include "drivers/ouster/crc64.hpp"
#include "drivers/ouster/imu_packet.hpp"
#include "drivers/ouster/lidar_packet.hpp"
#include "drivers/ouster/ouster_decoder.hpp"
#include "drivers/ouster/tests/ouster_test_util.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::ouster {
namespace {

using testutil::CapturedPacket;
using testutil::read_capture;

struct Capture {
  SensorMetadata meta;
  PacketFormat format;
  std::vector<CapturedPacket> packets;
};

Capture load(const std::string& pcap, const std::string& json) {
  Capture c;
  c.meta = load_metadata(test::data_path("ouster/pcaps/" + json));
  c.format = PacketFormat::from_metadata(c.meta);
  c.packets = read_capture(test::data_path("ouster/pcaps/" + pcap));
  return c;
}

std::span<const std::byte> bytes_of(std::string_view s) {
  return {reinterpret_cast<const std::byte*>(s.data()), s.size()};
}

TEST(OusterCrc64, StandardCheckValue) {
  EXPECT_EQ(crc64_xz(bytes_of("123456789")), 0x995DC9BBDF1939FAULL);
  EXPECT_EQ(crc64_xz({}), 0ULL);
  // The 8-byte-at-a-time path must agree with a plain bitwise CRC for every length and alignment.
  std::vector<std::byte> data(300);
  for (std::size_t i = 0; i < data.size(); ++i)
    data[i] = static_cast<std::byte>((i * 131 + 7) & 0xFF);
  for (std::size_t start = 0; start < 9; ++start) {
    for (std::size_t len = 0; len + start <= 64; ++len) {
      std::uint64_t crc = ~0ULL;
      for (std::size_t i = start; i < start + len; ++i) {
        crc ^= static_cast<std::uint8_t>(data[i]);
        for (int b = 0; b < 8; ++b) crc = (crc & 1) ? (crc >> 1) ^ 0xC96C5795D7870F42ULL : crc >> 1;
      }
      ASSERT_EQ(crc64_xz(std::span<const std::byte>(data).subspan(start, len)), ~crc)
          << start << " " << len;
    }
  }
}

TEST(OusterPackets, EveryPacketOfTheCrcCapturesValidates) {
  struct Case {
    const char* pcap;
    const char* json;
    std::size_t lidar, imu, zone;
  };
  for (const Case& k : {Case{"crc_test.pcap", "crc_test.json", 34, 10, 0},
                        Case{"shot_limiting_test.pcap", "shot_limiting_test.json", 1, 0, 0},
                        Case{"imu_zm_no_lidar.pcap", "imu_zm_no_lidar_0.json", 0, 8, 1}}) {
    SCOPED_TRACE(k.pcap);
    const Capture c = load(k.pcap, k.json);
    ASSERT_TRUE(c.format.lidar_crc);
    std::size_t lidar = 0, imu = 0, zone = 0;
    for (const auto& p : c.packets) {
      switch (classify_packet(p.payload, c.format)) {
        case PacketKind::kLidar: {
          LidarPacket lp;
          ASSERT_EQ(LidarPacket::parse(p.payload, c.format, lp), PacketError::kNone);
          EXPECT_TRUE(crc_matches(p.payload));
          ++lidar;
          break;
        }
        case PacketKind::kImu: {
          ImuPacket ip;
          ASSERT_EQ(parse_imu_packet(p.payload, c.format, ip), PacketError::kNone);
          if (c.format.imu_profile != ImuProfile::kLegacy) {
            EXPECT_TRUE(crc_matches(p.payload));
          }
          ++imu;
          break;
        }
        case PacketKind::kZone: {
          PacketHeader h;
          ASSERT_EQ(check_zone_packet(p.payload, c.format, h), PacketError::kNone);
          EXPECT_EQ(h.init_id, *c.meta.initialization_id);
          ++zone;
          break;
        }
        case PacketKind::kUnknown:
          ADD_FAILURE() << "unclassified packet of " << p.payload.size() << " bytes";
      }
    }
    EXPECT_EQ(lidar, k.lidar);
    EXPECT_EQ(imu, k.imu);
    EXPECT_EQ(zone, k.zone);
  }
}

TEST(OusterPackets, CorruptedBytesAreCaughtByTheCrc) {
  const Capture c = load("crc_test.pcap", "crc_test.json");
  std::vector<std::byte> packet;
  for (const auto& p : c.packets) {
    if (p.payload.size() == c.format.lidar_packet_size) {
      packet = p.payload;
      break;
    }
  }
  ASSERT_FALSE(packet.empty());
  // A flipped bit anywhere (header, a range, the footer, the CRC itself) is detected.
  for (std::size_t offset : {std::size_t{0}, std::size_t{5}, std::size_t{40}, packet.size() / 2,
                             packet.size() - 20, packet.size() - 1}) {
    SCOPED_TRACE(offset);
    std::vector<std::byte> bad = packet;
    bad[offset] ^= std::byte{0x10};
    LidarPacket lp;
    EXPECT_EQ(LidarPacket::parse(bad, c.format, lp), PacketError::kCrcMismatch);
  }
  // The decoder counts them and emits nothing from them.
  OusterDecoder decoder(c.meta);
  std::size_t scans = 0;
  DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan&) { ++scans; };
  std::size_t corrupted = 0;
  for (std::size_t i = 0; i < c.packets.size(); ++i) {
    std::vector<std::byte> bytes = c.packets[i].payload;
    if (bytes.size() == c.format.lidar_packet_size && i % 5 == 0) {
      bytes[100 + i] ^= std::byte{0x01};
      ++corrupted;
    }
    decoder.on_packet({bytes, c.packets[i].time_ns, c.packets[i].dst_port}, sinks);
  }
  decoder.flush(sinks);
  EXPECT_GT(corrupted, 3U);
  EXPECT_EQ(decoder.ouster_counters().crc_failures, corrupted);
  EXPECT_EQ(decoder.counters().decode_errors, corrupted);
  EXPECT_EQ(decoder.counters().lidar_packets, 34U - corrupted);
  // With CRC checking switched off the same corruption passes: the check is what catches it.
  OusterDecoderOptions no_crc;
  no_crc.crc = CrcPolicy::kNever;
  OusterDecoder unchecked(c.meta, no_crc);
  std::vector<std::byte> bad = packet;
  bad[200] ^= std::byte{0x01};
  unchecked.on_packet({bad, 0, 7502}, sinks);
  EXPECT_EQ(unchecked.ouster_counters().crc_failures, 0U);
  EXPECT_EQ(unchecked.counters().lidar_packets, 1U);
}

TEST(OusterPackets, FirmwareWithoutCrcIsNotChecked) {
  // FW 2.3 fills the footer with 0xDEADBEEF/0xC0DE: a CRC check would reject every packet.
  const Capture c = load("OS-2-128-U1_v2.3.0_1024x10.pcap", "OS-2-128-U1_v2.3.0_1024x10.json");
  EXPECT_FALSE(c.format.lidar_crc);
  std::size_t lidar = 0;
  for (const auto& p : c.packets) {
    LidarPacket lp;
    if (p.payload.size() != c.format.lidar_packet_size) continue;
    EXPECT_EQ(LidarPacket::parse(p.payload, c.format, lp), PacketError::kNone);
    EXPECT_FALSE(crc_matches(p.payload));
    ++lidar;
  }
  EXPECT_EQ(lidar, 64U);
  const PacketFormat strict = PacketFormat::from_metadata(c.meta, CrcPolicy::kAlways);
  LidarPacket lp;
  EXPECT_EQ(LidarPacket::parse(c.packets.front().payload, strict, lp), PacketError::kCrcMismatch);
}

TEST(OusterPackets, ShotLimitingHeader) {
  // sensor-protocols.md §9: cd_thermal 5, thermal 1, shot 1, alert 0x98.
  const Capture c = load("shot_limiting_test.pcap", "shot_limiting_test.json");
  ASSERT_EQ(c.packets.size(), 1U);
  LidarPacket lp;
  ASSERT_EQ(LidarPacket::parse(c.packets[0].payload, c.format, lp), PacketError::kNone);
  const PacketHeader& h = lp.header();
  EXPECT_EQ(h.packet_type, 1);
  EXPECT_EQ(h.countdown_thermal_shutdown, 5);
  EXPECT_EQ(h.thermal_shutdown, 1);
  EXPECT_EQ(h.shot_limiting, 1);
  EXPECT_EQ(h.countdown_shot_limiting, 0);
  EXPECT_EQ(h.alert_flags, 0x98);
  EXPECT_EQ(h.frame_id, 9496U);
  EXPECT_EQ(h.init_id, *c.meta.initialization_id);
  EXPECT_EQ(h.prod_sn, *c.meta.prod_sn_number);

  OusterDecoder decoder(c.meta);
  decoder.on_packet(c.packets[0].view(), {});
  EXPECT_EQ(decoder.ouster_counters().shot_limiting_packets, 1U);
  EXPECT_EQ(decoder.ouster_counters().thermal_shutdown_packets, 1U);
  EXPECT_EQ(decoder.sensor_status().shot_limiting, 1);
  EXPECT_EQ(decoder.sensor_status().thermal_shutdown, 1);
  EXPECT_EQ(decoder.sensor_status().countdown_thermal_shutdown, 5);
  EXPECT_EQ(decoder.sensor_status().alert_flags, 0x98);
}

TEST(OusterPackets, StandardAndFusaHeaders) {
  {
    // sensor-protocols.md §9: frame_id 1453, init_id 9599938, sn 992137000142.
    const Capture c =
        load("OS-0-32-U1_v2.2.0_1024x10-single-packet.pcap", "OS-0-32-U1_v2.2.0_1024x10.json");
    ASSERT_EQ(c.packets.size(), 1U);
    LidarPacket lp;
    ASSERT_EQ(LidarPacket::parse(c.packets[0].payload, c.format, lp), PacketError::kNone);
    EXPECT_EQ(lp.header().frame_id, 1453U);
    EXPECT_EQ(lp.header().init_id, 9599938U);
    EXPECT_EQ(lp.header().prod_sn, 992137000142ULL);
    EXPECT_EQ(lp.header().alert_flags, 0);
  }
  {
    // FUSA: 8-bit type, 24-bit init_id, 32-bit frame_id (values of ouster-sdk's test_fusa_fields).
    const Capture c = load("OS-1-128_767798045_1024x10_20230712_120049.pcap",
                           "OS-1-128_767798045_1024x10_20230712_120049.json");
    ASSERT_EQ(c.format.header_type, HeaderType::kFusa);
    ASSERT_EQ(c.format.lidar_packet_size, 16640U);
    std::size_t lidar = 0;
    for (const auto& p : c.packets) {
      if (classify_packet(p.payload, c.format) != PacketKind::kLidar) continue;
      LidarPacket lp;
      ASSERT_EQ(LidarPacket::parse(p.payload, c.format, lp), PacketError::kNone);
      EXPECT_EQ(lp.header().packet_type, 1);
      EXPECT_EQ(lp.header().frame_id, 229U);
      EXPECT_EQ(lp.header().init_id, *c.meta.initialization_id);
      EXPECT_EQ(lp.header().prod_sn, *c.meta.prod_sn_number);
      if (lidar == 0) {
        EXPECT_EQ(lp.column_timestamp_ns(0), 647839983424ULL);
      }
      ++lidar;
    }
    EXPECT_EQ(lidar, 8U);
  }
}

TEST(OusterPackets, LengthsAndMeasurementIdsAreChecked) {
  const Capture c = load("OS-2-128-U1_v2.3.0_1024x10.pcap", "OS-2-128-U1_v2.3.0_1024x10.json");
  const std::vector<std::byte>& good = c.packets.front().payload;
  ASSERT_EQ(good.size(), c.format.lidar_packet_size);
  LidarPacket lp;
  for (std::size_t n = 0; n < good.size(); n += 97) {
    EXPECT_EQ(LidarPacket::parse(std::span(good).first(n), c.format, lp), PacketError::kWrongSize);
  }
  EXPECT_EQ(LidarPacket::parse(std::span(good).first(good.size() - 1), c.format, lp),
            PacketError::kWrongSize);
  std::vector<std::byte> longer = good;
  longer.push_back(std::byte{0});
  EXPECT_EQ(LidarPacket::parse(longer, c.format, lp), PacketError::kWrongSize);

  std::vector<std::byte> bad = good;
  bad[0] = std::byte{2};  // packet_type IMU
  EXPECT_EQ(LidarPacket::parse(bad, c.format, lp), PacketError::kWrongPacketType);

  const auto set_mid = [&](std::vector<std::byte>& b, std::uint32_t col, std::uint16_t mid) {
    std::memcpy(b.data() + c.format.packet_header_size + col * c.format.column_size + 8, &mid, 2);
  };
  bad = good;
  set_mid(bad, 0, 1024);  // beyond columns_per_frame
  EXPECT_EQ(LidarPacket::parse(bad, c.format, lp), PacketError::kMeasurementIdOutOfRange);
  bad = good;
  set_mid(bad, 0, 1016);  // the packet would run past the last column
  EXPECT_EQ(LidarPacket::parse(bad, c.format, lp), PacketError::kMeasurementIdOutOfRange);
  bad = good;
  set_mid(bad, 7, 900);  // a column from elsewhere: spliced datagram
  EXPECT_EQ(LidarPacket::parse(bad, c.format, lp), PacketError::kInconsistentMeasurementIds);

  // Every rejection above reaches the decoder's counters, never a crash.
  OusterDecoder decoder(c.meta);
  decoder.on_packet({std::span(good).first(100), 0, 7502}, {});
  decoder.on_packet({bad, 0, 7502}, {});
  decoder.on_packet({std::span<const std::byte>(), 0, 7502}, {});
  EXPECT_EQ(decoder.counters().decode_errors, 3U);
  EXPECT_EQ(decoder.ouster_counters().bad_measurement_ids, 1U);
  EXPECT_EQ(decoder.ouster_counters().wrong_size, 2U);
}

TEST(OusterPackets, SamePortClassificationUsesTypeAndSize) {
  // same_ports_nonlegacy: two sensors on port 7502, each sending 16640-byte lidar packets (an
  // RNG19 dual 64-beam sensor and a FUSA 128-beam one) and 48-byte LEGACY IMU packets.
  const auto packets = read_capture(test::data_path("ouster/pcaps/same_ports_nonlegacy.pcap"));
  const SensorMetadata dual64 =
      load_metadata(test::data_path("ouster/pcaps/same_ports_nonlegacy.2.json"));
  const SensorMetadata fusa128 =
      load_metadata(test::data_path("ouster/pcaps/same_ports_nonlegacy.1.json"));
  const PacketFormat f_dual = PacketFormat::from_metadata(dual64);
  const PacketFormat f_fusa = PacketFormat::from_metadata(fusa128);
  ASSERT_EQ(f_dual.lidar_packet_size, f_fusa.lidar_packet_size);  // the §3.1 gotcha
  std::size_t imu = 0;
  for (const auto& p : packets) {
    if (p.payload.size() == 48) {
      EXPECT_EQ(classify_packet(p.payload, f_dual), PacketKind::kImu);
      EXPECT_EQ(classify_packet(p.payload, f_fusa), PacketKind::kImu);
      ++imu;
    }
  }
  EXPECT_EQ(imu, 2U);
  // All packets through one decoder: the other sensor's lidar packet has the right size but is
  // recognised as foreign (by its header), never decoded with the wrong layout.
  for (const auto* meta : {&dual64, &fusa128}) {
    OusterDecoder decoder(*meta);
    for (const auto& p : packets) decoder.on_packet(p.view(), {});
    EXPECT_EQ(decoder.counters().lidar_packets, 1U);
    EXPECT_EQ(decoder.counters().imu_packets, 2U);  // LEGACY IMU packets carry no sensor id
    EXPECT_EQ(decoder.counters().decode_errors, 1U);
  }
}

}  // namespace
}  // namespace livod::drivers::ouster
