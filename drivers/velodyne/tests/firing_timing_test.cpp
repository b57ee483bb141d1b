// Per-firing time offsets (§4.3 of shared/docs/sensor-protocols.md).

#include "drivers/velodyne/firing_timing.hpp"

#include <gtest/gtest.h>

namespace livod::drivers::velodyne {
namespace {

TEST(FiringTiming, Vlp16SingleReturnMatchesTheManualFormula) {
  const FiringTiming t(Model::kVlp16);
  // t = (2b + f) * 55.296 + laser * 2.304 us, channel = 16 f + laser.
  EXPECT_EQ(t.offset_ns(false, 3, 16 + 1), 389'376);  // VGAD's test vector t(3, 1, 1)
  EXPECT_EQ(t.offset_ns(false, 0, 0), 0);
  EXPECT_EQ(t.offset_ns(false, 0, 15), 15 * 2'304);
  EXPECT_EQ(t.offset_ns(false, 0, 16), 55'296);
  EXPECT_EQ(t.offset_ns(false, 11, 31), 23 * 55'296 + 15 * 2'304);  // 1306.368 us
  for (int b = 0; b < 12; ++b) {
    for (int c = 0; c < 32; ++c) {
      EXPECT_EQ(t.offset_ns(false, b, c), (2 * b + c / 16) * 55'296 + (c % 16) * 2'304);
    }
    EXPECT_EQ(t.block_reference_ns(false, b), 2 * b * 55'296);
  }
  EXPECT_EQ(t.packet_period_ns(false), 1'327'104);  // 754 packets/s
  EXPECT_EQ(t.blocks_used(false), 12);
}

TEST(FiringTiming, Vlp16DualReturnBlockPairsShareTheirFirings) {
  const FiringTiming t(Model::kVlp16);
  for (int b = 0; b < 12; ++b) {
    for (int c = 0; c < 32; ++c) {
      EXPECT_EQ(t.offset_ns(true, b, c), ((b - b % 2) + c / 16) * 55'296 + (c % 16) * 2'304);
      EXPECT_EQ(t.offset_ns(true, b, c), t.offset_ns(true, b ^ 1, c));
    }
  }
  EXPECT_EQ(t.offset_ns(true, 3, 16 + 1), (2 + 1) * 55'296 + 2'304);
  EXPECT_EQ(t.packet_period_ns(true), 663'552);  // 1508 packets/s
}

TEST(FiringTiming, PuckHiResUsesTheVlp16Table) {
  const FiringTiming vlp16(Model::kVlp16);
  const FiringTiming hires(Model::kPuckHiRes);
  for (int b = 0; b < 12; ++b) {
    for (int c = 0; c < 32; ++c)
      EXPECT_EQ(hires.offset_ns(false, b, c), vlp16.offset_ns(false, b, c));
  }
}

TEST(FiringTiming, Hdl32eAdvancesEveryLaserAsVdecDoes) {
  const FiringTiming t(Model::kHdl32e);
  for (int b = 0; b < 12; ++b) {
    for (int c = 0; c < 32; ++c) {
      EXPECT_EQ(t.offset_ns(false, b, c), b * 46'080 + c * 1'152);
      EXPECT_EQ(t.offset_ns(true, b, c), (b / 2) * 46'080 + c * 1'152);
    }
  }
  // 32 firings of 1.152 us then the 9.216 us recharge fill the 46.08 us cycle exactly: the last
  // laser's slot and the recharge separate it from the next block (VROS's floor(c/2) would
  // leave half the cycle empty).
  EXPECT_EQ(t.offset_ns(false, 1, 0) - t.offset_ns(false, 0, 31), 1'152 + 9'216);
  EXPECT_EQ(t.packet_period_ns(false), 552'960);  // 1808 packets/s
}

TEST(FiringTiming, Vlp32cFiresLaserPairs) {
  const FiringTiming t(Model::kVlp32c);
  for (int b = 0; b < 12; ++b) {
    for (int c = 0; c < 32; c += 2) {
      EXPECT_EQ(t.offset_ns(false, b, c), b * 55'296 + (c / 2) * 2'304);
      EXPECT_EQ(t.offset_ns(false, b, c + 1), t.offset_ns(false, b, c));
      EXPECT_EQ(t.offset_ns(true, b, c), (b / 2) * 55'296 + (c / 2) * 2'304);
    }
  }
}

TEST(FiringTiming, Vls128FollowsVdecsSequenceTable) {
  const FiringTiming t(Model::kVls128);
  constexpr int kSlot = 2'665;
  // Block 0, channel 0: first firing group, 7 us before the top-of-hour alignment point.
  EXPECT_EQ(t.offset_ns(false, 0, 0), -7'000);
  // dsr = 32 * bank + channel; groups of 8 lasers; 2 extra slots after dsr 63.
  EXPECT_EQ(t.offset_ns(false, 1, 0), 4 * kSlot - 7'000);          // dsr 32
  EXPECT_EQ(t.offset_ns(false, 2, 0), (8 + 2) * kSlot - 7'000);    // dsr 64
  EXPECT_EQ(t.offset_ns(false, 3, 31), (15 + 2) * kSlot - 7'000);  // dsr 127
  EXPECT_EQ(t.offset_ns(false, 4, 0), 20 * kSlot - 7'000);         // next sequence
  EXPECT_EQ(t.offset_ns(false, 11, 31), 2 * 20 * kSlot + 17 * kSlot - 7'000);
  EXPECT_EQ(t.block_reference_ns(false, 6), t.offset_ns(false, 4, 0));
  EXPECT_EQ(t.packet_period_ns(false), 3 * 20 * kSlot);  // 159.9 us: 6254 packets/s
  // Dual return: one sequence, pairs (2k, 2k+1) are bank k; blocks 8..11 unused.
  EXPECT_EQ(t.blocks_used(true), 8);
  EXPECT_EQ(t.offset_ns(true, 5, 3), t.offset_ns(false, 2, 3));
  EXPECT_EQ(t.offset_ns(true, 4, 3), t.offset_ns(true, 5, 3));
  // Firmware >= 5.2.3 uses 2.89 us slots.
  const FiringTiming new_fw(Model::kVls128, kVls128ChannelUsNewFirmware);
  EXPECT_EQ(new_fw.offset_ns(false, 4, 0), 20 * 2'890 - 7'000);
}

}  // namespace
}  // namespace livod::drivers::velodyne
