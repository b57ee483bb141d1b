// Livox data packets built byte by byte from the documented layouts (sensor-protocols.md 1.3,
// 2.3) rather than with livod's encoder, then decoded; plus encoder round trips.

#include "drivers/livox/packets.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "drivers/livox/crc.hpp"

namespace livod::livox {
namespace {

class Bytes {
 public:
  template <class T>
  Bytes& put(T v) {
    const auto* p = reinterpret_cast<const std::byte*>(&v);
    data.insert(data.end(), p, p + sizeof(T));
    return *this;
  }
  Bytes& u8(int v) { return put(static_cast<std::uint8_t>(v)); }
  std::vector<std::byte> data;
};

Bytes sdk1_header(int data_type, int ts_type, std::uint64_t ts) {
  Bytes b;
  b.u8(5).u8(1).u8(1).u8(0).put<std::uint32_t>(0x01000000).u8(ts_type).u8(data_type).put(ts);
  return b;
}

TEST(LivoxSdk1Packet, ExtendedCartesianWithTimingAndLines) {
  Bytes b = sdk1_header(2, 0, 1'000'000'000ULL);
  for (int i = 0; i < 96; ++i) {
    b.put<std::int32_t>(1000 + i).put<std::int32_t>(-2000).put<std::int32_t>(i == 5 ? 0 : 300);
    b.u8(i).u8(0x10);
  }
  // Make point 7 a no-return: x = y = z = 0.
  std::memset(b.data.data() + 18 + 7 * 14, 0, 12);
  ASSERT_EQ(b.data.size(), 1362u);
  LivoxPacket pkt;
  ASSERT_EQ(decode_sdk1(b.data, 4167, 6, pkt), DecodeError::kNone);
  EXPECT_EQ(pkt.kind, LivoxPacket::Kind::kPoints);
  EXPECT_EQ(pkt.count, 96);
  EXPECT_EQ(pkt.timestamp_ns, 1'000'000'000);
  EXPECT_EQ(pkt.status, 0x01000000u);
  EXPECT_FLOAT_EQ(pkt.points[3].x, 1.003F);
  EXPECT_FLOAT_EQ(pkt.points[3].y, -2.0F);
  EXPECT_FLOAT_EQ(pkt.points[3].z, 0.3F);
  EXPECT_EQ(pkt.points[3].reflectivity, 3);
  EXPECT_EQ(pkt.points[3].tag, 0x10);
  EXPECT_EQ(pkt.points[95].t_offset_ns, 95 * 4167);
  EXPECT_EQ(pkt.points[13].line, 13 % 6);
  EXPECT_TRUE(pkt.points[5].valid);  // z = 0 alone is a valid point
  EXPECT_FALSE(pkt.points[7].valid);
  EXPECT_EQ(pkt.span_ns, 95 * 4167);
}

TEST(LivoxSdk1Packet, DualSphericalSharesAnglesAndFiringTime) {
  Bytes b = sdk1_header(5, 1, 42);
  for (int f = 0; f < 48; ++f) {
    b.put<std::uint16_t>(9000).put<std::uint16_t>(
        static_cast<std::uint16_t>(100 * f));     // theta 90 deg
    b.put<std::uint32_t>(10000).u8(50).u8(0x00);  // 10 m
    b.put<std::uint32_t>(12000).u8(20).u8(0x10);  // 12 m
  }
  LivoxPacket pkt;
  ASSERT_EQ(decode_sdk1(b.data, 4167, 6, pkt), DecodeError::kNone);
  ASSERT_EQ(pkt.count, 96);
  const auto& first = pkt.points[2 * 9];
  const auto& second = pkt.points[2 * 9 + 1];
  const double phi = 9.0 * M_PI / 180.0;
  EXPECT_NEAR(first.x, 10.0 * std::cos(phi), 1e-5);
  EXPECT_NEAR(first.y, 10.0 * std::sin(phi), 1e-5);
  EXPECT_NEAR(first.z, 0.0, 1e-5);
  EXPECT_NEAR(second.x, 12.0 * std::cos(phi), 1e-5);
  EXPECT_EQ(first.t_offset_ns, second.t_offset_ns);
  EXPECT_EQ(first.t_offset_ns, 9 * 4167);
  EXPECT_EQ(first.return_index, 0);
  EXPECT_EQ(second.return_index, 1);
}

TEST(LivoxSdk1Packet, UtcTimestampAndImuInG) {
  Bytes b;
  b.u8(5).u8(1).u8(1).u8(0).put<std::uint32_t>(0).u8(3).u8(6);
  b.u8(24).u8(3).u8(15).u8(10).put<std::uint32_t>(1'500'000'000U);  // 2024-03-15 10:25:00
  b.put<float>(0.1F).put<float>(-0.2F).put<float>(0.3F);
  b.put<float>(0.0F).put<float>(0.0F).put<float>(1.0F);
  ASSERT_EQ(b.data.size(), 42u);
  LivoxPacket pkt;
  ASSERT_EQ(decode_sdk1(b.data, 4167, 6, pkt), DecodeError::kNone);
  EXPECT_EQ(pkt.kind, LivoxPacket::Kind::kImu);
  // 2024-03-15T10:00:00Z = 1710496800 s, plus 1500 s.
  EXPECT_EQ(pkt.timestamp_ns, (1710496800LL + 1500) * 1'000'000'000LL);
  EXPECT_NEAR(pkt.accel_m_s2.z(), 9.80665, 1e-6);
  EXPECT_NEAR(pkt.gyro_rad_s.y(), -0.2, 1e-7);
  b.data[11] = std::byte{13};  // month 13
  EXPECT_EQ(decode_sdk1(b.data, 4167, 6, pkt), DecodeError::kBadTime);
}

TEST(LivoxSdk1Packet, RejectsShortAndUnknownPackets) {
  Bytes b = sdk1_header(2, 0, 0);
  LivoxPacket pkt;
  EXPECT_EQ(decode_sdk1(b.data, 4167, 6, pkt), DecodeError::kTooShort);
  b.data.resize(18 + 96 * 14 - 1);
  EXPECT_EQ(decode_sdk1(b.data, 4167, 6, pkt), DecodeError::kTooShort);
  b.data[9] = std::byte{42};
  EXPECT_EQ(decode_sdk1(b.data, 4167, 6, pkt), DecodeError::kUnknownDataType);
  EXPECT_EQ(decode_sdk1(std::span(b.data).first(5), 4167, 6, pkt), DecodeError::kTooShort);
}

// Issue 13, defect 1: a datagram that is not SDK1 (another sensor's traffic on the port) must
// not decode into points. The constructed datagram is an extended-cartesian packet whose version
// byte is 0xFF and which carries 100 trailing bytes: both disqualify it on their own.
TEST(LivoxSdk1Packet, RejectsForeignVersionAndWrongLength) {
  auto points_packet = [](int version, std::size_t trailing) {
    Bytes b = sdk1_header(2, 0, 1'000'000'000ULL);
    b.data[0] = static_cast<std::byte>(version);
    for (int i = 0; i < 96; ++i)
      b.put<std::int32_t>(1000).put<std::int32_t>(0).put<std::int32_t>(0).u8(1).u8(0);
    b.data.insert(b.data.end(), trailing, std::byte{0x11});
    return b.data;
  };
  LivoxPacket pkt;
  ASSERT_EQ(decode_sdk1(points_packet(5, 0), 4167, 6, pkt), DecodeError::kNone);
  EXPECT_EQ(decode_sdk1(points_packet(0xFF, 100), 4167, 6, pkt), DecodeError::kBadVersion);
  EXPECT_EQ(decode_sdk1(points_packet(0xFF, 0), 4167, 6, pkt), DecodeError::kBadVersion);
  EXPECT_EQ(decode_sdk1(points_packet(5, 100), 4167, 6, pkt), DecodeError::kLengthMismatch);
  EXPECT_EQ(decode_sdk1(points_packet(5, 1), 4167, 6, pkt), DecodeError::kLengthMismatch);
  // An IMU packet is exactly 42 bytes; one with padding is not SDK1.
  Bytes imu = sdk1_header(6, 0, 0);
  for (int i = 0; i < 6; ++i) imu.put<float>(0.0F);
  ASSERT_EQ(decode_sdk1(imu.data, 4167, 6, pkt), DecodeError::kNone);
  imu.u8(0);
  EXPECT_EQ(decode_sdk1(imu.data, 4167, 6, pkt), DecodeError::kLengthMismatch);
  // The reserved timestamp type 2 (and anything above 4) is not a valid SDK1 header either.
  auto typed = points_packet(5, 0);
  typed[8] = std::byte{2};
  EXPECT_EQ(decode_sdk1(typed, 4167, 6, pkt), DecodeError::kBadTime);
  typed[8] = std::byte{9};
  EXPECT_EQ(decode_sdk1(typed, 4167, 6, pkt), DecodeError::kBadTime);
}

// A Velodyne data packet (1206 bytes, blocks flagged FF EE) on a Livox port: not SDK1, not SDK2.
TEST(LivoxPackets, RejectVelodyneDataPackets) {
  std::vector<std::byte> vlp(1206, std::byte{0});
  for (std::size_t b = 0; b < 12; ++b) {
    vlp[b * 100] = std::byte{0xFF};
    vlp[b * 100 + 1] = std::byte{0xEE};
    for (std::size_t c = 4; c < 100; c += 3) vlp[b * 100 + c] = std::byte{0x40};
  }
  vlp[1204] = std::byte{0x37};
  vlp[1205] = std::byte{0xA1};
  for (int type = 0; type < 9; ++type) {
    vlp[9] = static_cast<std::byte>(type);  // whatever byte 9 says
    LivoxPacket pkt;
    EXPECT_EQ(decode_sdk1(vlp, 4167, 6, pkt), DecodeError::kBadVersion);
  }
  LivoxPacket pkt;
  EXPECT_EQ(decode_sdk2(vlp, 4, pkt), DecodeError::kBadVersion);
}

Bytes sdk2_packet(int type, int dot_num, int interval, int point_bytes) {
  Bytes b;
  const int length = 36 + (type == 0 ? 24 : dot_num * point_bytes);
  b.u8(0).put<std::uint16_t>(static_cast<std::uint16_t>(length));
  b.put<std::uint16_t>(static_cast<std::uint16_t>(interval))
      .put<std::uint16_t>(static_cast<std::uint16_t>(dot_num));
  b.put<std::uint16_t>(7).u8(0).u8(type).u8(0);
  for (int i = 0; i < 12; ++i) b.u8(0);
  b.put<std::uint32_t>(0).put<std::uint64_t>(5'000'000'000ULL);
  return b;
}

TEST(LivoxSdk2Packet, Cartesian32AndTimingOverTheInterval) {
  Bytes b = sdk2_packet(1, 96, 4750, 14);
  for (int i = 0; i < 96; ++i)
    b.put<std::int32_t>(5000).put<std::int32_t>(i).put<std::int32_t>(-100).u8(9).u8(0);
  ASSERT_EQ(b.data.size(), 1380u);
  LivoxPacket pkt;
  ASSERT_EQ(decode_sdk2(b.data, 4, pkt), DecodeError::kNone);
  EXPECT_EQ(pkt.count, 96);
  EXPECT_EQ(pkt.udp_cnt, 7);
  EXPECT_EQ(pkt.timestamp_ns, 5'000'000'000);
  // 4750 * 100 ns / 95 = 5000 ns between points (200 kpts/s).
  EXPECT_EQ(pkt.points[1].t_offset_ns, 5000);
  EXPECT_EQ(pkt.points[95].t_offset_ns, 475000);
  EXPECT_FLOAT_EQ(pkt.points[10].y, 0.010F);
  EXPECT_EQ(pkt.points[10].line, 2);
}

TEST(LivoxSdk2Packet, Cartesian16SphericalAndCheckedImuCrc) {
  Bytes c = sdk2_packet(2, 96, 4750, 8);
  for (int i = 0; i < 96; ++i)
    c.put<std::int16_t>(123).put<std::int16_t>(-45).put<std::int16_t>(6).u8(1).u8(2);
  ASSERT_EQ(c.data.size(), 804u);
  LivoxPacket pkt;
  ASSERT_EQ(decode_sdk2(c.data, 4, pkt), DecodeError::kNone);
  EXPECT_FLOAT_EQ(pkt.points[0].x, 1.23F);
  EXPECT_FLOAT_EQ(pkt.points[0].y, -0.45F);

  Bytes s = sdk2_packet(3, 96, 4750, 10);
  for (int i = 0; i < 96; ++i)
    s.put<std::uint32_t>(2000).put<std::uint16_t>(0).put<std::uint16_t>(0).u8(0).u8(0);
  ASSERT_EQ(s.data.size(), 996u);
  ASSERT_EQ(decode_sdk2(s.data, 4, pkt), DecodeError::kNone);
  EXPECT_NEAR(pkt.points[0].z, 2.0F, 1e-6);  // zenith 0: straight up

  Bytes imu = sdk2_packet(0, 1, 0, 24);
  imu.put<float>(0.01F)
      .put<float>(0.02F)
      .put<float>(0.03F)
      .put<float>(0.0F)
      .put<float>(-1.0F)
      .put<float>(0.0F);
  ASSERT_EQ(imu.data.size(), 60u);
  const auto crc = crc32_standard(std::span<const std::byte>(imu.data).subspan(28));
  std::memcpy(imu.data.data() + 24, &crc, 4);
  ASSERT_EQ(decode_sdk2(imu.data, 4, pkt), DecodeError::kNone);
  EXPECT_EQ(pkt.kind, LivoxPacket::Kind::kImu);
  EXPECT_NEAR(pkt.accel_m_s2.y(), -9.80665, 1e-6);
  imu.data[40] ^= std::byte{1};
  EXPECT_EQ(decode_sdk2(imu.data, 4, pkt), DecodeError::kBadCrc);
}

TEST(LivoxSdk2Packet, RejectsInconsistentLengths) {
  Bytes b = sdk2_packet(1, 96, 4750, 14);
  LivoxPacket pkt;
  {
    Bytes full = sdk2_packet(1, 96, 4750, 14);
    for (int i = 0; i < 96 * 14; ++i) full.u8(1);
    ASSERT_EQ(decode_sdk2(full.data, 4, pkt), DecodeError::kNone);
    full.u8(0);  // one byte more than the length field says
    EXPECT_EQ(decode_sdk2(full.data, 4, pkt), DecodeError::kLengthMismatch);
    full.data.pop_back();
    full.data[0] = std::byte{5};  // an SDK1 version byte
    EXPECT_EQ(decode_sdk2(full.data, 4, pkt), DecodeError::kBadVersion);
    full.data[0] = std::byte{0};
    full.data[5] = std::byte{95};  // dot_num 95 with 96 points' bytes
    EXPECT_EQ(decode_sdk2(full.data, 4, pkt), DecodeError::kLengthMismatch);
  }
  EXPECT_EQ(decode_sdk2(b.data, 4, pkt), DecodeError::kLengthMismatch);  // no point bytes
  Bytes many = sdk2_packet(1, 500, 4750, 14);
  many.data.resize(36 + 500 * 14);
  EXPECT_EQ(decode_sdk2(many.data, 4, pkt), DecodeError::kLengthMismatch);  // > 100 points
  EXPECT_EQ(decode_sdk2(std::span(b.data).first(20), 4, pkt), DecodeError::kTooShort);
}

TEST(LivoxEncoders, RoundTripWithinQuantisation) {
  std::array<LivoxPoint, 96> pts{};
  for (int i = 0; i < 96; ++i) {
    pts[i].x = 3.0F + 0.0123F * i;
    pts[i].y = -1.5F;
    pts[i].z = 0.25F;
    pts[i].reflectivity = static_cast<std::uint8_t>(i);
    pts[i].valid = i != 4;
  }
  LivoxPacket pkt;
  const auto s1 = encode_sdk1_points(Sdk1Header{2, 0, 777, 0, 1, 1}, pts);
  ASSERT_EQ(decode_sdk1(s1, 4167, 6, pkt), DecodeError::kNone);
  for (int i = 0; i < 96; ++i) {
    EXPECT_EQ(pkt.points[i].valid, pts[i].valid);
    if (pts[i].valid) {
      EXPECT_NEAR(pkt.points[i].x, pts[i].x, 0.0005 + 1e-6);
    }
  }
  Sdk2Header h2;
  h2.time_interval_100ns = 4750;
  h2.write_crc = true;
  const auto s2 = encode_sdk2_points(h2, pts);
  ASSERT_EQ(s2.size(), 1380u);
  ASSERT_EQ(decode_sdk2(s2, 4, pkt), DecodeError::kNone);
  EXPECT_NEAR(pkt.points[50].x, pts[50].x, 0.0005 + 1e-6);
  const auto imu = encode_sdk2_imu(h2, Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::Vector3d(0, 0, 9.81));
  ASSERT_EQ(decode_sdk2(imu, 4, pkt), DecodeError::kNone);
  EXPECT_NEAR(pkt.accel_m_s2.z(), 9.81, 1e-5);
}

}  // namespace
}  // namespace livod::livox
