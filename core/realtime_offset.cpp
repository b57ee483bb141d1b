#include "core/realtime_offset.hpp"

#include <ctime>
#include <limits>

namespace livod {
namespace {

std::int64_t read_ns(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

void RealtimeToMonotonic::refresh() {
  constexpr int kTries = 3;  // the tightest of three brackets is plenty with the vDSO
  std::int64_t best_width = std::numeric_limits<std::int64_t>::max();
  for (int i = 0; i < kTries; ++i) {
    const std::int64_t before = read_ns(CLOCK_REALTIME);
    const std::int64_t mono = read_ns(CLOCK_MONOTONIC);
    const std::int64_t after = read_ns(CLOCK_REALTIME);
    const std::int64_t width = after - before;
    if (width >= 0 && width < best_width) {
      best_width = width;
      offset_ns_ = before + width / 2 - mono;
    }
  }
  bracket_ns_ = best_width;
}

}  // namespace livod
