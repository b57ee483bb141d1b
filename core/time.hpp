#pragma once
// Strong time types. livod keeps three clocks apart so that they cannot be mixed by accident:
//   SensorTime  - the sensor's own clock, unwrapped to ns (free-running, PTP, GPS...)
//   HostTime    - host receive time, CLOCK_MONOTONIC ns (kernel socket stamp where available)
//   MappedTime  - the common timeline every estimator input lives on (CLOCK_MONOTONIC domain)
// Durations are plain std::chrono::nanoseconds; per-point times inside a scan are integer ns
// offsets from the scan start (see core/measurement.hpp).

#include <chrono>
#include <compare>
#include <cstdint>

namespace livod {

inline constexpr std::int64_t kNsPerSecond = 1'000'000'000;

using Nanoseconds = std::chrono::nanoseconds;

template <class Tag>
struct TimePoint {
  std::int64_t ns = 0;

  constexpr TimePoint() = default;
  constexpr explicit TimePoint(std::int64_t nanoseconds) : ns(nanoseconds) {}

  static constexpr TimePoint from_seconds(double s) {
    return TimePoint(static_cast<std::int64_t>(s * 1e9 + (s >= 0 ? 0.5 : -0.5)));
  }
  [[nodiscard]] constexpr double seconds() const { return static_cast<double>(ns) * 1e-9; }

  constexpr auto operator<=>(const TimePoint&) const = default;

  constexpr TimePoint& operator+=(Nanoseconds d) {
    ns += d.count();
    return *this;
  }
  constexpr TimePoint& operator-=(Nanoseconds d) {
    ns -= d.count();
    return *this;
  }
  friend constexpr TimePoint operator+(TimePoint t, Nanoseconds d) { return t += d; }
  friend constexpr TimePoint operator-(TimePoint t, Nanoseconds d) { return t -= d; }
  friend constexpr Nanoseconds operator-(TimePoint a, TimePoint b) {
    return Nanoseconds(a.ns - b.ns);
  }
};

struct SensorClockTag {};
struct HostClockTag {};
struct MappedClockTag {};

using SensorTime = TimePoint<SensorClockTag>;
using HostTime = TimePoint<HostClockTag>;
using MappedTime = TimePoint<MappedClockTag>;

// Every measurement carries all three stamps (DESIGN.md invariant).
struct Stamp {
  SensorTime sensor;
  HostTime host;
  MappedTime mapped;
};

// CLOCK_MONOTONIC now, as a HostTime. Defined in time.cpp so that <time.h> stays out of headers.
HostTime host_now();

constexpr double to_seconds(Nanoseconds d) {
  return static_cast<double>(d.count()) * 1e-9;
}
constexpr Nanoseconds from_seconds(double s) {
  return Nanoseconds(static_cast<std::int64_t>(s * 1e9 + (s >= 0 ? 0.5 : -0.5)));
}

}  // namespace livod
