#include "drivers/imu/can_signal.hpp"

#include <gtest/gtest.h>

#include <array>
#include <random>

namespace livod::imu {
namespace {

TEST(CanSignal, IntelSignalsGrowUpwards) {
  const std::array<std::uint8_t, 8> d{0x34, 0x12, 0xF0, 0, 0, 0, 0, 0x80};
  EXPECT_EQ(extract_raw(d, {0, 16, false, false}), 0x1234);
  EXPECT_EQ(extract_raw(d, {4, 8, false, false}), 0x23);  // across a byte boundary
  EXPECT_EQ(extract_raw(d, {20, 4, false, false}), 0xF);  // high nibble of byte 2
  EXPECT_EQ(extract_raw(d, {20, 4, false, true}), -1);    // signed: 1111 = -1
  EXPECT_EQ(extract_raw(d, {63, 1, false, false}), 1);
  EXPECT_EQ(extract_raw(d, {56, 8, false, true}), -128);
}

TEST(CanSignal, MotorolaSignalsFollowTheDbcSawtooth) {
  // DBC big-endian: start bit 7 (MSB of byte 0), 16 bits -> bytes 0 (high) and 1 (low).
  const std::array<std::uint8_t, 8> d{0x12, 0x34, 0xAB, 0xCD, 0, 0, 0, 0};
  EXPECT_EQ(extract_raw(d, {7, 16, true, false}), 0x1234);
  // Start bit 3: bits 3..0 of byte 0, then byte 1 -> 0x2_34 (12 bits).
  EXPECT_EQ(extract_raw(d, {3, 12, true, false}), 0x234);
  // 8 bits from bit 19 (byte 2 bit 3): byte 2 bits 3..0 (0xB) then byte 3 bits 7..4 (0xC).
  EXPECT_EQ(extract_raw(d, {19, 8, true, false}), 0xBC);
  EXPECT_EQ(extract_raw(d, {23, 16, true, true}), static_cast<std::int16_t>(0xABCD));
  EXPECT_EQ(bytes_needed({7, 16, true, false}), 2);
  EXPECT_EQ(bytes_needed({3, 12, true, false}), 2);
  EXPECT_EQ(bytes_needed({23, 16, true, false}), 4);
  // From byte 7 onwards there is no next byte.
  EXPECT_FALSE(bytes_needed({59, 8, true, false}));
  EXPECT_TRUE(bytes_needed({59, 8, true, false}, 64));
  EXPECT_FALSE(check_bit_field({59, 8, true, false}).empty());
  EXPECT_TRUE(check_bit_field({63, 8, true, false}).empty());  // byte 7 alone
}

TEST(CanSignal, LimitsAreChecked) {
  EXPECT_FALSE(check_bit_field({0, 0, false, false}).empty());
  EXPECT_FALSE(check_bit_field({0, 65, false, false}).empty());
  EXPECT_FALSE(check_bit_field({64, 1, false, false}).empty());
  EXPECT_FALSE(check_bit_field({60, 8, false, false}).empty());  // Intel past bit 63
  EXPECT_TRUE(check_bit_field({0, 64, false, true}).empty());
  EXPECT_EQ(bytes_needed({0, 64, false, false}), 8);
  EXPECT_EQ(bytes_needed({500, 12, false, false}, 64), 64);
}

TEST(CanSignal, InsertThenExtractRoundTripsEveryValidField) {
  std::mt19937_64 rng(7);
  int checked = 0;
  for (int start = 0; start < 64; ++start) {
    for (int length = 1; length <= 64; ++length) {
      for (const bool big : {false, true}) {
        for (const bool is_signed : {false, true}) {
          const CanBitField f{start, length, big, is_signed};
          if (!bytes_needed(f)) continue;
          std::array<std::uint8_t, 8> d{};
          for (auto& b : d) b = static_cast<std::uint8_t>(rng());
          const auto before = d;
          const std::uint64_t mask = length == 64 ? ~0ULL : ((1ULL << length) - 1);
          const std::uint64_t bits = rng() & mask;
          std::int64_t expected = static_cast<std::int64_t>(bits);
          if (is_signed && length < 64 && ((bits >> (length - 1)) & 1U) != 0) {
            expected = static_cast<std::int64_t>(bits | ~mask);
          }
          insert_raw(d, f, static_cast<std::int64_t>(bits));
          ASSERT_EQ(extract_raw(d, f), expected) << start << " " << length << " " << big;
          // Only the field's own bits changed.
          std::array<std::uint8_t, 8> other = d;
          insert_raw(other, f, 0);
          std::array<std::uint8_t, 8> before_cleared = before;
          insert_raw(before_cleared, f, 0);
          ASSERT_EQ(other, before_cleared);
          ++checked;
        }
      }
    }
  }
  EXPECT_GT(checked, 4000);
}

}  // namespace
}  // namespace livod::imu
