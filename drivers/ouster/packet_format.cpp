#include "drivers/ouster/packet_format.hpp"

#include "core/little_endian.hpp"
#include "drivers/ouster/crc64.hpp"

namespace livod::drivers::ouster {
namespace {

std::uint64_t load_bytes_le(const std::byte* p, std::size_t n) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < n; ++i)
    v |= std::uint64_t{static_cast<std::uint8_t>(p[i])} << (8 * i);
  return v;
}

constexpr std::size_t kZoneTimestampAndHashSize = 8 + 32;
constexpr std::size_t kZoneCount = 16;
constexpr std::size_t kZoneMeasurementSize = 36;

}  // namespace

std::string_view to_string(PacketError error) {
  switch (error) {
    case PacketError::kNone:
      return "ok";
    case PacketError::kWrongSize:
      return "wrong size";
    case PacketError::kWrongPacketType:
      return "wrong packet type";
    case PacketError::kCrcMismatch:
      return "CRC mismatch";
    case PacketError::kMeasurementIdOutOfRange:
      return "measurement id out of range";
    case PacketError::kInconsistentMeasurementIds:
      return "inconsistent measurement ids";
  }
  return "unknown";
}

PacketFormat PacketFormat::from_metadata(const SensorMetadata& metadata, CrcPolicy crc) {
  const DataFormat& df = metadata.format;
  PacketFormat f;
  f.lidar_profile = df.udp_profile_lidar;
  f.imu_profile = df.udp_profile_imu;
  f.header_type = df.header_type;
  f.layout = &profile_layout(df.udp_profile_lidar);
  f.pixels_per_column = df.pixels_per_column;
  f.columns_per_packet = df.columns_per_packet;
  f.columns_per_frame = df.columns_per_frame;

  const bool legacy = f.legacy_lidar();
  f.packet_header_size = legacy ? 0 : kPacketHeaderSize;
  f.packet_footer_size = legacy ? 0 : kPacketFooterSize;
  f.column_header_size = legacy ? 16 : 12;
  f.column_footer_size = legacy ? 4 : 0;
  f.column_size = f.column_header_size + f.pixels_per_column * f.layout->channel_block_size +
                  f.column_footer_size;
  f.lidar_packet_size =
      f.packet_header_size + f.columns_per_packet * f.column_size + f.packet_footer_size;

  if (f.imu_profile == ImuProfile::kLegacy) {
    f.imu_measurements_per_packet = 1;
    f.imu_packet_size = kLegacyImuPacketSize;
  } else {
    f.imu_measurements_per_packet = df.imu_measurements_per_packet;
    f.imu_packet_size = f.imu_measurements_per_packet == 0
                            ? 0
                            : kPacketHeaderSize + kNmeaBlockSize +
                                  f.imu_measurements_per_packet * kImuMeasurementSize +
                                  kPacketFooterSize;
  }
  // Zone packets exist only with a packet header (zone monitoring is a FW 3.2 feature).
  const bool has_header = !legacy || f.imu_profile != ImuProfile::kLegacy;
  f.zone_packet_size = has_header ? kPacketHeaderSize + kZoneTimestampAndHashSize +
                                        kZoneCount * kZoneMeasurementSize + kPacketFooterSize
                                  : 0;

  switch (crc) {
    case CrcPolicy::kAuto:
      f.lidar_crc = metadata.lidar_packets_have_crc();
      f.imu_crc = metadata.imu_packets_have_crc();
      break;
    case CrcPolicy::kAlways:
      f.lidar_crc = !legacy;
      f.imu_crc = f.imu_profile != ImuProfile::kLegacy;
      break;
    case CrcPolicy::kNever:
      break;
  }
  return f;
}

PacketHeader read_packet_header(std::span<const std::byte> bytes, HeaderType type) {
  const std::byte* p = bytes.data();
  PacketHeader h;
  if (type == HeaderType::kFusa) {
    // type 8 b, init_id 24 b, frame_id 32 b at bytes 4-7, alert byte 8, serial at bits 88-127.
    h.packet_type = static_cast<std::uint8_t>(p[0]);
    h.init_id = static_cast<std::uint32_t>(load_bytes_le(p + 1, 3));
    h.frame_id = load_le<std::uint32_t>(p + 4);
    h.alert_flags = static_cast<std::uint8_t>(p[8]);
    h.prod_sn = load_bytes_le(p + 11, 5);
  } else {
    h.packet_type = load_le<std::uint16_t>(p);
    h.frame_id = load_le<std::uint16_t>(p + 2);
    h.init_id = static_cast<std::uint32_t>(load_bytes_le(p + 4, 3));
    h.prod_sn = load_bytes_le(p + 7, 5);
    h.alert_flags = static_cast<std::uint8_t>(p[12]);
  }
  h.countdown_thermal_shutdown = static_cast<std::uint8_t>(p[16]);
  h.countdown_shot_limiting = static_cast<std::uint8_t>(p[17]);
  h.thermal_shutdown = static_cast<std::uint8_t>(p[18]) & 0x0FU;
  h.shot_limiting = static_cast<std::uint8_t>(p[19]) & 0x0FU;
  return h;
}

PacketKind classify_packet(std::span<const std::byte> bytes, const PacketFormat& format) {
  const std::size_t n = bytes.size();
  // A LEGACY IMU packet has no header: its first bytes are a timestamp and may look like any
  // packet_type, so its size decides first. No lidar or zone packet is 48 bytes long.
  if (format.imu_profile == ImuProfile::kLegacy && n == kLegacyImuPacketSize)
    return PacketKind::kImu;
  if (format.legacy_lidar() && n == format.lidar_packet_size) return PacketKind::kLidar;
  if (n < kPacketHeaderSize + kPacketFooterSize) return PacketKind::kUnknown;
  const std::uint16_t type = read_packet_header(bytes, format.header_type).packet_type;
  switch (type) {
    case 1:
      return format.legacy_lidar() ? PacketKind::kUnknown : PacketKind::kLidar;
    case 2:
      return format.imu_profile == ImuProfile::kLegacy ? PacketKind::kUnknown : PacketKind::kImu;
    case 3:
      return PacketKind::kZone;
    default:
      return PacketKind::kUnknown;
  }
}

bool crc_matches(std::span<const std::byte> bytes) {
  if (bytes.size() < 8) return false;
  const std::size_t body = bytes.size() - 8;
  return crc64_xz(bytes.first(body)) == load_le<std::uint64_t>(bytes.data() + body);
}

PacketError check_zone_packet(std::span<const std::byte> bytes, const PacketFormat& format,
                              PacketHeader& header) {
  if (format.zone_packet_size == 0 || bytes.size() != format.zone_packet_size) {
    return PacketError::kWrongSize;
  }
  // Zone packets come from the same firmware as the IMU/lidar packets; use whichever says CRC.
  if ((format.lidar_crc || format.imu_crc) && !crc_matches(bytes)) return PacketError::kCrcMismatch;
  header = read_packet_header(bytes, format.header_type);
  if (header.packet_type != 3) return PacketError::kWrongPacketType;
  return PacketError::kNone;
}

}  // namespace livod::drivers::ouster
