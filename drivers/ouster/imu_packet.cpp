#include "drivers/ouster/imu_packet.hpp"

#include <cmath>

#include "core/little_endian.hpp"
#include "core/units.hpp"

namespace livod::drivers::ouster {
namespace {

Eigen::Vector3d load_vec3f(const std::byte* p) {
  return {load_le<float>(p), load_le<float>(p + 4), load_le<float>(p + 8)};
}

constexpr std::size_t kNmeaTimestampSize = 8;

PacketError parse_legacy(std::span<const std::byte> bytes, ImuPacket& out) {
  if (bytes.size() != kLegacyImuPacketSize) return PacketError::kWrongSize;
  const std::byte* p = bytes.data();
  ImuMeasurement& m = out.measurements[0];
  m.sys_timestamp_ns = load_le<std::uint64_t>(p);
  m.accel_timestamp_ns = load_le<std::uint64_t>(p + 8);
  m.timestamp_ns = load_le<std::uint64_t>(p + 16);  // gyro_ts
  m.measurement_id = 0;
  m.accel_m_s2 = load_vec3f(p + 24) * kStandardGravity;
  m.gyro_rad_s = load_vec3f(p + 36) * kDegToRad;
  m.valid = m.accel_m_s2.allFinite() && m.gyro_rad_s.allFinite();
  out.header = PacketHeader{};
  out.nmea_timestamp_ns = 0;
  out.nmea_sentence = {};
  out.count = 1;
  return PacketError::kNone;
}

PacketError parse_accel32_gyro32_nmea(std::span<const std::byte> bytes, const PacketFormat& format,
                                      ImuPacket& out) {
  constexpr std::size_t kFixed = kPacketHeaderSize + kNmeaBlockSize + kPacketFooterSize;
  const std::size_t n = bytes.size();
  if (n < kFixed + kImuMeasurementSize || (n - kFixed) % kImuMeasurementSize != 0) {
    return PacketError::kWrongSize;
  }
  const std::size_t count = (n - kFixed) / kImuMeasurementSize;
  if (count > kMaxImuMeasurementsPerPacket ||
      (format.imu_measurements_per_packet != 0 && count != format.imu_measurements_per_packet)) {
    return PacketError::kWrongSize;
  }
  if (format.imu_crc && !crc_matches(bytes)) return PacketError::kCrcMismatch;
  out.header = read_packet_header(bytes, format.header_type);
  if (out.header.packet_type != 2) return PacketError::kWrongPacketType;

  const std::byte* p = bytes.data();
  out.nmea_timestamp_ns = load_le<std::uint64_t>(p + kPacketHeaderSize);
  const char* sentence = reinterpret_cast<const char*>(p + kPacketHeaderSize + kNmeaTimestampSize);
  std::size_t len = kNmeaBlockSize - kNmeaTimestampSize;
  while (len > 0 && sentence[len - 1] == '\0') --len;
  out.nmea_sentence = std::string_view(sentence, len);

  const std::byte* meas = p + kPacketHeaderSize + kNmeaBlockSize;
  for (std::size_t i = 0; i < count; ++i, meas += kImuMeasurementSize) {
    ImuMeasurement& m = out.measurements[i];
    m.timestamp_ns = load_le<std::uint64_t>(meas);
    m.accel_timestamp_ns = m.timestamp_ns;
    m.sys_timestamp_ns = 0;
    m.measurement_id = load_le<std::uint16_t>(meas + 8);
    const std::uint16_t status = load_le<std::uint16_t>(meas + 10);
    m.accel_m_s2 = load_vec3f(meas + 12);  // already m/s^2
    m.gyro_rad_s = load_vec3f(meas + 24);  // already rad/s
    m.valid = (status & 1U) != 0 && m.accel_m_s2.allFinite() && m.gyro_rad_s.allFinite();
  }
  out.count = count;
  return PacketError::kNone;
}

}  // namespace

PacketError parse_imu_packet(std::span<const std::byte> bytes, const PacketFormat& format,
                             ImuPacket& out) {
  out.count = 0;
  return format.imu_profile == ImuProfile::kLegacy ? parse_legacy(bytes, out)
                                                   : parse_accel32_gyro32_nmea(bytes, format, out);
}

}  // namespace livod::drivers::ouster
