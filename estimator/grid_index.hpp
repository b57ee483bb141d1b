#pragma once
// Integer cell coordinates of points, shared by the voxel map, the scan downsampler and the
// spatial order of scan points.

#include <cstdint>

namespace livod::estimator {

// floor(x) as an integer. std::floor is a library call on baseline x86-64 (roundsd needs SSE4.1,
// and release builds do not assume it): truncate, then step down for negative non-integers.
// Needs |x| < 2^62 and x not NaN (callers pass finite coordinates divided by a cell size).
inline std::int64_t floor_to_int(double x) {
  const auto i = static_cast<std::int64_t>(x);
  return i - static_cast<std::int64_t>(x < static_cast<double>(i));
}

}  // namespace livod::estimator
