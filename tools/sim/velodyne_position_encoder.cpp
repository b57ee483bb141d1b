#include "tools/sim/velodyne_position_encoder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>

#include "drivers/velodyne/position_packet.hpp"
#include "drivers/velodyne/wire.hpp"

namespace livod::sim {
namespace {

namespace vel = drivers::velodyne;

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr long kMinTwelveBit = -2048;
constexpr long kMaxTwelveBit = 2047;

// Word tags in the upper nibble, by position in a sensor's group of four.
enum class WordKind : std::uint16_t { kGyro = 0, kTemperature = 1, kAccelX = 2, kAccelY = 3 };

std::uint16_t twelve_bit_word(double value, double per_lsb, WordKind kind) {
  const long counts = std::clamp(std::lround(value / per_lsb), kMinTwelveBit, kMaxTwelveBit);
  return static_cast<std::uint16_t>((static_cast<std::uint16_t>(kind) << 12) |
                                    (static_cast<std::uint16_t>(counts) & 0x0FFF));
}

}  // namespace

Hdl32eMotionWords encode_hdl32e_motion(const Eigen::Vector3d& gyro_rad_s,
                                       const Eigen::Vector3d& accel_m_s2,
                                       const std::array<double, 3>& temperature_c) {
  // The decoder's mapping (position_packet.hpp), solved for the words: in livod's frame
  // gyro = (g1, -g2, -g3) and accel = ((-a2y - a3y)/2, (a1y - a3x)/2, (a1x + a2x)/2), so each
  // sensor reads the components below; both words of an axis carry the same reading.
  const Eigen::Vector3d w = gyro_rad_s * kRadToDeg;
  const Eigen::Vector3d a = accel_m_s2 / kStandardGravity;
  struct Reading {
    double gyro_deg_s, accel_x_g, accel_y_g;
  };
  const std::array<Reading, 3> readings{{
      {w.x(), a.z(), a.y()},
      {-w.y(), a.z(), -a.x()},
      {-w.z(), -a.y(), -a.x()},
  }};
  Hdl32eMotionWords words{};
  for (std::size_t i = 0; i < readings.size(); ++i) {
    const Reading& r = readings[i];
    const std::size_t base = vel::wire::kImuWordsPerSensor * i;
    words[base] = twelve_bit_word(r.gyro_deg_s, vel::kHdlGyroDegPerSecPerLsb, WordKind::kGyro);
    words[base + 1] = twelve_bit_word(temperature_c[i] - vel::kHdlTemperatureOffsetC,
                                      vel::kHdlTemperatureCPerLsb, WordKind::kTemperature);
    words[base + 2] = twelve_bit_word(r.accel_x_g, vel::kHdlAccelGPerLsb, WordKind::kAccelX);
    words[base + 3] = twelve_bit_word(r.accel_y_g, vel::kHdlAccelGPerLsb, WordKind::kAccelY);
  }
  return words;
}

std::vector<std::byte> encode_position_packet(std::uint32_t toh_us,
                                              const Hdl32eMotionWords* motion) {
  std::vector<std::byte> payload(vel::wire::kPositionPacketSize, std::byte{0});
  if (motion != nullptr) {
    for (std::size_t i = 0; i < motion->size(); ++i) {
      vel::wire::put_u16le(payload, vel::wire::kImuWordsOffset + 2 * i, (*motion)[i]);
    }
  }
  vel::wire::put_u32le(payload, vel::wire::kPositionTimestampOffset, toh_us);
  payload[vel::wire::kPpsStatusOffset] = std::byte{0};  // free-running: no PPS
  // A receiver without a fix sends status V; the time fields follow the sensor clock (the hour
  // is unknown to a top-of-hour counter).
  const std::uint32_t s = toh_us / 1'000'000;
  char nmea[96];
  std::snprintf(nmea, sizeof(nmea), "$GPRMC,00%02u%02u,V,,,,,,,,,,N", s / 60 % 60, s % 60);
  unsigned checksum = 0;
  for (const char* p = nmea + 1; *p != '\0'; ++p) checksum ^= static_cast<unsigned char>(*p);
  char full[112];
  const int n = std::snprintf(full, sizeof(full), "%s*%02X\r\n", nmea, checksum);
  std::memcpy(payload.data() + vel::wire::kNmeaOffset, full, static_cast<std::size_t>(n));
  return payload;
}

}  // namespace livod::sim
