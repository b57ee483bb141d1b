#pragma once
// Simulated Ouster OS1-64 and OS1-128 writing their real wire formats (sensor-protocols.md §3):
// lidar mode 1024x10, profile RNG19_RFL8_SIG16_NIR16, 16 columns per 12 544 / 24 832-byte packet
// on UDP 7502 with a 32-byte header (packet_type 1, frame_id, init_id, prod_sn) and a 32-byte
// footer ending in a CRC-64/XZ (the metadata says firmware 2.5.2, which writes one); LEGACY 48-byte
// IMU packets (accel in g, gyro in deg/s) at the mount's IMU rate on UDP 7503. write_side_files()
// writes the firmware-2.5 nested metadata JSON the decoder needs (`<stem>.json`).
//
// Timing. The motor is phase-locked to the sensor's own oscillator, so column timestamps are
// evenly spaced by 1e9 / (1024 * 10) ns on the *sensor* clock: global column n (counted from
// scenario time 0, frame n / 1024, measurement_id n % 1024) is measured at scenario time
// n * 1e-4 / 1.024 / (1 + skew_ppm * 1e-6) and stamped with the SensorClock at that time. The
// IMU samples on the same clock: LEGACY sys_ts every 1 / rate, accel_ts 213.92 us and gyro_ts
// 435.3 us after it (the offsets of a real OS1 capture); the sample describes the gyro instant.
// run(t0, t1) emits what the sensor sends in [t0, t1): a lidar packet leaves with its last column,
// so a run over whole multiples of 0.1 s gives whole frames. frame_id starts at 65494 and wraps
// to 0 at frame 42 (4.2 s); init_id is constant (from the seed).
//
// Geometry. Each pixel is ray-cast from its beam origin along exactly the direction the decoder's
// XYZ model (§3.6) gives that pixel, so decoding returns the simulated point: the reported truth is
// the §3.6 point of the millimetre-quantised wire range, in the Ouster sensor frame.

#include <memory>

#include "tools/sim/lidar_registry.hpp"

namespace livod::sim {

std::unique_ptr<SimLidar> make_sim_os1_64(const SimLidarOptions& options);
std::unique_ptr<SimLidar> make_sim_os1_128(const SimLidarOptions& options);

}  // namespace livod::sim
