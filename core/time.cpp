#include "core/time.hpp"

#include <ctime>

namespace livod {

HostTime host_now() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return HostTime(static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec);
}

}  // namespace livod
