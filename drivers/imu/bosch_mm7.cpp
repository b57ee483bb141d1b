#include "drivers/imu/bosch_mm7.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/units.hpp"
#include "drivers/imu/can_signal.hpp"

namespace livod::imu {
namespace {

constexpr double kRateLsbDeg = 0.005;
constexpr double kRateOffsetDeg = -163.84;
constexpr double kAccelLsbG = 0.000127465;
constexpr double kAccelOffsetG = -4.1768;
constexpr double kTempOffsetC = -50.0;
constexpr std::uint8_t kTempInvalidLow = 0xFF;
constexpr std::uint8_t kTempInvalidHigh = 0xC9;
constexpr std::uint8_t kStatusMask = 0x07;
constexpr int kCounterModulus = 16;

constexpr CanBitField kRate{0, 16, false, false};
constexpr CanBitField kHwIndex{16, 4, false, false};
constexpr CanBitField kRateStat{20, 4, false, false};
constexpr CanBitField kTemp{24, 8, false, false};
constexpr CanBitField kAccel{32, 16, false, false};
constexpr CanBitField kCounter{48, 4, false, false};
constexpr CanBitField kAccelStat{52, 4, false, false};

double rate_rad_s(std::span<const std::uint8_t> d) {
  return (static_cast<double>(extract_raw(d, kRate)) * kRateLsbDeg + kRateOffsetDeg) * kDegToRad;
}

double accel_m_s2(std::span<const std::uint8_t> d) {
  return (static_cast<double>(extract_raw(d, kAccel)) * kAccelLsbG + kAccelOffsetG) *
         kStandardGravity;
}

std::uint8_t stat_bits(std::span<const std::uint8_t> d) {
  return static_cast<std::uint8_t>((extract_raw(d, kRateStat) | extract_raw(d, kAccelStat)) &
                                   kStatusMask);
}

std::int64_t quantise(double value, double lsb, double offset) {
  const double raw = std::round((value - offset) / lsb);
  return static_cast<std::int64_t>(std::clamp(raw, 0.0, 65535.0));
}

}  // namespace

void BoschMm7Decoder::on_frame(const CanRecord& frame, const ImuSink& sink) {
  if (frame.rtr || frame.error || frame.extended != (frame.id > 0x7FF)) return;
  const bool tx1 = frame.id == ids_.tx1;
  const bool tx2 = frame.id == ids_.tx2;
  const bool tx3 = frame.id == ids_.tx3;
  if (!tx1 && !tx2 && !tx3) return;
  ++counters_.frames;
  if (frame.len != 8) {
    ++counters_.malformed;
    return;
  }
  const auto d = frame.payload();
  const auto counter = static_cast<std::uint8_t>(extract_raw(d, kCounter));
  if (tx1) {
    if (stage_ != 0) ++counters_.incomplete;  // the previous sample never completed
    pending_ = ImuSample{};
    pending_.stamp.host = HostTime(frame.rx_time_ns);
    pending_.stamp.sensor = SensorTime(frame.rx_time_ns);
    pending_.gyro_rad_s.z() = rate_rad_s(d);
    pending_.accel_m_s2.y() = accel_m_s2(d);
    const auto temp = static_cast<std::uint8_t>(extract_raw(d, kTemp));
    temperature_c_ = (temp == kTempInvalidLow || temp == kTempInvalidHigh)
                         ? std::numeric_limits<double>::quiet_NaN()
                         : temp + kTempOffsetC;
    status_ = stat_bits(d);
    counter_ = counter;
    stage_ = 1;
    return;
  }
  if (stage_ == 0) return;  // joined mid-sample: wait for the next TX1
  if (counter != counter_ || (tx2 && stage_ != 1) || (tx3 && stage_ != 2)) {
    // A frame of another sample, or TX2/TX3 out of order: the pending sample is broken.
    ++counters_.incomplete;
    stage_ = 0;
    return;
  }
  status_ = static_cast<std::uint8_t>(status_ | stat_bits(d));
  if (tx2) {
    pending_.gyro_rad_s.x() = -rate_rad_s(d);  // the MM7 reports roll left-handed
    pending_.accel_m_s2.x() = accel_m_s2(d);
    stage_ = 2;
    return;
  }
  pending_.gyro_rad_s.y() = rate_rad_s(d);
  pending_.accel_m_s2.z() = accel_m_s2(d);
  hw_index_ = static_cast<std::uint8_t>(extract_raw(d, kHwIndex));
  stage_ = 0;
  if (have_last_counter_) {
    const int step = (counter_ - last_counter_ + kCounterModulus) % kCounterModulus;
    if (step > 1) counters_.sequence_gaps += static_cast<std::uint64_t>(step - 1);
  }
  have_last_counter_ = true;
  last_counter_ = counter_;
  if (status_ != 0) {
    ++counters_.invalid;
    return;
  }
  ++counters_.samples;
  if (sink) sink(pending_);
}

std::array<CanRecord, 3> encode_bosch_mm7_sample(std::uint8_t counter,
                                                 const Eigen::Vector3d& accel_m_s2,
                                                 const Eigen::Vector3d& gyro_rad_s,
                                                 double temperature_c, const BoschMm7Status& status,
                                                 const BoschMm7Ids& ids) {
  std::array<CanRecord, 3> frames{};
  const std::array<std::uint32_t, 3> id{ids.tx1, ids.tx2, ids.tx3};
  // Rate and acceleration axis of each frame; the roll rate goes out left-handed.
  const std::array<double, 3> rate_deg{gyro_rad_s.z() / kDegToRad, -gyro_rad_s.x() / kDegToRad,
                                       gyro_rad_s.y() / kDegToRad};
  const std::array<double, 3> accel_g{accel_m_s2.y() / kStandardGravity,
                                      accel_m_s2.x() / kStandardGravity,
                                      accel_m_s2.z() / kStandardGravity};
  for (std::size_t f = 0; f < 3; ++f) {
    CanRecord& r = frames[f];
    r.id = id[f];
    r.extended = r.id > 0x7FF;
    r.len = 8;
    std::span<std::uint8_t> d(r.data.data(), 8);
    insert_raw(d, kRate, quantise(rate_deg[f], kRateLsbDeg, kRateOffsetDeg));
    insert_raw(d, kRateStat, status.stat[2 * f]);
    insert_raw(d, kAccel, quantise(accel_g[f], kAccelLsbG, kAccelOffsetG));
    insert_raw(d, kAccelStat, status.stat[2 * f + 1]);
    insert_raw(d, kCounter, counter & 0x0F);
  }
  const double temp = std::clamp(std::round(temperature_c - kTempOffsetC), 0.0, 200.0);
  insert_raw(std::span<std::uint8_t>(frames[0].data.data(), 8), kTemp,
             static_cast<std::int64_t>(temp));
  return frames;
}

}  // namespace livod::imu
