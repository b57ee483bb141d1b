#pragma once
// Simulated Velodyne VLP-16 writing its real wire format: 1206-byte data packets (12 blocks of
// two 16-laser firing sequences, 2 mm ranges, top-of-hour microsecond stamps, strongest return)
// at 600 RPM on port 2368, and 512-byte position packets on port 8308 (top-of-hour stamp, PPS
// status, $GPRMC) at 10 Hz. Beam directions are the decoder's own: each packet is first laid out
// with a placeholder range and decoded, so the firing times, azimuth interpolation and laser
// elevations the simulator casts along are exactly those livod's decoder reports.

#include <memory>

#include "tools/sim/lidar_registry.hpp"

namespace livod::sim {

std::unique_ptr<SimLidar> make_sim_vlp16(const SimLidarOptions& options);

}  // namespace livod::sim
