#pragma once
// Velodyne position / telemetry packets (512 B payload, port 8308; §4.2 of
// shared/docs/sensor-protocols.md): top-of-hour timestamp, PPS status, the NMEA sentence from
// the GPS input and, on the HDL-32E, three gyro/temperature/2-axis-accelerometer sensors.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "core/units.hpp"
#include "drivers/velodyne/nmea.hpp"

namespace livod::drivers::velodyne {

enum class PpsStatus : std::uint8_t { kAbsent = 0, kSynchronizing = 1, kLocked = 2, kError = 3 };

// Scale factors of the HDL-32E motion words (12-bit two's complement): HDL-32E user's manual,
// positioning packet (Figure B3); VeloView vtkVelodyneHDLPositionReader.
inline constexpr double kHdlGyroDegPerSecPerLsb = 0.09766;
inline constexpr double kHdlTemperatureCPerLsb = 0.1453;
inline constexpr double kHdlTemperatureOffsetC = 25.0;
inline constexpr double kHdlAccelGPerLsb = 0.001221;

// One of the HDL-32E's three motion sensors, converted from 12-bit two's complement words with
// the scale factors above.
struct HdlMotionSensor {
  double gyro_deg_s = 0.0;     // 0.09766 deg/s per LSB
  double temperature_c = 0.0;  // 0.1453 C per LSB + 25 C
  double accel_x_g = 0.0;      // 0.001221 g per LSB
  double accel_y_g = 0.0;
};

struct PositionPacket {
  std::uint32_t toh_us = 0;               // microseconds since the top of the hour
  std::uint8_t pps_raw = 0;               // byte 202 as sent
  std::optional<PpsStatus> pps;           // nullopt if byte 202 is not 0..3
  std::string_view nmea;                  // the sentence, without the NUL; views the payload
  std::optional<RmcFix> rmc;              // parsed when the sentence is a well-formed RMC
  std::array<HdlMotionSensor, 3> motion;  // meaningful on the HDL-32E only
};

enum class PositionDecodeStatus : std::uint8_t { kOk, kBadLength, kBadTimestamp };

struct PositionDecodeResult {
  PositionDecodeStatus status = PositionDecodeStatus::kBadLength;
  PositionPacket packet;
};

// Pure: no allocation; the result's `nmea` views `payload`.
[[nodiscard]] PositionDecodeResult decode_position_packet(std::span<const std::byte> payload);

// The HDL-32E motion sensors as one IMU in livod's LiDAR frame (x forward, y left, z up), SI
// units. Axis assignment (docs/drivers/velodyne.md): in Velodyne's sensor frame (x right,
// y forward = azimuth 0, z up), gyro 2 is the x rate, gyro 1 the y rate and -gyro 3 the z rate;
// each acceleration axis is the mean of the two accelerometer axes that measure it:
// x = (-accel1_y + accel3_x)/2, y = (-accel2_y - accel3_y)/2, z = (accel1_x + accel2_x)/2
// (sensors numbered from 1, as in the manual's Figure B2). Gravity reads +9.8 m/s^2 on z for an
// upright sensor, which the monterey capture confirms.
struct ImuVectors {
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
};
[[nodiscard]] ImuVectors hdl32e_imu_in_lidar_frame(const PositionPacket& packet);

}  // namespace livod::drivers::velodyne
