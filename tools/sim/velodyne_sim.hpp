#pragma once
// Simulated Velodyne LiDARs writing their real wire format: 1206-byte data packets (12 blocks,
// 2 mm ranges, top-of-hour microsecond stamps, strongest return) at 600 RPM on port 2368, and
// 512-byte position packets on port 8308 (top-of-hour stamp, no PPS, $GPRMC without fix; see
// velodyne_position_encoder.hpp). Beam directions are the decoder's own: each packet is first
// laid out with a placeholder range and decoded, so the firing times, azimuth interpolation and
// laser elevations the simulator casts along are exactly those livod's decoder reports.
//
// VLP-16: blocks of two 16-laser firing sequences (55.296 us each), position packets at 10 Hz,
// no IMU. HDL-32E: blocks of one 32-laser sequence (32 x 1.152 us firings in a 46.08 us cycle,
// the decoder's firing table and built-in calibration), factory byte 0x21, and position packets
// every 4.988 ms (200.5 Hz, the mean spacing of the real monterey capture, whose packets come
// irregularly, 1.3 to 9.7 ms apart; the simulator sends them evenly) carrying the internal IMU:
// its three gyro / temperature / two-axis accelerometer sensors, quantised as the real words
// (0.09766 deg/s, 1.221 mg) and laid out so that the decoder's hdl32e_imu_in_lidar_frame returns
// the simulated specific force and rate in the LiDAR frame. The IMU sits at the LiDAR origin with
// the LiDAR's axes (that is the frame the decoder reports it in); its sample time is the position
// packet's stamp and its rate is the packet rate, whatever SimLidarOptions::imu_noise.rate_hz
// says. With SimLidarOptions::imu false the motion words are zero (the decoder then emits no IMU).

#include <memory>

#include "tools/sim/lidar_registry.hpp"

namespace livod::sim {

std::unique_ptr<SimLidar> make_sim_vlp16(const SimLidarOptions& options);
std::unique_ptr<SimLidar> make_sim_hdl32e(const SimLidarOptions& options);

}  // namespace livod::sim
