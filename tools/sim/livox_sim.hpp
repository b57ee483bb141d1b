#pragma once
// Simulated Livox LiDARs writing their real wire formats: Avia (SDK1, 6-line non-repetitive
// rosette over 70.4 x 77.2 deg, 240 kpts/s, extended-cartesian packets of 96 points, internal IMU
// in g at 200 Hz) and Mid-360 (SDK2, 360 x (-7..52) deg, 4 lines, 200 kpts/s, cartesian packets
// of 96 points with time_interval, internal IMU at 200 Hz on its own port).

#include <memory>

#include "tools/sim/lidar_registry.hpp"

namespace livod::sim {

std::unique_ptr<SimLidar> make_sim_avia(const SimLidarOptions& options);
std::unique_ptr<SimLidar> make_sim_mid360(const SimLidarOptions& options);

}  // namespace livod::sim
