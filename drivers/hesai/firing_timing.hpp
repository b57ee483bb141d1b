#pragma once
// When each channel of each block fired, relative to the packet's timestamp (the "absolute time"
// of the packet in Hesai's manuals, Appendix II).
//
// PandarXT-32: the packet time is the start of the firing round stored in the last block (last
// block pair in dual return); rounds are 50 us apart; a block's round starts 5.632 us after its
// reference instant and channel c (0-based) fires 0.368 + 1.512 c us into the round (the figures
// of docs/sensor-protocols.md section 5).
// Pandar40P: the packet time t0 is when the last round was triggered; block b (1-based, n = 10)
// ends at t0 - 28.58 - 55.56 (10 - b) us (pairs of blocks share one end in dual return), and the
// 40 lasers fire at the end minus the per-laser offsets of the manual's Table II.4 (3.62 us for
// lasers 4 and 40 ... 54.67 us for laser 8).

#include <array>
#include <cstdint>

#include "drivers/hesai/model.hpp"
#include "drivers/hesai/packet.hpp"

namespace livod::drivers::hesai {

class FiringTiming {
 public:
  explicit FiringTiming(Model model);

  // ns from the packet timestamp to the firing of `channel` in `block`.
  [[nodiscard]] std::int32_t offset_ns(bool dual, int block, int channel) const {
    return table_[dual ? 1 : 0][static_cast<std::size_t>(block * kMaxChannels + channel)];
  }
  // The first firing of the block's round (its earliest channel).
  [[nodiscard]] std::int32_t block_start_ns(bool dual, int block) const {
    return start_[dual ? 1 : 0][static_cast<std::size_t>(block)];
  }
  // The packet's last firing (the latest channel of its last block): the packet leaves after it.
  [[nodiscard]] std::int32_t last_firing_ns(bool dual) const { return last_firing_[dual ? 1 : 0]; }
  // Time one packet's rounds take (the nominal time between packets).
  [[nodiscard]] std::int64_t packet_period_ns(bool dual) const { return period_ns_[dual ? 1 : 0]; }

 private:
  std::array<std::array<std::int32_t, kMaxBlocks * kMaxChannels>, 2> table_{};
  std::array<std::array<std::int32_t, kMaxBlocks>, 2> start_{};
  std::array<std::int32_t, 2> last_firing_{};
  std::array<std::int64_t, 2> period_ns_{};
};

}  // namespace livod::drivers::hesai
