#pragma once
// The Hesai family's configuration section (`hesai:` in a sensor entry).

#include <optional>

#include "drivers/azimuth_window.hpp"

namespace livod::drivers::hesai {

struct HesaiSettings {
  // `fov_deg: [start, end]`: the sensor's start/end angle setting; the packets of the skipped
  // sector are no loss.
  std::optional<AzimuthWindow> fov;
  // `range_m: [min, max]`: returns outside are dropped (default: the model's datasheet range).
  std::optional<double> min_range_m;
  std::optional<double> max_range_m;
};

}  // namespace livod::drivers::hesai
