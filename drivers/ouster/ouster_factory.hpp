#pragma once
// The Ouster family's decoder factory (ouster_family.cpp): needs the sensor metadata JSON.

#include <memory>

#include "drivers/lidar_decoder.hpp"
#include "drivers/lidar_family.hpp"

namespace livod::drivers::ouster {

// Loads config.metadata and builds an OusterDecoder with default options. Throws livod::Error if
// the metadata is missing, unreadable or invalid, or if a Velodyne calibration was given.
[[nodiscard]] std::unique_ptr<LidarDecoder> make_ouster_decoder(const DecoderConfig& config);

}  // namespace livod::drivers::ouster
