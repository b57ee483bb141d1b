#pragma once
// Registry factory for Livox models (drivers/registry.cpp).

#include <memory>

#include "drivers/lidar_decoder.hpp"
#include "drivers/registry.hpp"

namespace livod::livox {

// Builds a LivoxDecoder for config.model (AVIA, HORIZON, TELE-15, MID-40, MID-70, MID-360, HAP).
// Livox sensors need no calibration or metadata files: passing one is an error.
std::unique_ptr<drivers::LidarDecoder> make_livox_decoder(const drivers::DecoderConfig& config);

}  // namespace livod::livox
