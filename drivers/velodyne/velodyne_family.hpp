#pragma once
// The Velodyne family's descriptor (drivers/lidar_family.hpp): its models, ports, cuts,
// calibration file, `velodyne:` configuration section and decoder factory.

#include "drivers/lidar_family.hpp"

namespace livod::drivers::velodyne {

[[nodiscard]] const LidarFamily& velodyne_family();

}  // namespace livod::drivers::velodyne
