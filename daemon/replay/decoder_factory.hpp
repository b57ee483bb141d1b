#pragma once
// SensorConfig -> the family's LidarDecoder, honouring the configured frame cut. (The model
// registry in drivers/registry.hpp builds decoders with default options for `livod decode`;
// replay needs the configuration's scan period / cut angle and metadata or calibration files.)

#include <memory>

#include "daemon/config/config.hpp"
#include "drivers/lidar_decoder.hpp"
#include "drivers/ouster/metadata.hpp"

namespace livod::daemon::replay {

// Throws livod::Error for a driver that is not a packet LiDAR, a frame cut the family's decoder
// cannot do, unreadable metadata / calibration, or an Ouster model that the metadata contradicts.
std::unique_ptr<drivers::LidarDecoder> make_lidar_decoder(const SensorConfig& sensor);

// An Ouster decoder from metadata found elsewhere than sensor.metadata (a bag's metadata topic);
// the same checks as make_lidar_decoder.
std::unique_ptr<drivers::LidarDecoder> make_ouster_decoder(
    const SensorConfig& sensor, const drivers::ouster::SensorMetadata& metadata);

// Why a configured Ouster model contradicts the metadata (product line or beam count), or empty.
std::string ouster_model_mismatch(const SensorConfig& sensor,
                                  const drivers::ouster::SensorMetadata& metadata);

}  // namespace livod::daemon::replay
