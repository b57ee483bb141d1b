#include "drivers/velodyne/firing_timing.hpp"

#include <cmath>

namespace livod::drivers::velodyne {
namespace {

// VLP-16 / Puck Hi-Res and VLP-32C: 16 firings of 2.304 us plus an 18.43 us recharge make a
// 55.296 us sequence (VLP-16 manual; VROS rawdata.cc, VDEC packet_decoder.cpp buildTimings).
constexpr std::int32_t kVlp16SequenceNs = 55'296;
constexpr std::int32_t kVlp16FiringNs = 2'304;
// HDL-32E: 32 firings of 1.152 us plus a 9.216 us recharge make a 46.08 us cycle. VDEC (and the
// HDL-32E manual) advance the time with every laser; VROS uses floor(c/2), copied from the
// VLP-32C branch. 32 x 1.152 us exactly fills the cycle, which supports VDEC.
constexpr std::int32_t kHdl32eCycleNs = 46'080;
constexpr std::int32_t kHdl32eFiringNs = 1'152;
// VLS-128 (VDEC, after VeloView's VelodynePlugin): a firing sequence is 20 channel slots (16
// groups of 8 lasers plus maintenance slots); the top of the hour is aligned with the fourth
// group, hence the 7 us shift.
constexpr int kVls128SlotsPerSequence = 20;
constexpr std::int32_t kVls128ToHAdjustNs = 7'000;

}  // namespace

FiringTiming::FiringTiming(Model model, double vls128_channel_us) : model_(model) {
  const auto vls_slot_ns = static_cast<std::int32_t>(std::llround(vls128_channel_us * 1000.0));
  for (int mode = 0; mode < 2; ++mode) {
    const bool dual = mode == 1;
    auto& table = table_[static_cast<std::size_t>(mode)];
    auto& reference = reference_[static_cast<std::size_t>(mode)];
    for (int b = 0; b < wire::kBlocksPerPacket; ++b) {
      for (int c = 0; c < wire::kChannelsPerBlock; ++c) {
        std::int32_t t = 0;
        switch (model) {
          case Model::kVlp16:
          case Model::kPuckHiRes: {
            // Each block holds two sequences of 16 lasers; in dual return mode a block pair
            // (2k, 2k+1) carries the two returns of the same firings.
            const int first_sequence = dual ? (b - b % 2) : 2 * b;
            t = (first_sequence + c / 16) * kVlp16SequenceNs + (c % 16) * kVlp16FiringNs;
            break;
          }
          case Model::kVlp32c: {
            const int sequence = dual ? b / 2 : b;
            t = sequence * kVlp16SequenceNs + (c / 2) * kVlp16FiringNs;  // lasers fire in pairs
            break;
          }
          case Model::kHdl32e: {
            const int sequence = dual ? b / 2 : b;
            t = sequence * kHdl32eCycleNs + c * kHdl32eFiringNs;
            break;
          }
          case Model::kVls128: {
            // Single return: 3 sequences x 4 banks. Dual return: one sequence, block pairs
            // (2k, 2k+1) hold bank k's last and strongest returns.
            const int sequence = dual ? 0 : b / 4;
            const int bank = dual ? b / 2 : b % 4;
            const int dsr = 32 * bank + c;
            t = sequence * kVls128SlotsPerSequence * vls_slot_ns +
                (dsr / 8 + 2 * (dsr / 64)) * vls_slot_ns - kVls128ToHAdjustNs;
            break;
          }
        }
        table[static_cast<std::size_t>(b)][static_cast<std::size_t>(c)] = t;
      }
    }
    for (int b = 0; b < wire::kBlocksPerPacket; ++b) {
      int first_block_of_sequence = b;
      if (model == Model::kVls128) first_block_of_sequence = dual ? 0 : (b / 4) * 4;
      reference[static_cast<std::size_t>(b)] =
          table[static_cast<std::size_t>(first_block_of_sequence)][0];
    }
  }

  blocks_used_ = {wire::kBlocksPerPacket, model == Model::kVls128 ? 8 : wire::kBlocksPerPacket};
  switch (model) {
    case Model::kVlp16:
    case Model::kPuckHiRes:
      period_ns_ = {24LL * kVlp16SequenceNs, 12LL * kVlp16SequenceNs};
      break;
    case Model::kVlp32c:
      period_ns_ = {12LL * kVlp16SequenceNs, 6LL * kVlp16SequenceNs};
      break;
    case Model::kHdl32e:
      period_ns_ = {12LL * kHdl32eCycleNs, 6LL * kHdl32eCycleNs};
      break;
    case Model::kVls128:
      period_ns_ = {3LL * kVls128SlotsPerSequence * vls_slot_ns,
                    1LL * kVls128SlotsPerSequence * vls_slot_ns};
      break;
  }
}

}  // namespace livod::drivers::velodyne
