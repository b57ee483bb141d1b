#pragma once
// SensorConfig -> the family's LidarDecoder: the factory of the sensor's LiDAR family
// (drivers/lidar_family.hpp) with the configuration's model, metadata or calibration file, frame
// cut and family section (daemon::decoder_config). Used by replay and the runtime.

#include <memory>

#include "daemon/config/config.hpp"
#include "drivers/lidar_decoder.hpp"

namespace livod::daemon::replay {

// Throws livod::Error (naming the sensor) for a driver that is not a packet LiDAR, a frame cut
// the family's decoder cannot do, or unreadable metadata / calibration.
std::unique_ptr<drivers::LidarDecoder> make_lidar_decoder(const SensorConfig& sensor);

}  // namespace livod::daemon::replay
