#pragma once
// Conversion of CLOCK_REALTIME stamps (kernel socket timestamps, Aravis system stamps, pcap record
// times) onto CLOCK_MONOTONIC, the host timeline of livod. The offset is measured with bracketed
// clock_gettime(REALTIME) / (MONOTONIC) / (REALTIME) triples; the tightest bracket of a few tries
// wins, which bounds the error by half the bracket width (typically < 100 ns with the vDSO).
// REALTIME can be stepped by NTP at any time, so callers refresh() periodically (the capture
// threads do it every kRealtimeOffsetRefreshNs) and a step shows up as a jump of offset_ns().

#include <cstdint>

#include "core/time.hpp"

namespace livod {

// How often a capture thread re-measures the offset: an NTP step is seen within 100 ms.
inline constexpr std::int64_t kRealtimeOffsetRefreshNs = 100'000'000;

class RealtimeToMonotonic {
 public:
  RealtimeToMonotonic() { refresh(); }

  // Re-measures the offset (about 6 clock_gettime calls; no allocation, no syscalls with vDSO).
  void refresh();

  // monotonic = realtime - offset
  [[nodiscard]] std::int64_t offset_ns() const { return offset_ns_; }
  [[nodiscard]] std::int64_t bracket_ns() const { return bracket_ns_; }
  [[nodiscard]] HostTime to_host(std::int64_t realtime_ns) const {
    return HostTime(realtime_ns - offset_ns_);
  }

 private:
  std::int64_t offset_ns_ = 0;
  std::int64_t bracket_ns_ = 0;
};

}  // namespace livod
