#include "estimator/map/voxel_map.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "estimator/tests/support/road_ring.hpp"

namespace livod::estimator {
namespace {

std::vector<CovPoint> sample_plane(std::mt19937& rng, const Eigen::Vector3d& origin,
                                   const Eigen::Vector3d& u, const Eigen::Vector3d& v, int n,
                                   double noise) {
  std::uniform_real_distribution<double> a(0.0, 1.0);
  std::normal_distribution<double> g(0.0, noise);
  const Eigen::Vector3d normal = u.cross(v).normalized();
  std::vector<CovPoint> out;
  for (int i = 0; i < n; ++i) {
    CovPoint p;
    p.p = origin + a(rng) * u + a(rng) * v + g(rng) * normal;
    p.cov = Eigen::Matrix3d::Identity() * noise * noise;
    out.push_back(p);
  }
  return out;
}

TEST(VoxelMap, KeysAreATrueFloor) {
  EXPECT_EQ(voxel_key({-1.0, 0.0, 0.49}, 0.5), (VoxelKey{-2, 0, 0}));
  EXPECT_EQ(voxel_key({-0.01, 0.5, -0.5}, 0.5), (VoxelKey{-1, 1, -1}));
}

TEST(VoxelMap, MatchesPointsToTheirPlaneAndRejectsOutliers) {
  LioParams lio;
  MapParams map;
  VoxelMap vm(lio, map);
  std::mt19937 rng(2);
  // A floor (z = 0) and a wall (x = 2), 4 m wide, with 1 cm noise.
  vm.insert(sample_plane(rng, {-2, -2, 0}, {4, 0, 0}, {0, 4, 0}, 20000, 0.01));
  vm.insert(sample_plane(rng, {2, -2, 0}, {0, 4, 0}, {0, 0, 3}, 20000, 0.01));
  const auto stats = vm.stats();
  EXPECT_GT(stats.planes, 100u);
  const Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() * 1e-4;
  PlaneMatch m;
  ASSERT_TRUE(vm.match({0.3, 0.7, 0.02}, cov, m));
  EXPECT_GT(std::abs(m.plane->normal.z()), 0.99);
  EXPECT_NEAR(std::abs(m.distance), 0.02, 0.01);
  ASSERT_TRUE(vm.match({1.97, 0.4, 1.3}, cov, m));
  EXPECT_GT(std::abs(m.plane->normal.x()), 0.99);
  EXPECT_NEAR(std::abs(m.distance), 0.03, 0.01);
  // 20 cm off the floor inside its voxel: far beyond 3 sigma.
  EXPECT_FALSE(vm.match({0.3, 0.7, 0.2}, cov, m));
  // In empty space.
  EXPECT_FALSE(vm.match({0.0, 0.0, 1.5}, cov, m));
}

// A plane seen many times (a near wall seen head-on, 2 cm range noise): FAST-LIVO2 freezes it on
// its first max_points_num points. With a larger max_points_num it keeps learning past the
// max_cov_points it stores, from their moments, at a frozen node's memory.
TEST(VoxelMap, APlanePastItsStoredPointsKeepsLearningFromTheirMoments) {
  constexpr int kScans = 40;
  constexpr int kPointsPerScan = 25;
  const auto offset_rms = [&](int max_points_num, bool check_memory) {
    double sum2 = 0.0;
    constexpr int kTrials = 30;
    for (int trial = 0; trial < kTrials; ++trial) {
      LioParams lio;
      lio.max_points_num = max_points_num;
      lio.max_cov_points = 50;
      MapParams map;
      VoxelMap vm(lio, map);
      std::mt19937 rng(100 + trial);
      // z = 0.1 inside the root voxel [0, 0.5)^3.
      for (int scan = 0; scan < kScans; ++scan) {
        vm.insert(
            sample_plane(rng, {0.02, 0.02, 0.1}, {0.46, 0, 0}, {0, 0.46, 0}, kPointsPerScan, 0.02));
        const VoxelMapStats s = vm.stats();
        if (check_memory) {
          EXPECT_LE(s.stored_points, 50u) << scan;
          if ((scan + 1) * kPointsPerScan > 50) {
            // Past the stored points: none kept, the plane not frozen until max_points_num.
            EXPECT_EQ(s.stored_points, 0u) << scan;
            EXPECT_EQ(s.frozen_nodes, (scan + 1) * kPointsPerScan >= max_points_num ? 1u : 0u)
                << scan;
          }
        }
      }
      PlaneMatch m;
      EXPECT_TRUE(vm.match({0.25, 0.25, 0.1}, Eigen::Matrix3d::Identity() * 1e-6, m));
      sum2 += m.distance * m.distance;
    }
    return std::sqrt(sum2 / kTrials);
  };
  const double frozen_at_50 = offset_rms(50, false);
  const double frozen_at_1000 = offset_rms(kScans * kPointsPerScan, true);
  // 2 cm / sqrt(N): about 2.8 mm on 50 points, 0.6 mm on 1000.
  EXPECT_GT(frozen_at_50, 0.0015);
  EXPECT_LT(frozen_at_1000, 0.001);
  EXPECT_LT(frozen_at_1000, 0.4 * frozen_at_50);
}

// A voxel crossed by one ring holds a line, not a plane (plane.hpp, min_plane_spread_ratio): it
// matches nothing and is not split, and the next ring through it makes it the road's plane.
TEST(VoxelMap, OneRingIsALineUntilTheNextRingSpansTheVoxel) {
  LioParams lio;
  lio.min_plane_spread_ratio = 4.0;
  MapParams map;
  VoxelMap vm(lio, map);
  std::mt19937 rng(6);
  // A ring across one root voxel of road at z = 0.25 (off the voxel faces), y in (0, 0.5).
  test_support::RoadRing ring{
      .range_m = 9.6, .road_z_m = 0.25, .y_begin_m = 0.02, .y_end_m = 0.48, .points = 40};
  vm.insert(test_support::road_ring(rng, ring));
  PlaneMatch m;
  const Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() * 1e-4;
  EXPECT_FALSE(vm.match({9.8, 0.25, 0.25}, cov, m));
  EXPECT_EQ(vm.stats().planes, 0u);
  EXPECT_EQ(vm.stats().nodes, 1u);  // waits whole for the points that span it
  ring.range_m = 9.9;
  vm.insert(test_support::road_ring(rng, ring));
  ASSERT_TRUE(vm.match({9.8, 0.25, 0.25}, cov, m));
  EXPECT_EQ(vm.stats().planes, 1u);
  EXPECT_GT(std::abs(m.plane->normal.z()), 0.999);
  EXPECT_LT(std::abs(m.distance), 0.01);
}

TEST(VoxelMap, NeighbourFallbackUsesVoxelUnits) {
  LioParams lio;
  lio.voxel_size = 1.0;
  MapParams map;
  VoxelMap vm(lio, map);
  std::mt19937 rng(3);
  // A plane at z = 0.95 filling voxel z-index 0 only (x, y in [10, 11)).
  vm.insert(sample_plane(rng, {10.0, 10.0, 0.95}, {0.999, 0, 0}, {0, 0.999, 0}, 200, 0.002));
  PlaneMatch m;
  // A point at z = 1.0 lies in voxel z-index 1 (empty), 0.0 above its floor face: the fallback
  // must look down into voxel 0 and match the plane 5 cm below.
  ASSERT_TRUE(vm.match({10.5, 10.5, 1.0}, Eigen::Matrix3d::Identity() * 1e-3, m));
  EXPECT_NEAR(std::abs(m.distance), 0.05, 0.01);
  // Near the top face of voxel 1 the fallback looks up, not down: no match.
  EXPECT_FALSE(vm.match({10.5, 10.5, 1.9}, Eigen::Matrix3d::Identity() * 1e-3, m));
}

TEST(VoxelMap, PlanesFreezeAndTheMapSlidesSoMemoryIsBounded) {
  LioParams lio;
  MapParams map;
  map.half_extent_m = 20.0;
  map.slide_threshold_m = 5.0;
  VoxelMap vm(lio, map);
  std::mt19937 rng(4);
  std::size_t peak_bytes = 0;
  for (int step = 0; step < 60; ++step) {
    const double x = step * 5.0;  // drive 300 m along a corridor-like floor
    // Three scans see the new stretch of floor (mid-voxel height, so each voxel gets them all).
    for (int scan = 0; scan < 3; ++scan) {
      vm.insert(sample_plane(rng, {x, -5, 0.25}, {5, 0, 0}, {0, 10, 0}, 8000, 0.01));
    }
    vm.slide({x, 0, 1});
    peak_bytes = std::max(peak_bytes, vm.stats().bytes);
    if (step == 10) {
      // After warm-up the footprint must stay flat: compare later peaks against this one.
      EXPECT_GT(vm.stats().frozen_nodes, 0u);
    }
  }
  const auto s = vm.stats();
  EXPECT_GT(s.removed_voxels, 0u);
  // Everything left lies within the extent (+ one voxel) of the last position.
  EXPECT_LE(s.root_voxels, static_cast<std::size_t>((2 * 41 + 1) * (2 * 41 + 1) * 3));
  // Frozen planes released their points: far fewer points stored than the 8 x 24000 inserted
  // within the extent.
  EXPECT_LT(s.stored_points, 24000u);
  EXPECT_LT(peak_bytes, 64u * 1024 * 1024);
  EXPECT_EQ(s.evicted_voxels, 0u);  // a normal drive never reaches the voxel budget
}

// A diverged estimate: scans land in random orientations around a position that wanders off, so
// they fill the sliding box's volume rather than its surfaces. The budget must hold the map (and
// the voxels awaiting release) to a bounded size, keep the voxels around the sensor and let the
// far ones go. Without the budget this map grows with every scan (the box is 100 m wide).
TEST(VoxelMap, AVoxelBudgetBoundsAMapFilledByADivergedEstimate) {
  LioParams lio;
  MapParams map;
  map.max_voxels = 20000;
  VoxelMap vm(lio, map);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::size_t peak_roots = 0;
  std::size_t peak_retired = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  for (int scan = 0; scan < 120; ++scan) {
    position += Eigen::Vector3d(0.3, 0.2, 0.05);  // drifting, slower than the slide threshold
    std::vector<CovPoint> points(3000);
    for (auto& p : points) {
      // A random direction and range up to 30 m: a spinning sensor's scan.
      p.p = position + Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 30.0;
      p.cov = Eigen::Matrix3d::Identity() * 1e-4;
    }
    vm.insert(points);
    vm.slide(position);
    const auto st = vm.stats();
    peak_roots = std::max(peak_roots, st.root_voxels);
    peak_retired = std::max(peak_retired, st.retired_voxels);
  }
  const auto s = vm.stats();
  EXPECT_LE(peak_roots, map.max_voxels);
  EXPECT_GT(s.evicted_voxels, 100000u);  // 360 k points, nearly one voxel each
  // Released at least an eighth per scan: the backlog stays below a few scans' evictions.
  EXPECT_LT(peak_retired, 2 * map.max_voxels);
  // The voxels around the sensor are the ones kept: a plane inserted next to it still matches.
  vm.insert(
      sample_plane(rng, position + Eigen::Vector3d(-2, -2, -1), {4, 0, 0}, {0, 4, 0}, 4000, 0.005));
  vm.slide(position);
  PlaneMatch m;
  EXPECT_TRUE(vm.match(position + Eigen::Vector3d(0.3, 0.2, -1.0 + 0.002),
                       Eigen::Matrix3d::Identity() * 1e-4, m));
}

// The map keeps its counts as it changes instead of walking every voxel per report: they must
// equal a walk after every kind of change - new voxels, planes that split into octants (a wall
// corner) or freeze, voxels that slide out, voxels over the budget, and the release of dropped
// voxels over the following inserts.
TEST(VoxelMap, TheCountsItKeepsEqualAWalkOfTheMap) {
  LioParams lio;
  MapParams map;
  map.half_extent_m = 15.0;
  map.slide_threshold_m = 4.0;
  map.max_voxels = 6000;
  VoxelMap vm(lio, map);
  SerialTaskRunner runner;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto expect_counts_equal_a_walk = [&](int step) {
    const VoxelMapStats kept = vm.stats();
    const VoxelMapStats walked = vm.count_by_traversal();
    EXPECT_EQ(kept.root_voxels, walked.root_voxels) << step;
    EXPECT_EQ(kept.nodes, walked.nodes) << step;
    EXPECT_EQ(kept.planes, walked.planes) << step;
    EXPECT_EQ(kept.frozen_nodes, walked.frozen_nodes) << step;
    EXPECT_EQ(kept.stored_points, walked.stored_points) << step;
    EXPECT_EQ(kept.bytes, walked.bytes) << step;
    EXPECT_EQ(kept.retired_voxels, walked.retired_voxels) << step;
  };
  bool split = false, frozen = false, slid = false, evicted = false, released = false;
  std::size_t last_retired = 0;
  for (int step = 0; step < 40; ++step) {
    const Eigen::Vector3d at(3.0 * step, 0.0, 1.0);
    // Floor, a wall meeting it (corner voxels split) and scattered points (no plane).
    auto scan =
        sample_plane(rng, at + Eigen::Vector3d(-4, -4, 0.1), {8, 0, 0}, {0, 8, 0}, 6000, 0.01);
    const auto wall =
        sample_plane(rng, at + Eigen::Vector3d(-4, 3.9, 0.1), {8, 0, 0}, {0, 0, 3}, 2000, 0.01);
    scan.insert(scan.end(), wall.begin(), wall.end());
    for (int i = 0; i < 1500; ++i) {
      CovPoint p;
      p.p = at + Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 12.0;
      p.cov = Eigen::Matrix3d::Identity() * 1e-4;
      scan.push_back(p);
    }
    vm.insert(scan, step % 2 == 0 ? &runner : nullptr);
    expect_counts_equal_a_walk(step);
    released = released || vm.stats().retired_voxels < last_retired;
    const VoxelMapStats before = vm.stats();
    if (vm.slide(at) > 0) slid = true;
    expect_counts_equal_a_walk(step);
    const VoxelMapStats after = vm.stats();
    split = split || after.nodes > after.root_voxels;
    frozen = frozen || after.frozen_nodes > 0;
    evicted = evicted || after.evicted_voxels > 0;
    last_retired = after.retired_voxels;
    EXPECT_LE(after.nodes, before.nodes) << step;  // sliding only removes
  }
  // Every kind of change happened.
  EXPECT_TRUE(split);
  EXPECT_TRUE(frozen);
  EXPECT_TRUE(slid);
  EXPECT_TRUE(evicted);
  EXPECT_TRUE(released);
}

}  // namespace
}  // namespace livod::estimator
