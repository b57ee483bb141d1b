#pragma once
// Per-firing time offsets from the packet timestamp (which stamps the first firing of block 0),
// following §4.3 of shared/docs/sensor-protocols.md. Where VROS and VDEC disagree (HDL-32E,
// VLS-128) the VDEC tables are used; docs/drivers/velodyne.md lists the sources.

#include <array>
#include <cstdint>

#include "drivers/velodyne/model.hpp"
#include "drivers/velodyne/wire.hpp"

namespace livod::drivers::velodyne {

// VLS-128 channel (firing group) duration: 2.665 us up to firmware 5.1.7, 2.89 us since 5.2.3.
inline constexpr double kVls128ChannelUsOldFirmware = 2.665;
inline constexpr double kVls128ChannelUsNewFirmware = 2.89;

class FiringTiming {
 public:
  explicit FiringTiming(Model model, double vls128_channel_us = kVls128ChannelUsOldFirmware);

  // ns from the packet timestamp to the firing of `channel` (0..31) in `block` (0..11).
  [[nodiscard]] std::int32_t offset_ns(bool dual, int block, int channel) const {
    return table_[dual ? 1 : 0][static_cast<std::size_t>(block)][static_cast<std::size_t>(channel)];
  }

  // The instant the block's azimuth field refers to: the first firing of the block's firing
  // sequence (for VLS-128 the sequence spans four blocks, one per laser bank).
  [[nodiscard]] std::int32_t block_reference_ns(bool dual, int block) const {
    return reference_[dual ? 1 : 0][static_cast<std::size_t>(block)];
  }

  // Blocks that carry data: 12, except VLS-128 dual return where blocks 8..11 are unused.
  [[nodiscard]] int blocks_used(bool dual) const { return blocks_used_[dual ? 1 : 0]; }

  // Duration of one packet's worth of firings (the nominal time between packets).
  [[nodiscard]] std::int64_t packet_period_ns(bool dual) const { return period_ns_[dual ? 1 : 0]; }

  [[nodiscard]] Model model() const { return model_; }

 private:
  using BlockTable =
      std::array<std::array<std::int32_t, wire::kChannelsPerBlock>, wire::kBlocksPerPacket>;
  Model model_;
  std::array<BlockTable, 2> table_{};
  std::array<std::array<std::int32_t, wire::kBlocksPerPacket>, 2> reference_{};
  std::array<int, 2> blocks_used_{wire::kBlocksPerPacket, wire::kBlocksPerPacket};
  std::array<std::int64_t, 2> period_ns_{};
};

}  // namespace livod::drivers::velodyne
