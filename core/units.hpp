#pragma once
// Physical constants used where sensors report in non-SI units (converted once, in the driver).

#include <cstdint>
#include <numbers>

namespace livod {

// Standard gravity (m/s^2 per g): ISO 80000-3 / CGPM 1901. IMUs that report in g (Livox, Ouster
// LEGACY, the HDL-32E) are converted with it, as their vendors' SDKs do.
inline constexpr double kStandardGravity = 9.80665;

// Angles: sensors and configurations give degrees, the code works in radians.
inline constexpr double kDegToRad = std::numbers::pi / 180.0;

}  // namespace livod
