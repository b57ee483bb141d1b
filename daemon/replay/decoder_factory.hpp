#pragma once
// SensorConfig -> the family's LidarDecoder, honouring the configured frame cut. (The model
// registry in drivers/registry.hpp builds decoders with default options for `livod decode`;
// replay needs the configuration's scan period / cut angle and metadata or calibration files.)

#include <memory>

#include "daemon/config/config.hpp"
#include "drivers/lidar_decoder.hpp"

namespace livod::daemon::replay {

// Throws livod::Error for a driver that is not a packet LiDAR, a frame cut the family's decoder
// cannot do, or unreadable metadata / calibration.
std::unique_ptr<drivers::LidarDecoder> make_lidar_decoder(const SensorConfig& sensor);

}  // namespace livod::daemon::replay
