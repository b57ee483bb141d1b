#include "drivers/velodyne/position_packet.hpp"

#include <numbers>

#include "core/units.hpp"
#include "drivers/velodyne/wire.hpp"

namespace livod::drivers::velodyne {
namespace {

int twelve_bit_signed(std::uint16_t word) {
  const int v = word & 0x0FFF;
  return (v & 0x0800) != 0 ? v - 0x1000 : v;
}

}  // namespace

PositionDecodeResult decode_position_packet(std::span<const std::byte> payload) {
  PositionDecodeResult result;
  if (payload.size() != wire::kPositionPacketSize) return result;
  auto& p = result.packet;
  p.toh_us = wire::u32le(payload, wire::kPositionTimestampOffset);
  if (p.toh_us >= wire::kMicrosecondsPerHour) {
    result.status = PositionDecodeStatus::kBadTimestamp;
    return result;
  }
  p.pps_raw = wire::u8(payload, wire::kPpsStatusOffset);
  if (p.pps_raw <= 3) p.pps = static_cast<PpsStatus>(p.pps_raw);

  for (std::size_t i = 0; i < wire::kImuSensors; ++i) {
    const std::size_t base = wire::kImuWordsOffset + 2 * wire::kImuWordsPerSensor * i;
    auto& m = p.motion[i];
    m.gyro_deg_s = twelve_bit_signed(wire::u16le(payload, base)) * kHdlGyroDegPerSecPerLsb;
    m.temperature_c = twelve_bit_signed(wire::u16le(payload, base + 2)) * kHdlTemperatureCPerLsb +
                      kHdlTemperatureOffsetC;
    m.accel_x_g = twelve_bit_signed(wire::u16le(payload, base + 4)) * kHdlAccelGPerLsb;
    m.accel_y_g = twelve_bit_signed(wire::u16le(payload, base + 6)) * kHdlAccelGPerLsb;
  }

  // The sentence is NUL-terminated; without a NUL it runs to the end of the packet.
  const auto text = payload.subspan(wire::kNmeaOffset);
  std::size_t length = 0;
  while (length < text.size() && text[length] != std::byte{0}) ++length;
  p.nmea = std::string_view(reinterpret_cast<const char*>(text.data()), length);
  p.rmc = parse_rmc(p.nmea);
  result.status = PositionDecodeStatus::kOk;
  return result;
}

ImuVectors hdl32e_imu_in_lidar_frame(const PositionPacket& packet) {
  const auto& s1 = packet.motion[0];
  const auto& s2 = packet.motion[1];
  const auto& s3 = packet.motion[2];
  // Velodyne sensor frame: x right, y forward (azimuth 0), z up.
  const Eigen::Vector3d gyro_velodyne(s2.gyro_deg_s, s1.gyro_deg_s, -s3.gyro_deg_s);
  const Eigen::Vector3d accel_velodyne((-s1.accel_y_g + s3.accel_x_g) / 2.0,
                                       (-s2.accel_y_g - s3.accel_y_g) / 2.0,
                                       (s1.accel_x_g + s2.accel_x_g) / 2.0);
  // livod LiDAR frame: x forward = y_velodyne, y left = -x_velodyne, z up.
  const auto to_lidar = [](const Eigen::Vector3d& v) {
    return Eigen::Vector3d(v.y(), -v.x(), v.z());
  };
  ImuVectors out;
  out.gyro_rad_s = to_lidar(gyro_velodyne) * kDegToRad;
  out.accel_m_s2 = to_lidar(accel_velodyne) * kStandardGravity;
  return out;
}

}  // namespace livod::drivers::velodyne
