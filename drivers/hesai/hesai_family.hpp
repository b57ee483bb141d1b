#pragma once
// The Hesai family's descriptor (drivers/lidar_family.hpp): PandarXT-32 and Pandar40P, their
// ports, cuts, the angle correction file, the `hesai:` configuration section and the factory.

#include "drivers/lidar_family.hpp"

namespace livod::drivers::hesai {

[[nodiscard]] const LidarFamily& hesai_family();

}  // namespace livod::drivers::hesai
