#pragma once
// Velodyne position packets as the simulator writes them (512 B, port 8308; §4.2 of
// shared/docs/sensor-protocols.md, docs/drivers/velodyne.md): the inverse of
// drivers/velodyne/position_packet.cpp. Byte 198 carries the top-of-hour microseconds, byte 202
// the PPS status (0: no PPS, a free-running clock), byte 206 a $GPRMC without fix (status V)
// whose time of day follows the sensor clock, and, on the HDL-32E, bytes 14..37 the three motion
// sensors' words.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace livod::sim {

// The twelve words of the HDL-32E's motion sensors (gyro, temperature, accel x, accel y of
// sensors 1..3), in wire order.
using Hdl32eMotionWords = std::array<std::uint16_t, 12>;

// Words that drivers::velodyne::hdl32e_imu_in_lidar_frame decodes to `gyro_rad_s` and
// `accel_m_s2` (livod's LiDAR frame: x forward, y left, z up; SI) within the quantisation: half
// an LSB per word, i.e. 0.0488 deg/s per gyro axis and 0.61 mg per acceleration axis (each axis
// is the mean of two accelerometer words that carry the same value). Values beyond the 12-bit
// range saturate, as the sensor's converters do. The upper nibble of each word holds its index
// in the sensor's group (0 gyro, 1 temperature, 2 accel x, 3 accel y), as the real capture shows;
// decoders ignore it.
[[nodiscard]] Hdl32eMotionWords encode_hdl32e_motion(const Eigen::Vector3d& gyro_rad_s,
                                                     const Eigen::Vector3d& accel_m_s2,
                                                     const std::array<double, 3>& temperature_c);

// A 512-byte position packet stamped `toh_us` (microseconds since the top of the hour), without
// PPS and without GPS fix; `motion`, when given, fills the HDL-32E motion words (other models
// leave them zero).
[[nodiscard]] std::vector<std::byte> encode_position_packet(std::uint32_t toh_us,
                                                            const Hdl32eMotionWords* motion);

}  // namespace livod::sim
