#pragma once
// The Ouster family's descriptor (drivers/lidar_family.hpp): its models, ports, the frame-id cut,
// the metadata file and the decoder factory (ouster_factory.hpp).

#include "drivers/lidar_family.hpp"

namespace livod::drivers::ouster {

[[nodiscard]] const LidarFamily& ouster_family();

}  // namespace livod::drivers::ouster
