#pragma once
// The Ouster family's decoder factory (ouster_family.cpp): needs the sensor metadata JSON, and
// checks a configured model (OS1-128, ...) against it.

#include <memory>
#include <string>
#include <string_view>

#include "drivers/lidar_decoder.hpp"
#include "drivers/lidar_family.hpp"
#include "drivers/ouster/metadata.hpp"

namespace livod::drivers::ouster {

// Why a model name (OS1-128, OS-1-128, ...) contradicts the metadata (product line or beam
// count), or empty. The family's "OS" entry (any Ouster) and an empty or unknown name contradict
// nothing.
[[nodiscard]] std::string model_mismatch(std::string_view model, const SensorMetadata& metadata);

// An OusterDecoder with default options for metadata found anywhere (a file, a bag's metadata
// topic). Throws livod::Error for a frame cut other than frame_id, a Velodyne/Hesai calibration
// file, or a model the metadata contradicts.
[[nodiscard]] std::unique_ptr<LidarDecoder> make_ouster_decoder(const DecoderConfig& config,
                                                                const SensorMetadata& metadata);

// Loads config.metadata, then as above. Throws livod::Error also if the metadata is missing,
// unreadable or invalid.
[[nodiscard]] std::unique_ptr<LidarDecoder> make_ouster_decoder(const DecoderConfig& config);

}  // namespace livod::drivers::ouster
