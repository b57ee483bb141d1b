// The drift bound of issue 15 on long drives: the end point within 0.05 % of the distance in every
// axis after the 15-minute (9 km) and the 30-minute (18 km) street drives. Not met yet (open:
// docs/estimator.md "Long drives"; measured 2026-11-27: the 30-minute drive ends (-0.8, -8.9,
// +49.7) m, 0.28 % high, a pitch error growing by about 0.17 mrad a minute). Label "open": left
// out of the release test preset, run with `ctest --test-dir build/release -L open` (about 25
// minutes of both cores). The 15-minute drive's memory and on-track checks run in every CI run
// (long_run_memory_test.cpp).

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace livod
