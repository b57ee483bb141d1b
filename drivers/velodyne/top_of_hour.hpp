#pragma once
// Velodyne timestamps count microseconds since the top of the hour (§4.1). The hour comes from
// elsewhere: a reference time (the packet's receive time, or the UTC time of a $GPRMC sentence)
// chooses it with the §4.6 rule, then a running unwrapper follows the hour rollovers.

#include <cstdint>

namespace livod::drivers::velodyne {

inline constexpr std::int64_t kHourNs = 3'600'000'000'000;

// §4.6 (VROS time_conversion.hpp, VDEC getPacketTimestamp): take the hour of `reference_ns`, add
// the microseconds, and move by one hour if that lands more than 30 minutes from the reference.
// Both times are ns on the same epoch.
[[nodiscard]] std::int64_t resolve_top_of_hour(std::uint32_t toh_us, std::int64_t reference_ns);

// Turns a stream of top-of-hour stamps into a continuous sensor timeline (ns).
class TopOfHourClock {
 public:
  // The first call anchors the hour with resolve_top_of_hour(toh_us, reference_ns); later calls
  // keep each stamp within 30 minutes of the previous one, which follows hour rollovers and
  // tolerates slightly out-of-order packets.
  [[nodiscard]] std::int64_t to_sensor_ns(std::uint32_t toh_us, std::int64_t reference_ns);

  // Moves the timeline by a whole number of hours (a GPS fix disagreed with the first anchor).
  void shift_hours(std::int64_t hours);

  [[nodiscard]] bool anchored() const { return anchored_; }
  [[nodiscard]] std::uint64_t hour_rollovers() const { return rollovers_; }

 private:
  bool anchored_ = false;
  std::int64_t hour_base_ns_ = 0;  // sensor time of the current top of the hour
  std::int64_t last_ns_ = 0;
  std::uint64_t rollovers_ = 0;
};

}  // namespace livod::drivers::velodyne
