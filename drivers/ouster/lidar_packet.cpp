#include "drivers/ouster/lidar_packet.hpp"

namespace livod::drivers::ouster {

PacketError LidarPacket::parse(std::span<const std::byte> bytes, const PacketFormat& format,
                               LidarPacket& out) {
  if (format.layout == nullptr || bytes.size() != format.lidar_packet_size) {
    return PacketError::kWrongSize;
  }
  LidarPacket p;
  p.data_ = bytes.data();
  p.format_ = &format;
  if (!format.legacy_lidar()) {
    // CRC first: a corrupted packet_type byte is corruption, not a foreign packet.
    if (format.lidar_crc && !crc_matches(bytes)) return PacketError::kCrcMismatch;
    p.header_ = read_packet_header(bytes, format.header_type);
    if (p.header_.packet_type != 1) return PacketError::kWrongPacketType;
  }
  // The columns of one packet are consecutive measurements. Anything else means the datagram was
  // spliced together from two packets (e.g. a stale IPv4 fragment) or is corrupt, and placing
  // its pixels by these ids would put points at wrong angles.
  const std::uint32_t first = p.measurement_id(0);
  if (first + format.columns_per_packet > format.columns_per_frame) {
    return PacketError::kMeasurementIdOutOfRange;
  }
  for (std::uint32_t c = 1; c < format.columns_per_packet; ++c) {
    if (p.measurement_id(c) != first + c) return PacketError::kInconsistentMeasurementIds;
  }
  if (format.legacy_lidar()) p.header_.frame_id = p.column_frame_id(0);
  out = p;
  return PacketError::kNone;
}

}  // namespace livod::drivers::ouster
