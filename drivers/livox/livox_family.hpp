#pragma once
// The Livox families' descriptors (drivers/lidar_family.hpp): SDK1 (Avia, Horizon, Tele-15,
// Mid-40, Mid-70) and SDK2 (Mid-360, HAP) are two configuration drivers with one decoder.

#include <memory>

#include "drivers/lidar_family.hpp"

namespace livod::livox {

[[nodiscard]] const drivers::LidarFamily& livox_sdk1_family();
[[nodiscard]] const drivers::LidarFamily& livox_sdk2_family();

// Builds a LivoxDecoder for config.model (either SDK). Livox sensors need no calibration or
// metadata file: passing one is an error; the only cut is by time (config.cut's period).
[[nodiscard]] std::unique_ptr<drivers::LidarDecoder> make_livox_decoder(
    const drivers::LidarDecoderConfig& config);

}  // namespace livod::livox
