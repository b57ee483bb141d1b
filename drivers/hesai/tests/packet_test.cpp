// Hesai packets built byte by byte from the manuals' layouts (not with livod's encoder), then
// decoded; encoder round trips; foreign traffic refused.

#include "drivers/hesai/packet.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "io/pcap.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::hesai {
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

// A single-return PandarXT-32 packet: block b at azimuth 100 + 18 b (0.01 deg), channel c at
// distance 1000 + c (x 4 mm), reflectivity c; 2023-01-11 01:31:18.123456 UTC; sequence 77.
std::vector<std::byte> xt32_single() {
  Bytes b;
  b.u8(0xEE).u8(0xFF).u8(6).u8(1).u8(0).u8(0);
  b.u8(32).u8(8).u8(0).u8(4).u8(1).u8(1);
  for (int blk = 0; blk < 8; ++blk) {
    b.put<std::uint16_t>(static_cast<std::uint16_t>(100 + 18 * blk));
    for (int c = 0; c < 32; ++c)
      b.put<std::uint16_t>(static_cast<std::uint16_t>(1000 + c)).u8(c).u8(0);
  }
  for (int i = 0; i < 9; ++i) b.u8(0);
  b.u8(0);                                     // high temperature
  b.u8(0x37);                                  // strongest return
  b.put<std::uint16_t>(600);                   // RPM
  b.u8(123).u8(1).u8(11).u8(1).u8(31).u8(18);  // 2023-01-11 01:31:18
  b.put<std::uint32_t>(123456);
  b.u8(0x42);
  b.put<std::uint32_t>(77);
  return b.data;
}

// A Pandar40P packet with the UDP sequence: block b at azimuth 35900 + 20 b (wrapping), laser c
// at 2000 + c; 2024-02-29 23:59:59.999999 UTC; dual return (last + strongest).
std::vector<std::byte> pandar40p_dual() {
  Bytes b;
  for (int blk = 0; blk < 10; ++blk) {
    b.u8(0xFF).u8(0xEE).put<std::uint16_t>(
        static_cast<std::uint16_t>((35900 + 20 * (blk / 2)) % 36000));
    for (int c = 0; c < 40; ++c) b.put<std::uint16_t>(static_cast<std::uint16_t>(2000 + c)).u8(7);
  }
  for (int i = 0; i < 5; ++i) b.u8(0);
  b.u8(1);  // high temperature: shutdown in 60 s
  b.u8(0).u8(0);
  b.put<std::uint16_t>(1200);
  b.put<std::uint32_t>(999999);
  b.u8(0x39);
  b.u8(0x42);
  b.u8(24).u8(2).u8(29).u8(23).u8(59).u8(59);
  b.put<std::uint32_t>(0xFFFFFFFF);
  return b.data;
}

