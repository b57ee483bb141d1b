#pragma once
// How many LiDARs one estimator fuses (docs/estimator.md "Several LiDARs"): the point-to-plane
// residuals keep each LiDAR's pose in a fixed-size table, and the configuration check refuses more.

#include <cstddef>

namespace livod::estimator {

inline constexpr std::size_t kMaxLidars = 8;

}  // namespace livod::estimator
