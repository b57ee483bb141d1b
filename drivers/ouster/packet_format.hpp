#pragma once
// Byte layout of the lidar, IMU and zone packets of one sensor configuration, derived once from
// the metadata. Everything the per-packet decoders need is a precomputed size or offset here.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "drivers/ouster/metadata.hpp"
#include "drivers/ouster/profile.hpp"

namespace livod::drivers::ouster {

// Why a packet was rejected. Every decoder returns one of these instead of throwing.
enum class PacketError : std::uint8_t {
  kNone,
  kWrongSize,                  // length differs from what the metadata's profile implies
  kWrongPacketType,            // header packet_type is not the expected kind
  kCrcMismatch,                // CRC-64/XZ footer does not match the contents
  kMeasurementIdOutOfRange,    // column measurement_id >= columns_per_frame
  kInconsistentMeasurementIds  // columns of one packet are not consecutive (spliced datagram)
};
[[nodiscard]] std::string_view to_string(PacketError error);

enum class PacketKind : std::uint8_t { kLidar, kImu, kZone, kUnknown };

// Whether to verify the CRC-64 footer.
enum class CrcPolicy : std::uint8_t {
  kAuto,    // when the metadata says the firmware writes one (SensorMetadata::*_have_crc)
  kAlways,  // every non-LEGACY packet must carry a valid CRC
  kNever,
};

struct PacketFormat {
  LidarProfile lidar_profile = LidarProfile::kLegacy;
  ImuProfile imu_profile = ImuProfile::kLegacy;
  HeaderType header_type = HeaderType::kStandard;
  const ProfileLayout* layout = nullptr;

  std::uint32_t pixels_per_column = 0;
  std::uint32_t columns_per_packet = 0;
  std::uint32_t columns_per_frame = 0;

  std::size_t packet_header_size = 0;  // 0 (LEGACY) or 32
  std::size_t packet_footer_size = 0;  // 0 (LEGACY) or 32; CRC in its last 8 bytes
  std::size_t column_header_size = 0;  // 16 (LEGACY: ts, measurement_id, frame_id, encoder) or 12
  std::size_t column_footer_size = 0;  // 4 (LEGACY: status) or 0
  std::size_t column_size = 0;
  std::size_t lidar_packet_size = 0;

  // ACCEL32_GYRO32_NMEA: 32 header + 100 NMEA block + n x 36 + 32 footer. n = 0 when the metadata
  // did not report imu_measurements_per_packet: any n that fits the size is accepted then.
  std::uint32_t imu_measurements_per_packet = 1;
  std::size_t imu_packet_size = 48;  // LEGACY size, or the ACCEL32 size when n is known (else 0)
  std::size_t zone_packet_size = 0;  // 680 with the standard header; 0 when no packet header

  bool lidar_crc = false;
  bool imu_crc = false;

  [[nodiscard]] bool legacy_lidar() const { return lidar_profile == LidarProfile::kLegacy; }
  [[nodiscard]] std::uint32_t returns() const { return layout->returns; }
  [[nodiscard]] std::uint64_t frame_id_modulus() const {
    return header_type == HeaderType::kFusa ? (std::uint64_t{1} << 32) : (std::uint64_t{1} << 16);
  }

  [[nodiscard]] static PacketFormat from_metadata(const SensorMetadata& metadata,
                                                  CrcPolicy crc = CrcPolicy::kAuto);
};

inline constexpr std::size_t kLegacyImuPacketSize = 48;
inline constexpr std::size_t kPacketHeaderSize = 32;
inline constexpr std::size_t kPacketFooterSize = 32;
inline constexpr std::size_t kNmeaBlockSize = 100;
inline constexpr std::size_t kImuMeasurementSize = 36;
inline constexpr std::size_t kMaxImuMeasurementsPerPacket = 64;

// Header of non-LEGACY lidar, IMU and zone packets (32 bytes; sensor-protocols.md §3.3).
struct PacketHeader {
  std::uint16_t packet_type = 0;  // 1 lidar, 2 IMU, 3 zone
  std::uint32_t frame_id = 0;
  std::uint32_t init_id = 0;
  std::uint64_t prod_sn = 0;
  std::uint8_t alert_flags = 0;
  std::uint8_t countdown_thermal_shutdown = 0;
  std::uint8_t countdown_shot_limiting = 0;
  std::uint8_t thermal_shutdown = 0;  // 0 normal, 1 imminent
  std::uint8_t shot_limiting = 0;     // 0 normal, 1 imminent, 2..9 = 0-10 % .. 70-80 % reduction
};

// Reads the 32-byte header; `bytes` must hold at least 32 bytes.
[[nodiscard]] PacketHeader read_packet_header(std::span<const std::byte> bytes, HeaderType type);

// Tells lidar, IMU and zone packets apart when they share a port: by packet_type when the packets
// have a header, by size otherwise (a 48-byte LEGACY IMU packet never has a lidar size). Only
// classifies; the decoders still check everything.
[[nodiscard]] PacketKind classify_packet(std::span<const std::byte> bytes,
                                         const PacketFormat& format);

// Checks the CRC-64/XZ in the last 8 bytes of a packet with a footer.
[[nodiscard]] bool crc_matches(std::span<const std::byte> bytes);

// Validates a zone-monitoring packet (size, packet_type 3, CRC when expected).
[[nodiscard]] PacketError check_zone_packet(std::span<const std::byte> bytes,
                                            const PacketFormat& format, PacketHeader& header);

}  // namespace livod::drivers::ouster
