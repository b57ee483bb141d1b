// Statistics, RPE pair selection and the relative/absolute error definitions, on hand-made
// trajectories whose errors are known in closed form.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "core/so3.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/eval/metrics.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace livod::eval {
namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;

TEST(Statistics, MatchDefinitions) {
  const std::vector<double> e = {4.0, 1.0, 3.0, 2.0};
  const ErrorStatistics s = compute_statistics(e);
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);  // mean of the two middle values
  EXPECT_DOUBLE_EQ(s.sse, 30.0);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));  // population, not sample, deviation
  EXPECT_EQ(s.min, 1.0);
  EXPECT_EQ(s.max, 4.0);
  const std::vector<double> odd = {5.0, 0.5, 2.0};
  EXPECT_EQ(compute_statistics(odd).median, 2.0);
  EXPECT_THROW(compute_statistics(std::vector<double>{}), Error);
}

// A straight walk along x, one metre and 0.5 s per pose.
Trajectory straight_line(std::size_t n) {
  Trajectory t;
  for (std::size_t i = 0; i < n; ++i) {
    t.stamps_s.push_back(0.5 * static_cast<double>(i));
    t.poses.emplace_back(Eigen::Matrix3d::Identity(),
                         Eigen::Vector3d(static_cast<double>(i), 0, 0));
  }
  return t;
}

TEST(RpePairs, FramesAreConsecutiveNonOverlapping) {
  const Trajectory t = straight_line(10);
  EXPECT_EQ(select_rpe_pairs(t, 3, DeltaUnit::kFrames),
            (std::vector<IndexPair>{{0, 3}, {3, 6}, {6, 9}}));
  EXPECT_EQ(select_rpe_pairs(t, 1, DeltaUnit::kFrames).size(), 9u);
  EXPECT_THROW(select_rpe_pairs(t, 1.5, DeltaUnit::kFrames), Error);
  EXPECT_THROW(select_rpe_pairs(t, 0, DeltaUnit::kFrames), Error);
}

TEST(RpePairs, MetresFollowTheAccumulatedPath) {
  const Trajectory t = straight_line(12);
  // Path reaches 2.5 m at pose 3, then 2.5 m more at pose 6, 9: evo's consecutive rule starts
  // at the first index whose path reaches delta, not at pose 0.
  EXPECT_EQ(select_rpe_pairs(t, 2.5, DeltaUnit::kMeters), (std::vector<IndexPair>{{3, 6}, {6, 9}}));
  // Exactly reaching delta counts: 3 m at poses 3, 6, 9 (11 is only 2 m past 9).
  EXPECT_EQ(select_rpe_pairs(t, 3.0, DeltaUnit::kMeters), (std::vector<IndexPair>{{3, 6}, {6, 9}}));
  EXPECT_TRUE(select_rpe_pairs(t, 100.0, DeltaUnit::kMeters).empty());
}

TEST(RpePairs, SecondsStartAtTheFirstPose) {
  Trajectory t = straight_line(10);  // 0, 0.5, ..., 4.5 s
  EXPECT_EQ(select_rpe_pairs(t, 1.2, DeltaUnit::kSeconds),
            (std::vector<IndexPair>{{0, 3}, {3, 6}, {6, 9}}));
  t.stamps_s.clear();
  EXPECT_THROW(select_rpe_pairs(t, 1.0, DeltaUnit::kSeconds), Error);
}

TEST(Rpe, IsInvariantToAGlobalRigidTransform) {
  const Trajectory gt = read_tum(test::data_path("trajectory_eval/freiburg1_xyz-groundtruth.txt"));
  const RigidTransform3d T_other_world(so3::exp(Eigen::Vector3d(0.3, -2.0, 1.0)),
                                       Eigen::Vector3d(10, -4, 2));
  Trajectory est = gt;
  for (RigidTransform3d& p : est.poses) p = T_other_world * p;
  const RelativeErrors r =
      relative_pose_errors(gt, est, select_rpe_pairs(est, 10, DeltaUnit::kFrames));
  ASSERT_FALSE(r.pairs.empty());
  for (std::size_t k = 0; k < r.pairs.size(); ++k) {
    ASSERT_LT(r.translation_m[k], 1e-9);
    ASSERT_LT(r.rotation_deg[k], 1e-6);
  }
  // ...while the absolute error sees the transform.
  EXPECT_GT(compute_statistics(absolute_translation_errors(gt, est)).min, 1.0);
}

TEST(Rpe, MeasuresABodyFramePerturbationOfTheLaterPose) {
  // est_j = gt_j · Exp(ξ) at the second pose of each pair: E = Exp(ξ), so the translation error
  // is |V(φ)·ρ| and the rotation error |φ| in degrees.
  const Trajectory gt = read_tum(test::data_path("trajectory_eval/freiburg1_xyz-groundtruth.txt"));
  const std::vector<IndexPair> pairs = select_rpe_pairs(gt, 25, DeltaUnit::kFrames);
  Vector6d xi;
  xi << 0.02, -0.05, 0.01, 0.1, 0.03, -0.2;
  Trajectory est = gt;
  std::vector<bool> perturbed(gt.size(), false);
  for (const auto& [i, j] : pairs) {
    if (j % 50 == 0) {
      est.poses[j] = se3::boxplus(gt.poses[j], xi);
      perturbed[j] = true;
    }
  }
  const RelativeErrors r = relative_pose_errors(gt, est, pairs);
  const double expected_t = se3::exp(xi).translation.norm();
  const double expected_deg = xi.head<3>().norm() * 180.0 / std::numbers::pi;
  int exact = 0;
  for (std::size_t k = 0; k < r.pairs.size(); ++k) {
    const auto [i, j] = r.pairs[k];
    if (perturbed[j] && !perturbed[i]) {
      EXPECT_NEAR(r.translation_m[k], expected_t, 1e-12);
      EXPECT_NEAR(r.rotation_deg[k], expected_deg, 1e-9);
      ++exact;
    } else if (perturbed[i] && !perturbed[j]) {
      // E = Q_rel⁻¹·Exp(−ξ)·Q_rel: a conjugate, so the same angle.
      EXPECT_NEAR(r.rotation_deg[k], expected_deg, 1e-9);
      EXPECT_GT(r.translation_m[k], 1e-3);
    } else {
      EXPECT_LT(r.translation_m[k], 1e-12);
      EXPECT_LT(r.rotation_deg[k], 1e-9);
    }
  }
  EXPECT_GT(exact, 10);
}

TEST(Ape, IsThePositionDistance) {
  Trajectory gt = straight_line(5);
  Trajectory est = gt;
  est.poses[2].translation += Eigen::Vector3d(0, 3, 4);
  est.poses[4].rotation = so3::exp(Eigen::Vector3d(0, 0, 1));  // rotation is not part of it
  const std::vector<double> e = absolute_translation_errors(gt, est);
  EXPECT_EQ(e, (std::vector<double>{0, 0, 5, 0, 0}));
  est.poses.pop_back();
  EXPECT_THROW(absolute_translation_errors(gt, est), Error);
}

}  // namespace
}  // namespace livod::eval
