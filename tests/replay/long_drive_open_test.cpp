// The drift bound of issue 15 on long drives: the end point within 0.05 % of the distance in every
// axis after the 15-minute (9 km) and the 30-minute (18 km) street drives. Not met yet (open:
// docs/estimator.md "Long drives"; measured 2026-11-27: the 30-minute drive ends (-0.8, -8.9,
// +49.7) m, 0.28 % high, a pitch error growing by about 0.17 mrad a minute; the last test isolates
// its cause, the range noise). Label "open": left out of the release test preset, run with
// `ctest --test-dir build/release -L open` (about 25 minutes of both cores). The 15-minute drive's
// memory and on-track checks run in every CI run (long_run_memory_test.cpp).

#include <gtest/gtest.h>

#include <cmath>

#include "tests/replay/long_drive.hpp"

namespace livod {
namespace {

TEST(LongDrive, FifteenMinutesStayWithinTheDriftBound) {
  constexpr double kDurationS = 15.0 * 60.0 + 10.0;
  const test::DriveResult r = test::run_street_drive({kDurationS, true, 11});
  ASSERT_GE(r.minutes.size(), 15U);
  EXPECT_GT(r.path_m, 8900.0);
  test::expect_end_error_within_bound(r);
}

TEST(LongDrive, ThirtyMinutesStayWithinTheDriftBound) {
  constexpr double kDurationS = 30.0 * 60.0 + 10.0;
  const test::DriveResult r = test::run_street_drive({kDurationS, true, 11});
  ASSERT_GE(r.minutes.size(), 30U);
  EXPECT_GT(r.path_m, 17900.0);
  EXPECT_LT(r.map.root_voxels, 100'000U);
  test::expect_end_error_within_bound(r);
}

// The cause, isolated: the same drive over 2 km with an error-free IMU, with and without the range
// noise of the OS1's datasheet (1.5 cm). Without range noise the estimate holds its attitude
// (measured: pitch -0.05 mrad, end (-0.02, +0.07, +0.13) m); with it the pitch error grows
// (-0.85 mrad, z +1.14 m after 2 km): the drift is a bias of the estimator under zero-mean range
// noise, not the IMU (docs/estimator.md "Long drives"). Only the noise-free drive is held to the
// bound; the noisy one prints its figures after it.
TEST(LongDrive, WithoutRangeNoiseTheDriveHoldsItsAttitude) {
  constexpr double kDurationS = 210.0;
  test::DriveOptions noiseless{kDurationS, true, 11};
  noiseless.ideal_imu = true;
  noiseless.noiseless_range = true;
  const test::DriveResult clean = test::run_street_drive(noiseless);
  EXPECT_GT(clean.path_m, 2000.0);
  test::expect_end_error_within_bound(clean);
  // Pitch and roll: the drift shows in them first (a pitch error e lifts the track by e per metre).
  EXPECT_LT(std::abs(clean.end_rotation_error.x()), 0.2e-3);
  EXPECT_LT(std::abs(clean.end_rotation_error.y()), 0.2e-3);

  test::DriveOptions noisy = noiseless;
  noisy.noiseless_range = false;
  // run_street_drive prints its end position and attitude errors.
  test::run_street_drive(noisy);
}

}  // namespace
}  // namespace livod
