#pragma once
// Ouster IMU packets, converted to SI on the way out (sensor-protocols.md §3.4):
//   LEGACY (48 B, no header): sys/accel/gyro timestamps, accel in g, gyro in deg/s.
//   ACCEL32_GYRO32_NMEA (FW >= 3.2): 32 B header, NMEA block, n x 36 B measurements already in
//   m/s^2 and rad/s, 32 B footer with CRC-64.
// The measurements stay in the IMU's own axes (T_sensor_imu in the metadata places them).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <string_view>

#include "core/units.hpp"
#include "drivers/ouster/packet_format.hpp"

namespace livod::drivers::ouster {

struct ImuMeasurement {
  // The instant the sample describes, sensor clock ns: gyro_ts for LEGACY (ouster-ros stamps
  // LEGACY IMU messages with it; accel and gyro are sampled within microseconds), the
  // measurement's own timestamp for ACCEL32_GYRO32_NMEA.
  std::uint64_t timestamp_ns = 0;
  std::uint64_t accel_timestamp_ns = 0;  // LEGACY only (else = timestamp_ns)
  std::uint64_t sys_timestamp_ns = 0;    // LEGACY only (else 0)
  std::uint16_t measurement_id = 0;      // ACCEL32_GYRO32_NMEA only
  bool valid = false;                    // status bit 0 (LEGACY samples are always valid)
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
};

struct ImuPacket {
  PacketHeader header;                  // zero for LEGACY
  std::uint64_t nmea_timestamp_ns = 0;  // ACCEL32_GYRO32_NMEA only
  std::string_view nmea_sentence;       // view into the packet bytes, trailing NULs removed
  std::size_t count = 0;                // measurements filled
  std::array<ImuMeasurement, kMaxImuMeasurementsPerPacket> measurements{};
};

// Decodes one IMU packet into `out` (no allocation). Checks the size, the packet type and the
// CRC when the format expects one.
[[nodiscard]] PacketError parse_imu_packet(std::span<const std::byte> bytes,
                                           const PacketFormat& format, ImuPacket& out);

}  // namespace livod::drivers::ouster
