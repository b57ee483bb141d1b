// Issue 15's drift bound on long drives: the end point within 0.05 % of the distance in every axis.
// The 15-minute (9 km) drive with noise seed 11 is held to it in every CI run
// (long_run_memory_test.cpp); here the 30-minute (18 km) drive, whose street is laid out for its
// length and so differs from the 15-minute one, and the 15-minute drive with two other noise seeds
// (the drift this bound caught was a bias that every seed showed alike: docs/estimator.md, "Long
// drives"). Label "long": left out of the release test preset, run with
// `ctest --test-dir build/release -L long` (about 20 minutes of both cores).

#include <gtest/gtest.h>

#include "tests/replay/long_drive.hpp"

namespace livod {
namespace {

TEST(LongDrive, ThirtyMinutesStayWithinTheDriftBound) {
  constexpr double kDurationS = 30.0 * 60.0 + 10.0;
  const test::DriveResult r = test::run_street_drive({kDurationS, true, 11});
  ASSERT_GE(r.minutes.size(), 30U);
  EXPECT_GT(r.path_m, 17900.0);
  EXPECT_LT(r.map.root_voxels, 100'000U);
  test::expect_end_error_within_bound(r);
}

class LongDriveSeed : public ::testing::TestWithParam<std::uint64_t> {};

TEST_P(LongDriveSeed, FifteenMinutesStayWithinTheDriftBound) {
  constexpr double kDurationS = 15.0 * 60.0 + 10.0;
  const test::DriveResult r = test::run_street_drive({kDurationS, true, GetParam()});
  ASSERT_GE(r.minutes.size(), 15U);
  EXPECT_GT(r.path_m, 8900.0);
  test::expect_end_error_within_bound(r);
}

INSTANTIATE_TEST_SUITE_P(NoiseSeeds, LongDriveSeed, ::testing::Values(12U, 13U));

}  // namespace
}  // namespace livod
