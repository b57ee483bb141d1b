#pragma once
// The Velodyne family's configuration section (`velodyne:` in a sensor entry).

#include <optional>

#include "drivers/azimuth_window.hpp"

namespace livod::drivers::velodyne {

struct VelodyneSettings {
  // `fov_deg: [start, end]`: the sensor's FOV setting, so that its skipped sector is never
  // counted as loss (the decoder also learns it from the packets that straddle its edge).
  std::optional<AzimuthWindow> fov;
};

}  // namespace livod::drivers::velodyne
