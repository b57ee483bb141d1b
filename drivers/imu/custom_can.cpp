#include "drivers/imu/custom_can.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/units.hpp"

namespace livod::imu {
namespace {

constexpr std::uint32_t kAllAxes = 0x3F;
constexpr int kClassicBytes = 8;

bool is_accel(ImuAxis a) {
  return a == ImuAxis::accel_x || a == ImuAxis::accel_y || a == ImuAxis::accel_z;
}

const char* axis_name(ImuAxis a) {
  static constexpr std::array<const char*, 6> kNames{"accel_x", "accel_y", "accel_z",
                                                     "gyro_x",  "gyro_y",  "gyro_z"};
  return kNames[static_cast<std::size_t>(a)];
}

// Unit -> SI factor.
double si_scale(ImuUnit u) {
  switch (u) {
    case ImuUnit::g:
      return kStandardGravity;
    case ImuUnit::deg_s:
      return kDegToRad;
    case ImuUnit::m_s2:
    case ImuUnit::rad_s:
      return 1.0;
  }
  return 1.0;
}

}  // namespace

std::vector<std::string> check_spec(const CustomCanSpec& spec) {
  std::vector<std::string> problems;
  std::array<int, 6> count{};
  bool sample_id_used = false;
  for (const auto& s : spec.signals) {
    const auto axis = static_cast<std::size_t>(s.axis);
    if (axis >= count.size()) {
      problems.emplace_back("a signal has an unknown axis");
      continue;
    }
    ++count[axis];
    const std::string where = std::string("signal ") + axis_name(s.axis) + ": ";
    if (const auto why = check_bit_field(s.bits, kClassicBytes); !why.empty()) {
      problems.push_back(where + why);
    }
    const bool accel_unit = s.unit == ImuUnit::m_s2 || s.unit == ImuUnit::g;
    if (accel_unit != is_accel(s.axis)) problems.push_back(where + "unit does not fit the axis");
    if (s.factor == 0.0 || !std::isfinite(s.factor) || !std::isfinite(s.offset)) {
      problems.push_back(where + "factor must be finite and non-zero, offset finite");
    }
    if (s.id > 0x1FFFFFFF) problems.push_back(where + "identifier beyond 29 bits");
    sample_id_used = sample_id_used || s.id == spec.sample_id;
  }
  for (std::size_t a = 0; a < count.size(); ++a) {
    if (count[a] == 0) {
      problems.push_back(std::string("no signal for ") + axis_name(static_cast<ImuAxis>(a)));
    } else if (count[a] > 1) {
      problems.push_back(std::string("more than one signal for ") +
                         axis_name(static_cast<ImuAxis>(a)));
    }
  }
  if (!sample_id_used) {
    problems.push_back("no signal is carried by the sample frame " +
                       std::to_string(spec.sample_id));
  }
  return problems;
}

CustomCanDecoder::CustomCanDecoder(CustomCanSpec spec) : spec_(std::move(spec)) {
  const auto problems = check_spec(spec_);
  if (!problems.empty()) {
    std::string text = "custom CAN IMU decoder:";
    for (const auto& p : problems) text += " " + p + ";";
    throw std::invalid_argument(text);
  }
  for (const auto& s : spec_.signals) {
    ids_.push_back(s.id);
    needed_bytes_.push_back(*bytes_needed(s.bits, kClassicBytes));
  }
  std::sort(ids_.begin(), ids_.end());
  ids_.erase(std::unique(ids_.begin(), ids_.end()), ids_.end());
}

void CustomCanDecoder::on_frame(const CanRecord& frame, const ImuSink& sink) {
  if (frame.rtr || frame.error || frame.extended != (frame.id > 0x7FF)) return;
  if (!std::binary_search(ids_.begin(), ids_.end(), frame.id)) return;
  ++counters_.frames;
  const auto data = frame.payload();
  // Check the whole frame first: a short frame contributes nothing.
  for (std::size_t i = 0; i < spec_.signals.size(); ++i) {
    if (spec_.signals[i].id == frame.id && frame.len < needed_bytes_[i]) {
      ++counters_.malformed;
      return;
    }
  }
  if (seen_ == 0) first_rx_ns_ = frame.rx_time_ns;
  for (const auto& s : spec_.signals) {
    if (s.id != frame.id) continue;
    const auto raw = static_cast<double>(extract_raw(data, s.bits));
    values_[static_cast<std::size_t>(s.axis)] = (raw * s.factor + s.offset) * si_scale(s.unit);
    seen_ |= 1U << static_cast<unsigned>(s.axis);
  }
  if (frame.id != spec_.sample_id) return;
  if (seen_ != kAllAxes) {
    ++counters_.incomplete;
    seen_ = 0;
    return;
  }
  ImuSample sample;
  sample.stamp.host = HostTime(first_rx_ns_);
  sample.stamp.sensor = SensorTime(first_rx_ns_);
  sample.accel_m_s2 = {values_[0], values_[1], values_[2]};
  sample.gyro_rad_s = {values_[3], values_[4], values_[5]};
  seen_ = 0;
  ++counters_.samples;
  if (sink) sink(sample);
}

std::vector<CanRecord> encode_custom_sample(const CustomCanSpec& spec,
                                            const Eigen::Vector3d& accel_m_s2,
                                            const Eigen::Vector3d& gyro_rad_s) {
  std::vector<std::uint32_t> order;
  for (const auto& s : spec.signals) {
    if (s.id != spec.sample_id && std::find(order.begin(), order.end(), s.id) == order.end()) {
      order.push_back(s.id);
    }
  }
  order.push_back(spec.sample_id);
  std::vector<CanRecord> frames;
  for (const auto id : order) {
    CanRecord r;
    r.id = id;
    r.extended = id > 0x7FF;
    int len = 0;
    for (const auto& s : spec.signals) {
      if (s.id != id) continue;
      const auto axis = static_cast<std::size_t>(s.axis);
      const double si = axis < 3 ? accel_m_s2[static_cast<Eigen::Index>(axis)]
                                 : gyro_rad_s[static_cast<Eigen::Index>(axis - 3)];
      const double raw = std::round((si / si_scale(s.unit) - s.offset) / s.factor);
      const double lo = s.bits.is_signed ? -std::ldexp(1.0, s.bits.length - 1) : 0.0;
      const double hi = s.bits.is_signed ? std::ldexp(1.0, s.bits.length - 1) - 1.0
                                         : std::ldexp(1.0, s.bits.length) - 1.0;
      insert_raw(std::span<std::uint8_t>(r.data.data(), kClassicBytes), s.bits,
                 static_cast<std::int64_t>(std::clamp(raw, lo, hi)));
      len = std::max(len, *bytes_needed(s.bits, kClassicBytes));
    }
    r.len = static_cast<std::uint8_t>(len);
    frames.push_back(r);
  }
  return frames;
}

}  // namespace livod::imu
