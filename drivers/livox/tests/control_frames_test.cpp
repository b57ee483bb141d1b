// Byte-exact control frames from sensor-protocols.md Appendix A (verified there against the
// vendor CRC code and an independent implementation).

#include <gtest/gtest.h>

#include <sstream>

#include "drivers/livox/sdk1_control.hpp"
#include "drivers/livox/sdk2_control.hpp"

namespace livod::livox {
namespace {

std::vector<std::byte> hex(const std::string& text) {
  std::istringstream is(text);
  std::vector<std::byte> out;
  std::string byte;
  while (is >> byte) out.push_back(static_cast<std::byte>(std::stoi(byte, nullptr, 16)));
  return out;
}

TEST(LivoxSdk1Control, HeartbeatAndStartSamplingAreByteExact) {
  EXPECT_EQ(sdk1::encode(sdk1::heartbeat(1)), hex("AA 00 0F 00 00 01 00 F7 CA 00 03 C9 8B 3E A8"));
  EXPECT_EQ(sdk1::encode(sdk1::sampling(2, true)),
            hex("AA 00 10 00 00 02 00 23 3E 00 04 01 D2 95 68 9A"));
}

TEST(LivoxSdk1Control, ParseRoundTripsAndRejectsCorruption) {
  const auto bytes = sdk1::encode(sdk1::handshake(7, 0xC0A80132, 56001, 55501, 56001));
  sdk1::ControlFrame f;
  ASSERT_EQ(sdk1::parse(bytes, f), sdk1::ParseError::kNone);
  EXPECT_EQ(f.type, sdk1::PacketType::kAck);  // the SDK's handshake quirk
  EXPECT_EQ(f.seq, 7);
  EXPECT_EQ(f.cmd_id, sdk1::cmd::kHandshake);
  ASSERT_EQ(f.payload.size(), 10u);
  EXPECT_EQ(f.payload[0], std::byte{192});
  EXPECT_EQ(f.payload[3], std::byte{50});
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    auto bad = bytes;
    bad[i] ^= std::byte{0x01};
    EXPECT_NE(sdk1::parse(bad, f), sdk1::ParseError::kNone) << "flip at byte " << i;
  }
  EXPECT_EQ(sdk1::parse(std::span(bytes).first(10), f), sdk1::ParseError::kTooShort);
}

TEST(LivoxSdk2Control, DiscoveryWorkModeAndDestinationAreByteExact) {
  EXPECT_EQ(sdk2::encode(sdk2::discovery(0)),
            hex("AA 00 18 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 C8 64 00 00 00 00"));
  EXPECT_EQ(sdk2::encode(sdk2::set_work_mode(1, sdk2::WorkMode::kSampling)),
            hex("AA 00 21 00 01 00 00 00 00 01 00 00 00 00 00 00 00 00 35 28 6F D5 E7 AD 01 00 00 "
                "00 1A 00 01 00 01"));
  const auto dest = sdk2::destination(sdk2::key::kPointDestination, 0xC0A80132, 56301, 56300);
  EXPECT_EQ(sdk2::encode(sdk2::set_params(2, {dest})),
            hex("AA 00 28 00 02 00 00 00 00 01 00 00 00 00 00 00 00 00 37 1C 25 29 65 E6 01 00 00 "
                "00 06 00 08 00 C0 A8 01 32 ED DB EC DB"));
}

TEST(LivoxSdk2Control, ParsesADiscoveryAckAndRejectsCorruption) {
  sdk2::ControlFrame ack{5, sdk2::cmd::kDiscovery, 1, 1, {}};
  ack.data = {std::byte{0}, std::byte{9}};
  const std::string sn = "47MDL9T0020193";
  for (std::size_t i = 0; i < 16; ++i) {
    ack.data.push_back(i < sn.size() ? static_cast<std::byte>(sn[i]) : std::byte{0});
  }
  for (int b : {192, 168, 1, 193}) ack.data.push_back(static_cast<std::byte>(b));
  ack.data.push_back(std::byte{0x24});
  ack.data.push_back(std::byte{0xDB});  // 56100
  const auto bytes = sdk2::encode(ack);
  sdk2::ControlFrame parsed;
  ASSERT_EQ(sdk2::parse(bytes, parsed), sdk2::ParseError::kNone);
  sdk2::DiscoveryAck info;
  ASSERT_TRUE(sdk2::parse_discovery_ack(parsed, info));
  EXPECT_EQ(info.device_type, 9);
  EXPECT_EQ(info.serial, sn);
  EXPECT_EQ(info.lidar_ip, 0xC0A801C1u);
  EXPECT_EQ(info.cmd_port, 56100);
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    if (i >= 12 && i < 18) continue;  // reserved bytes are covered by the header CRC too
    auto bad = bytes;
    bad[i] ^= std::byte{0x80};
    EXPECT_NE(sdk2::parse(bad, parsed), sdk2::ParseError::kNone) << "flip at byte " << i;
  }
}

}  // namespace
}  // namespace livod::livox
