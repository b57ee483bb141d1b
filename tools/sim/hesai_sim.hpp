#pragma once
// Simulated Hesai PandarXT-32 writing its real wire format: 1080-byte point cloud packets of 8
// single-return blocks (strongest return, 4 mm distance unit, UDP sequence on) at 600 RPM on
// port 2368, a firing round every 50 us (0.18 degree), the tail stamped with UTC date and
// microseconds from the sensor clock (a PTP-disciplined unit: SimLidarOptions::clock reads UTC;
// offset_s is where it starts). Beams are the decoder's own (drivers/hesai/geometry.hpp with the
// simulated unit's angle correction file, written beside the capture as <stem>.csv), and each
// return is cast at its firing time (drivers/hesai/firing_timing.hpp). No internal IMU.

#include <memory>

#include "tools/sim/lidar_registry.hpp"

namespace livod::sim {

std::unique_ptr<SimLidar> make_sim_pandar_xt32(const SimLidarOptions& options);

}  // namespace livod::sim
