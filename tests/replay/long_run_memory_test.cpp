// Long runs (issue 15 and the bounded-memory requirement): a 15-minute drive (9 km at 10 m/s along
// a simulated street, Ouster OS1-64 with its internal IMU, the estimator as the daemon configures
// an OS1-64 by default) streamed from the simulator into the pipeline (long_drive.hpp). The
// estimator's map must stay the size of its sliding box, its accounted bytes must stop growing
// after warm-up, the voxels it drops must be freed, resident memory must be flat from the third
// minute to the last - and the odometry must still be on track at the end (a bounded map that lost
// track would prove nothing). Map sliding must not bias the solution: the same drive with and
// without sliding agrees within issue 15's drift bound, 0.05 % of the distance (on a 100 s
// stretch: without sliding the map keeps every voxel of the street).
//
// That bound over the whole 15- and 30-minute drives is not met yet: long_drive_open_test.cpp
// (label "open", not run by default). The replay engine around the estimator has its own
// bounded-memory test through real files: replay_memory_test.cpp.

#include <gtest/gtest.h>

#include "tests/replay/long_drive.hpp"

namespace livod {
namespace {

double max_over(const std::vector<test::DriveMinute>& m, std::size_t begin, std::size_t end,
                double test::DriveMinute::*field) {
  double best = 0.0;
  for (std::size_t i = begin; i < std::min(end, m.size()); ++i) best = std::max(best, m[i].*field);
  return best;
}

TEST(LongRunMemory, FifteenMinuteDriveStaysBoundedAndOnTrack) {
  constexpr double kDurationS = 15.0 * 60.0 + 10.0;
  const test::DriveResult r = test::run_street_drive({kDurationS, true, 11});
  ASSERT_GE(r.minutes.size(), 15U);
  EXPECT_GE(static_cast<double>(r.frames), (kDurationS - 5.0) / 0.1);
  // The map slid all the way (9 km of street hold millions of voxels), kept the size of its box
  // and freed what it dropped.
  EXPECT_GT(r.map.removed_voxels, 1'000'000U);
  EXPECT_LT(r.map.root_voxels, 100'000U);
  EXPECT_LT(r.map.retired_voxels, 100'000U);
  const double map_warm = max_over(r.minutes, 2, 5, &test::DriveMinute::map_mib);
  const double map_late = max_over(r.minutes, 5, r.minutes.size(), &test::DriveMinute::map_mib);
  EXPECT_LT(map_late, 1.25 * map_warm) << "the estimator's map keeps growing";
  EXPECT_LT(static_cast<double>(r.map_bytes_max) / 1048576.0, 1.25 * map_warm);
  // Flat after warm-up: the heap may settle, it may not grow with the distance driven.
  const double rss_warm = max_over(r.minutes, 2, 5, &test::DriveMinute::rss_mib);
  const double rss_late = max_over(r.minutes, 5, r.minutes.size(), &test::DriveMinute::rss_mib);
  EXPECT_LT(rss_late, rss_warm + 24.0) << "resident memory keeps growing";
  // Still on track after 9 km. Not issue 15's drift bound (0.05 % of the distance at the end,
  // long_drive_open_test.cpp): the estimate climbs, +13 m at the end (0.14 %; docs/estimator.md
  // "Long drives"). These bounds catch a lost track.
  EXPECT_GT(r.path_m, 8900.0);
  EXPECT_LT(r.rmse_m, 0.002 * r.path_m);
  EXPECT_LT(r.end_error.norm(), 0.005 * r.path_m);
}

TEST(LongRunMemory, SlidingDoesNotBiasTheDrive) {
  constexpr double kDurationS = 100.0;  // 950 m: the unbounded map stays a few hundred MiB
  const test::DriveResult sliding = test::run_street_drive({kDurationS, true, 11});
  const test::DriveResult kept = test::run_street_drive({kDurationS, false, 11});
  EXPECT_GT(sliding.map.removed_voxels, 10'000U);
  EXPECT_EQ(kept.map.removed_voxels, 0U);
  test::expect_end_error_within_bound(sliding);
  test::expect_end_error_within_bound(kept);
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_LE(std::abs(sliding.end_error[axis] - kept.end_error[axis]),
              test::kEndErrorFraction * sliding.path_m)
        << "axis " << axis;
  }
}

}  // namespace
}  // namespace livod
