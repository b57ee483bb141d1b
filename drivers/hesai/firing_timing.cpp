#include "drivers/hesai/firing_timing.hpp"

#include <algorithm>
#include <cmath>

namespace livod::drivers::hesai {
namespace {

constexpr std::int32_t kXtRoundNs = 50'000;
constexpr std::int32_t kXtRoundStartNs = 5'632;
constexpr std::int32_t kXtFirstChannelNs = 368;
constexpr std::int32_t kXtChannelStepNs = 1'512;

constexpr std::int32_t k40pRoundNs = 55'560;
constexpr std::int32_t k40pLastBlockEndNs = -28'580;
// Pandar40P manual, Table II.4: firing time before the block's end, by laser id 1..40 (ns).
constexpr std::array<std::int32_t, 40> k40pLaserBeforeEndNs{
    42'220, 28'470, 16'040, 3'620,  45'490, 31'740, 47'460, 54'670, 20'620, 33'710,
    40'910, 8'190,  20'620, 27'160, 50'730, 8'190,  14'740, 36'980, 45'490, 52'700,
    23'890, 31'740, 38'950, 11'470, 18'650, 25'190, 48'760, 6'230,  12'770, 35'010,
    21'920, 9'500,  43'520, 29'770, 17'350, 4'920,  42'220, 28'470, 16'040, 3'620};

}  // namespace

FiringTiming::FiringTiming(Model model) {
  const ModelTraits& t = traits(model);
  for (int mode = 0; mode < 2; ++mode) {
    const int returns = mode + 1;
    auto& table = table_[static_cast<std::size_t>(mode)];
    auto& start = start_[static_cast<std::size_t>(mode)];
    for (int b = 0; b < t.blocks; ++b) {
      // Rounds before the packet's last one (block pairs share a round in dual return).
      const int rounds_before_last = (t.blocks - 1 - b) / returns;
      std::int32_t earliest = 0;
      std::int32_t latest = 0;
      for (int c = 0; c < t.channels; ++c) {
        std::int32_t offset = 0;
        if (model == Model::kPandarXT32) {
          offset = kXtRoundStartNs - kXtRoundNs * rounds_before_last + kXtFirstChannelNs +
                   kXtChannelStepNs * c;
        } else {
          offset = k40pLastBlockEndNs - k40pRoundNs * rounds_before_last -
                   k40pLaserBeforeEndNs[static_cast<std::size_t>(c)];
        }
        table[static_cast<std::size_t>(b * kMaxChannels + c)] = offset;
        earliest = c == 0 ? offset : std::min(earliest, offset);
        latest = c == 0 ? offset : std::max(latest, offset);
      }
      start[static_cast<std::size_t>(b)] = earliest;
      if (b == t.blocks - 1) last_firing_[static_cast<std::size_t>(mode)] = latest;
    }
    period_ns_[static_cast<std::size_t>(mode)] =
        std::llround(t.firing_round_ns * t.blocks / returns);
  }
}

}  // namespace livod::drivers::hesai
