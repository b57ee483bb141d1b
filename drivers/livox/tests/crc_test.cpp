#include "drivers/livox/crc.hpp"

#include <gtest/gtest.h>

#include <string_view>

namespace livod::livox {
namespace {

std::span<const std::byte> bytes(std::string_view s) {
  return {reinterpret_cast<const std::byte*>(s.data()), s.size()};
}

TEST(LivoxCrc, CheckValuesFromTheProtocolReference) {
  EXPECT_EQ(crc16_sdk1(bytes("123456789")), 0xAB4E);
  EXPECT_EQ(crc32_sdk1(bytes("123456789")), 0xB08DB5B1U);
  EXPECT_EQ(crc16_ccitt_false(bytes("123456789")), 0x29B1);
  EXPECT_EQ(crc32_standard(bytes("123456789")), 0xCBF43926U);
}

}  // namespace
}  // namespace livod::livox