TEST(HesaiPacket, Xt32SingleReturnFieldsAndTime) {
  const auto bytes = xt32_single();
  ASSERT_EQ(bytes.size(), 1080U);
  HesaiPacket p;
  ASSERT_EQ(decode_packet(Model::kPandarXT32, bytes, p), PacketError::kNone);
  EXPECT_EQ(p.returns, 1);
  EXPECT_EQ(p.return_mode, 0x37);
  EXPECT_DOUBLE_EQ(p.distance_unit_m, 0.004);
  EXPECT_EQ(p.azimuth[3], 154);
  EXPECT_EQ(p.raw_distance(5, 31), 1031);
  EXPECT_EQ(p.raw_reflectivity(5, 31), 31);
  EXPECT_EQ(p.motor_rpm, 600);
  // 2023-01-11T01:31:18Z = 1673400678 s (the reference scan's bag stamp second).
  EXPECT_EQ(p.timestamp_ns, 1673400678LL * 1'000'000'000 + 123'456'000);
  ASSERT_TRUE(p.udp_sequence);
  EXPECT_EQ(*p.udp_sequence, 77U);
  EXPECT_FALSE(p.high_temperature);
}

TEST(HesaiPacket, Pandar40pDualWithSequenceAndLeapDay) {
  const auto bytes = pandar40p_dual();
  ASSERT_EQ(bytes.size(), 1266U);
  HesaiPacket p;
  ASSERT_EQ(decode_packet(Model::kPandar40P, bytes, p), PacketError::kNone);
  EXPECT_EQ(p.returns, 2);
  EXPECT_EQ(p.azimuth[9], (35900 + 80) % 36000);
  EXPECT_EQ(p.raw_distance(9, 39), 2039);
  EXPECT_TRUE(p.high_temperature);
  EXPECT_EQ(p.motor_rpm, 1200);
  // 2024-02-29T23:59:59Z = 1709251199 s.
  EXPECT_EQ(p.timestamp_ns, 1709251199LL * 1'000'000'000 + 999'999'000);
  EXPECT_EQ(*p.udp_sequence, 0xFFFFFFFFU);
  // Without the sequence the packet is 1262 bytes.
  auto shorter = bytes;
  shorter.resize(1262);
  ASSERT_EQ(decode_packet(Model::kPandar40P, shorter, p), PacketError::kNone);
  EXPECT_FALSE(p.udp_sequence);
}

TEST(HesaiPacket, EncoderRoundTrips) {
  for (const auto& bytes : {xt32_single(), pandar40p_dual()}) {
    const Model model = bytes.size() == 1080 ? Model::kPandarXT32 : Model::kPandar40P;
    HesaiPacket p;
    ASSERT_EQ(decode_packet(model, bytes, p), PacketError::kNone);
    EXPECT_EQ(encode_packet(p), bytes);
  }
}

TEST(HesaiPacket, RealXt32PacketsDecodeAndReencodeExactly) {
  io::PcapReader reader(test::data_path("hesai/hesai_xt32.pcap"));
  std::size_t n = 0;
  while (auto d = reader.next()) {
    const std::vector<std::byte> bytes(d->payload.begin(), d->payload.end());
    HesaiPacket p;
    ASSERT_EQ(decode_packet(Model::kPandarXT32, bytes, p), PacketError::kNone) << n;
    // Reserved bytes (each channel's fourth byte, the tail's first nine) are not kept: compare
    // everything else.
    auto again = encode_packet(p);
    for (std::size_t i = 1052; i < 1061; ++i) again[i] = bytes[i];
    for (std::size_t blk = 0; blk < 8; ++blk) {
      for (std::size_t c = 0; c < 32; ++c) {
        const std::size_t reserved = 12 + blk * 130 + 2 + c * 4 + 3;
        again[reserved] = bytes[reserved];
      }
    }
    ASSERT_EQ(again, bytes) << n;
    ++n;
  }
  EXPECT_EQ(n, 2000U);
}

// Issue 13: every decoder rejects what is not its protocol.
TEST(HesaiPacket, ForeignAndDamagedDatagramsAreRefused) {
  HesaiPacket p;
  // A Velodyne data packet (1206 bytes, FF EE block flags) and a Livox SDK1 packet.
  std::vector<std::byte> velodyne(1206, std::byte{0});
  for (std::size_t b = 0; b < 12; ++b) {
    velodyne[b * 100] = std::byte{0xFF};
    velodyne[b * 100 + 1] = std::byte{0xEE};
  }
  EXPECT_EQ(decode_packet(Model::kPandarXT32, velodyne, p), PacketError::kWrongSize);
  EXPECT_EQ(decode_packet(Model::kPandar40P, velodyne, p), PacketError::kWrongSize);
  std::vector<std::byte> livox(1362, std::byte{0});
  livox[0] = std::byte{5};
  EXPECT_EQ(decode_packet(Model::kPandarXT32, livox, p), PacketError::kWrongSize);
  // Each model refuses the other's packets.
  EXPECT_EQ(decode_packet(Model::kPandar40P, xt32_single(), p), PacketError::kWrongSize);
  EXPECT_EQ(decode_packet(Model::kPandarXT32, pandar40p_dual(), p), PacketError::kWrongSize);

  auto xt = xt32_single();
  auto damaged = xt;
  damaged[0] = std::byte{0xFF};
  EXPECT_EQ(decode_packet(Model::kPandarXT32, damaged, p), PacketError::kBadHeader);
  damaged = xt;
  damaged[2] = std::byte{1};  // protocol 1.x: a Pandar128
  EXPECT_EQ(decode_packet(Model::kPandarXT32, damaged, p), PacketError::kBadHeader);
  damaged = xt;
  damaged[6] = std::byte{16};  // an XT-16's header
  EXPECT_EQ(decode_packet(Model::kPandarXT32, damaged, p), PacketError::kWrongModel);
  damaged = xt;
  damaged[11] = std::byte{0};  // says "no UDP sequence" but has one
  EXPECT_EQ(decode_packet(Model::kPandarXT32, damaged, p), PacketError::kBadHeader);
  damaged = xt;
  damaged[12] = std::byte{0xA0};  // azimuth 0x8CA0 = 36000
  damaged[13] = std::byte{0x8C};
  EXPECT_EQ(decode_packet(Model::kPandarXT32, damaged, p), PacketError::kBadAzimuth);
  damaged = xt;
  damaged[1062] = std::byte{0x39};  // dual return mode with a return number of 1
  EXPECT_EQ(decode_packet(Model::kPandarXT32, damaged, p), PacketError::kBadReturnMode);
  damaged = xt;
  damaged[1066] = std::byte{2};
  damaged[1067] = std::byte{30};  // February 30
  EXPECT_EQ(decode_packet(Model::kPandarXT32, damaged, p), PacketError::kBadTime);
  damaged = xt;
  const std::uint32_t too_many_us = 1'000'001;
  std::memcpy(damaged.data() + 1071, &too_many_us, 4);
  EXPECT_EQ(decode_packet(Model::kPandarXT32, damaged, p), PacketError::kBadTime);

  auto p40 = pandar40p_dual();
  damaged = p40;
  damaged[5 * 124 + 1] = std::byte{0xDD};  // block 6's flag
  EXPECT_EQ(decode_packet(Model::kPandar40P, damaged, p), PacketError::kBadHeader);
  damaged = p40;
  damaged[1254] = std::byte{0x33};  // "first return" is an XT mode
  EXPECT_EQ(decode_packet(Model::kPandar40P, damaged, p), PacketError::kBadReturnMode);
  damaged = p40;
  damaged.resize(1264);
  EXPECT_EQ(decode_packet(Model::kPandar40P, damaged, p), PacketError::kWrongSize);
}

}  // namespace
}  // namespace livod::drivers::hesai
