#pragma once
// SensorConfig -> the family's LidarDecoder: the factory of the sensor's LiDAR family
// (drivers/lidar_family.hpp) with the configuration's model, metadata or calibration file, frame
// cut and family section (daemon::decoder_config). Used by replay, preflight and the runtime.

#include <memory>
#include <string>

#include "daemon/config/config.hpp"
#include "drivers/lidar_decoder.hpp"
#include "drivers/ouster/metadata.hpp"

namespace livod::daemon::replay {

// Throws livod::Error (naming the sensor) for a driver that is not a packet LiDAR, a frame cut
// the family's decoder cannot do, unreadable metadata / calibration, or an Ouster model that the
// metadata contradicts.
std::unique_ptr<drivers::LidarDecoder> make_lidar_decoder(const SensorConfig& sensor);

// An Ouster decoder from metadata found elsewhere than sensor.metadata (a bag's metadata topic);
// the same checks as make_lidar_decoder.
std::unique_ptr<drivers::LidarDecoder> make_ouster_decoder(
    const SensorConfig& sensor, const drivers::ouster::SensorMetadata& metadata);

// Why a configured Ouster model contradicts the metadata (product line or beam count), or empty
// (drivers::ouster::model_mismatch).
std::string ouster_model_mismatch(const SensorConfig& sensor,
                                  const drivers::ouster::SensorMetadata& metadata);

}  // namespace livod::daemon::replay
