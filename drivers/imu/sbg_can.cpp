#include "drivers/imu/sbg_can.hpp"

#include <algorithm>
#include <cmath>

namespace livod::imu {
namespace {

constexpr double kAccelLsb = 0.01;  // m/s^2 per count
constexpr double kGyroLsb = 0.001;  // rad/s per count
constexpr double kTempLsb = 0.01;   // degC per count
constexpr std::int64_t kCounterSpanUs = std::int64_t{1} << 32;

std::int16_t read_i16(const std::array<std::uint8_t, 8>& d, int offset) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(d[offset]) |
                                   static_cast<std::uint16_t>(d[offset + 1] << 8));
}

void write_i16(std::array<std::uint8_t, 8>& d, int offset, double value, double lsb) {
  const long counts = std::clamp(std::lround(value / lsb), -32768L, 32767L);
  const auto u = static_cast<std::uint16_t>(static_cast<std::int16_t>(counts));
  d[offset] = static_cast<std::uint8_t>(u & 0xFF);
  d[offset + 1] = static_cast<std::uint8_t>(u >> 8);
}

Eigen::Vector3d read_vec(const std::array<std::uint8_t, 8>& d, double lsb) {
  return {read_i16(d, 0) * lsb, read_i16(d, 2) * lsb, read_i16(d, 4) * lsb};
}

}  // namespace

std::optional<SbgSample> SbgCanDecoder::on_frame(const CanPayload& frame) {
  if (frame.id != ids_.info && frame.id != ids_.accel && frame.id != ids_.gyro) return std::nullopt;
  ++counters_.frames;
  if (frame.id == ids_.info) {
    if (frame.len < 8) {
      ++counters_.malformed;
      return std::nullopt;
    }
    if (have_info_) ++counters_.incomplete;  // the previous sample never got its GYRO frame
    const std::uint32_t raw = static_cast<std::uint32_t>(frame.data[0]) |
                              (static_cast<std::uint32_t>(frame.data[1]) << 8) |
                              (static_cast<std::uint32_t>(frame.data[2]) << 16) |
                              (static_cast<std::uint32_t>(frame.data[3]) << 24);
    if (seen_counter_ && raw < last_raw_us_ && last_raw_us_ - raw > 0x80000000U) {
      wrap_offset_us_ += kCounterSpanUs;
      ++counters_.counter_wraps;
    }
    seen_counter_ = true;
    last_raw_us_ = raw;
    pending_ = SbgSample{};
    pending_.imu.stamp.sensor = SensorTime((wrap_offset_us_ + raw) * 1000);
    pending_.imu.stamp.host = HostTime(frame.rx_time_ns);
    pending_.status = static_cast<std::uint16_t>(frame.data[4] | (frame.data[5] << 8));
    pending_.temperature_c = read_i16(frame.data, 6) * kTempLsb;
    have_info_ = true;
    have_accel_ = false;
    return std::nullopt;
  }
  if (frame.len < 6) {
    ++counters_.malformed;
    return std::nullopt;
  }
  if (!have_info_) return std::nullopt;  // joined mid-sample: wait for the next INFO frame
  if (frame.id == ids_.accel) {
    pending_.imu.accel_m_s2 = read_vec(frame.data, kAccelLsb);
    have_accel_ = true;
    return std::nullopt;
  }
  // GYRO closes the sample.
  have_info_ = false;
  if (!have_accel_) {
    ++counters_.incomplete;
    return std::nullopt;
  }
  pending_.imu.gyro_rad_s = read_vec(frame.data, kGyroLsb);
  ++counters_.samples;
  return pending_;
}

std::array<CanPayload, 3> encode_sbg_sample(std::uint32_t device_time_us,
                                            const Eigen::Vector3d& accel_m_s2,
                                            const Eigen::Vector3d& gyro_rad_s, double temperature_c,
                                            const SbgCanIds& ids) {
  std::array<CanPayload, 3> frames{};
  frames[0].id = ids.info;
  frames[0].len = 8;
  for (int i = 0; i < 4; ++i) {
    frames[0].data[i] = static_cast<std::uint8_t>((device_time_us >> (8 * i)) & 0xFF);
  }
  write_i16(frames[0].data, 6, temperature_c, kTempLsb);
  frames[1].id = ids.accel;
  frames[1].len = 6;
  frames[2].id = ids.gyro;
  frames[2].len = 6;
  for (int a = 0; a < 3; ++a) {
    write_i16(frames[1].data, 2 * a, accel_m_s2[a], kAccelLsb);
    write_i16(frames[2].data, 2 * a, gyro_rad_s[a], kGyroLsb);
  }
  return frames;
}

}  // namespace livod::imu
