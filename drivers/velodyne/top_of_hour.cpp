#include "drivers/velodyne/top_of_hour.hpp"

#include "core/numeric.hpp"

namespace livod::drivers::velodyne {
namespace {

constexpr std::int64_t kHalfHourNs = kHourNs / 2;

}  // namespace

std::int64_t resolve_top_of_hour(std::uint32_t toh_us, std::int64_t reference_ns) {
  const std::int64_t hour_start = floor_div(reference_ns, kHourNs) * kHourNs;
  std::int64_t stamp = hour_start + static_cast<std::int64_t>(toh_us) * 1000;
  if (stamp - reference_ns > kHalfHourNs) {
    stamp -= kHourNs;
  } else if (reference_ns - stamp > kHalfHourNs) {
    stamp += kHourNs;
  }
  return stamp;
}

std::int64_t TopOfHourClock::to_sensor_ns(std::uint32_t toh_us, std::int64_t reference_ns) {
  const std::int64_t within_hour = static_cast<std::int64_t>(toh_us) * 1000;
  if (!anchored_) {
    const std::int64_t stamp = resolve_top_of_hour(toh_us, reference_ns);
    hour_base_ns_ = stamp - within_hour;
    anchored_ = true;
    last_ns_ = stamp;
    return stamp;
  }
  std::int64_t stamp = hour_base_ns_ + within_hour;
  if (last_ns_ - stamp > kHalfHourNs) {
    hour_base_ns_ += kHourNs;  // the microsecond counter rolled over into the next hour
    stamp += kHourNs;
    ++rollovers_;
  } else if (stamp - last_ns_ > kHalfHourNs) {
    // A packet from just before a rollover arrived after it: it belongs to the previous hour.
    // The base stays; only this stamp moves back.
    stamp -= kHourNs;
    return stamp;
  }
  last_ns_ = stamp;
  return stamp;
}

void TopOfHourClock::shift_hours(std::int64_t hours) {
  hour_base_ns_ += hours * kHourNs;
  last_ns_ += hours * kHourNs;
}

}  // namespace livod::drivers::velodyne
