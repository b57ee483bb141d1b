#pragma once
// Livox point-cloud and IMU data packets, SDK1 (18-byte header, sensor-protocols.md 1.3) and SDK2
// (36-byte header, 2.3): pure decoders over bytes into a fixed-capacity packet (no allocation),
// and encoders used by the simulator and the tests. Units are converted here, once: mm -> m,
// 0.01 deg -> rad, g -> m/s^2.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "core/units.hpp"

namespace livod::livox {

inline constexpr std::size_t kMaxPointsPerPacket = 100;
inline constexpr std::size_t kSdk1HeaderBytes = 18;
inline constexpr std::size_t kSdk2HeaderBytes = 36;
inline constexpr std::uint8_t kSdk1Version = 5;  // byte 0 of every SDK1 data packet
inline constexpr std::uint8_t kSdk2Version = 0;

struct LivoxPoint {
  float x = 0, y = 0, z = 0;  // metres, LiDAR frame (x forward)
  std::uint8_t reflectivity = 0;
  std::uint8_t tag = 0;
  std::uint8_t return_index = 0;  // 0..2 for multi-return packets
  std::uint8_t line = 0;
  std::int32_t t_offset_ns = 0;  // from the packet timestamp (time of the first point)
  bool valid = false;            // false: (0,0,0) / depth 0 = no return
};

struct LivoxPacket {
  enum class Kind : std::uint8_t { kPoints, kImu };
  Kind kind = Kind::kPoints;
  std::uint8_t data_type = 0;
  std::uint8_t time_type = 0;     // SDK1 timestamp_type / SDK2 time_type
  std::int64_t timestamp_ns = 0;  // sensor clock, ns (SDK1 UTC type converted to epoch ns)
  std::uint32_t status = 0;       // SDK1 err_code
  std::uint16_t udp_cnt = 0;      // SDK2 only
  std::uint8_t frame_cnt = 0;     // SDK2 only
  std::int32_t span_ns = 0;       // time of the last point minus the first
  std::uint16_t count = 0;
  std::array<LivoxPoint, kMaxPointsPerPacket> points{};
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
};

// kBadVersion: the version byte is not the protocol's (SDK1 data packets carry 5, SDK2 0), i.e.
// the datagram is not a Livox data packet at all (another sensor on the port).
enum class DecodeError {
  kNone,
  kTooShort,
  kUnknownDataType,
  kLengthMismatch,
  kBadCrc,
  kBadTime,
  kBadVersion,
};
inline constexpr std::size_t kDecodeErrorKinds = 7;
const char* to_string(DecodeError e);

// SDK1: `point_interval_ns` is 10000 for Mid-40/70 and 4167 for Avia/Horizon/Tele-15;
// `lines` is 1 for Mid-40/70 and 6 for the others. A datagram is accepted only if it is an SDK1
// data packet: version byte 5, a known data type, a defined timestamp type (0, 1, 3, 4) and
// exactly the length of that data type (18 + N x point size); anything else (another sensor's
// traffic on the port) is an error and yields no points.
DecodeError decode_sdk1(std::span<const std::byte> payload, std::uint32_t point_interval_ns,
                        std::uint8_t lines, LivoxPacket& out);

// SDK2: `lines` is 4 for Mid-360 and 6 for HAP. A zero CRC field means "not computed" (real
// Mid-360 point packets carry 0) and is accepted; otherwise the CRC-32 must match. The version
// byte must be 0, the length field must equal the datagram's length, and that length must be
// exactly the header plus dot_num points of the data type (IMU: one sample).
DecodeError decode_sdk2(std::span<const std::byte> payload, std::uint8_t lines, LivoxPacket& out);

// Encoders. Points are given in metres; encoding quantises to the wire format's resolution.
struct Sdk1Header {
  std::uint8_t data_type = 2;
  std::uint8_t timestamp_type = 0;
  std::uint64_t timestamp = 0;  // raw field (ns for types 0/1/4)
  std::uint32_t status = 0;
  std::uint8_t slot = 1;
  std::uint8_t lidar_id = 1;
};
// data_type 2 (extended cartesian, 96 points), 4 (dual, 48 x 2) or 6 (IMU).
std::vector<std::byte> encode_sdk1_points(const Sdk1Header& header,
                                          std::span<const LivoxPoint> points);
std::vector<std::byte> encode_sdk1_imu(const Sdk1Header& header, const Eigen::Vector3d& gyro_rad_s,
                                       const Eigen::Vector3d& accel_m_s2);

struct Sdk2Header {
  std::uint8_t data_type = 1;
  std::uint8_t time_type = 0;
  std::uint64_t timestamp_ns = 0;
  std::uint16_t time_interval_100ns = 0;  // last point minus first, 0.1 us
  std::uint16_t udp_cnt = 0;
  std::uint8_t frame_cnt = 0;
  bool write_crc = false;  // real Mid-360 point packets carry 0, IMU packets a real CRC
};
// data_type 1 (cartesian i32 mm) or 2 (cartesian i16 cm); 0 = IMU.
std::vector<std::byte> encode_sdk2_points(const Sdk2Header& header,
                                          std::span<const LivoxPoint> points);
std::vector<std::byte> encode_sdk2_imu(const Sdk2Header& header, const Eigen::Vector3d& gyro_rad_s,
                                       const Eigen::Vector3d& accel_m_s2);

}  // namespace livod::livox
