#pragma once
// Model name -> decoder, whichever family has the model. The tables are the families'
// descriptors (drivers/lidar_family.hpp); this header keeps the short name its callers use.

#include <memory>

#include "drivers/lidar_family.hpp"

namespace livod::drivers {

// make_lidar_decoder: throws livod::Error for an unknown model (listing the known ones) and
// whatever the family's factory throws for bad files or options.
[[nodiscard]] inline std::unique_ptr<LidarDecoder> make_decoder(const DecoderConfig& config) {
  return make_lidar_decoder(config);
}

}  // namespace livod::drivers
