#include "drivers/imu/sbg_can.hpp"

#include <algorithm>
#include <cmath>

namespace livod::imu {
namespace {

constexpr double kAccelLsb = 0.01;  // m/s^2 per count
constexpr double kGyroLsb = 0.001;  // rad/s per count
constexpr double kTempLsb = 0.01;   // degC per count
constexpr std::int64_t kCounterSpanUs = std::int64_t{1} << 32;

std::int16_t read_i16(std::span<const std::uint8_t> d, int offset) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(d[offset]) |
                                   static_cast<std::uint16_t>(d[offset + 1] << 8));
}

void write_i16(std::array<std::uint8_t, 64>& d, int offset, double value, double lsb) {
  const long counts = std::clamp(std::lround(value / lsb), -32768L, 32767L);
  const auto u = static_cast<std::uint16_t>(static_cast<std::int16_t>(counts));
  d[offset] = static_cast<std::uint8_t>(u & 0xFF);
  d[offset + 1] = static_cast<std::uint8_t>(u >> 8);
}

Eigen::Vector3d read_vec(std::span<const std::uint8_t> d, double lsb) {
  return {read_i16(d, 0) * lsb, read_i16(d, 2) * lsb, read_i16(d, 4) * lsb};
}

}  // namespace

void SbgCanDecoder::on_frame(const CanRecord& frame, const ImuSink& sink) {
  if (frame.rtr || frame.error || frame.extended != (frame.id > 0x7FF)) return;
  if (frame.id != ids_.info && frame.id != ids_.accel && frame.id != ids_.gyro) return;
  ++counters_.frames;
  const auto data = frame.payload();
  if (frame.id == ids_.info) {
    if (frame.len < 8) {
      ++counters_.malformed;
      return;
    }
    if (have_info_) ++counters_.incomplete;  // the previous sample never got its GYRO frame
    const std::uint32_t raw =
        static_cast<std::uint32_t>(data[0]) | (static_cast<std::uint32_t>(data[1]) << 8) |
        (static_cast<std::uint32_t>(data[2]) << 16) | (static_cast<std::uint32_t>(data[3]) << 24);
    if (seen_counter_ && raw < last_raw_us_ && last_raw_us_ - raw > 0x80000000U) {
      wrap_offset_us_ += kCounterSpanUs;
      ++counters_.counter_wraps;
    }
    seen_counter_ = true;
    last_raw_us_ = raw;
    pending_ = ImuSample{};
    pending_.stamp.sensor = SensorTime((wrap_offset_us_ + raw) * 1000);
    pending_.stamp.host = HostTime(frame.rx_time_ns);
    status_ = static_cast<std::uint16_t>(data[4] | (data[5] << 8));
    temperature_c_ = read_i16(data, 6) * kTempLsb;
    have_info_ = true;
    have_accel_ = false;
    return;
  }
  if (frame.len < 6) {
    ++counters_.malformed;
    return;
  }
  if (!have_info_) return;  // joined mid-sample: wait for the next INFO frame
  if (frame.id == ids_.accel) {
    pending_.accel_m_s2 = read_vec(data, kAccelLsb);
    have_accel_ = true;
    return;
  }
  // GYRO closes the sample.
  have_info_ = false;
  if (!have_accel_) {
    ++counters_.incomplete;
    return;
  }
  pending_.gyro_rad_s = read_vec(data, kGyroLsb);
  ++counters_.samples;
  if (sink) sink(pending_);
}

std::array<CanRecord, 3> encode_sbg_sample(std::uint32_t device_time_us,
                                           const Eigen::Vector3d& accel_m_s2,
                                           const Eigen::Vector3d& gyro_rad_s, double temperature_c,
                                           const SbgCanIds& ids) {
  std::array<CanRecord, 3> frames{};
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
  for (auto& f : frames) f.extended = f.id > 0x7FF;
  return frames;
}

}  // namespace livod::imu
