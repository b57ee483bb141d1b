// Umeyama alignment: recovers a known similarity applied to real ground truth, is a least-squares
// optimum (zero gradient by finite differences on the manifold), and never returns a reflection.

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "core/so3.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/eval/alignment.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace livod::eval {
namespace {

std::vector<Eigen::Vector3d> positions(const Trajectory& t) {
  std::vector<Eigen::Vector3d> p;
  for (const RigidTransform3d& pose : t.poses) p.push_back(pose.translation);
  return p;
}

double cost(const std::vector<Eigen::Vector3d>& est, const std::vector<Eigen::Vector3d>& gt,
            const Eigen::Matrix3d& r, const Eigen::Vector3d& t, double s) {
  double c = 0.0;
  for (std::size_t i = 0; i < est.size(); ++i) c += (gt[i] - (s * r * est[i] + t)).squaredNorm();
  return c;
}

TEST(Alignment, RecoversAKnownSimilarityFromRealGroundTruth) {
  const Trajectory gt = read_tum(test::data_path("trajectory_eval/freiburg1_xyz-groundtruth.txt"));
  // est = S⁻¹(gt): the estimate lives in a frame rotated, shifted and scaled by 0.37.
  const Eigen::Matrix3d r_true = so3::exp(Eigen::Vector3d(0.4, -1.1, 2.3));
  const Eigen::Vector3d t_true(3.0, -7.5, 1.25);
  const double s_true = 2.7;
  Trajectory est = gt;
  for (RigidTransform3d& p : est.poses) {
    p.translation = r_true.transpose() * (p.translation - t_true) / s_true;
    p.rotation = r_true.transpose() * p.rotation;
  }
  const Similarity3 sim = align(gt, est, Alignment::kSim3);
  EXPECT_LT((sim.rotation - r_true).norm(), 1e-9);
  EXPECT_LT((sim.translation - t_true).norm(), 1e-9);
  EXPECT_NEAR(sim.scale, s_true, 1e-9);
  const Trajectory back = transformed(est, sim);
  for (std::size_t i = 0; i < gt.size(); ++i) {
    ASSERT_LT((back.poses[i].translation - gt.poses[i].translation).norm(), 1e-9);
    ASSERT_LT((back.poses[i].rotation - gt.poses[i].rotation).norm(), 1e-9);
  }
  // SE(3) alignment keeps the scale at 1, so it cannot undo the shrink.
  const Similarity3 rigid = align(gt, est, Alignment::kSe3);
  EXPECT_EQ(rigid.scale, 1.0);
  EXPECT_GT(cost(positions(est), positions(gt), rigid.rotation, rigid.translation, 1.0), 1e-3);
  // No alignment is the identity.
  const Similarity3 none = align(gt, est, Alignment::kNone);
  EXPECT_TRUE(none.rotation.isIdentity(0.0));
  EXPECT_EQ(none.scale, 1.0);
}

TEST(Alignment, IsALeastSquaresOptimumOnNoisyData) {
  // KITTI ORB vs ground truth: no exact solution; the cost gradient over (δθ, δt, δs) at the
  // returned parameters must vanish (central differences, perturbing R on the right).
  const auto dir = std::string("trajectory_eval/");
  const auto gt = positions(read_kitti(test::data_path(dir + "KITTI_00_gt.txt")));
  const auto est = positions(read_kitti(test::data_path(dir + "KITTI_00_ORB.txt")));
  for (bool with_scale : {false, true}) {
    SCOPED_TRACE(with_scale ? "sim3" : "se3");
    const Similarity3 s = umeyama(est, gt, with_scale);
    const double c0 = cost(est, gt, s.rotation, s.translation, s.scale);
    const double h = 1e-5;
    for (int k = 0; k < 7; ++k) {
      if (k == 6 && !with_scale) continue;
      Eigen::Matrix<double, 7, 1> d = Eigen::Matrix<double, 7, 1>::Zero();
      d(k) = h;
      const auto at = [&](const Eigen::Matrix<double, 7, 1>& e) {
        return cost(est, gt, so3::boxplus(s.rotation, Eigen::Vector3d(e.head<3>())),
                    s.translation + e.segment<3>(3), s.scale + e(6));
      };
      const double grad = (at(d) - at(-d)) / (2 * h);
      // Relative to the cost's own size: its gradient for a unit step is O(c0).
      EXPECT_LT(std::abs(grad), 1e-6 * c0) << "parameter " << k;
    }
  }
}

TEST(Alignment, NeverReturnsAReflection) {
  // A mirrored point set: the best orthogonal map is a reflection, Umeyama's S must flip it.
  std::mt19937 rng(3);
  std::normal_distribution<double> n;
  std::vector<Eigen::Vector3d> est;
  std::vector<Eigen::Vector3d> gt;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d p(n(rng), n(rng), 0.1 * n(rng));
    est.push_back(p);
    gt.emplace_back(p.x(), p.y(), -p.z());
  }
  const Similarity3 s = umeyama(est, gt, true);
  EXPECT_NEAR(s.rotation.determinant(), 1.0, 1e-12);
  EXPECT_LT((s.rotation.transpose() * s.rotation - Eigen::Matrix3d::Identity()).norm(), 1e-12);
}

TEST(Alignment, RejectsDegenerateInput) {
  const std::vector<Eigen::Vector3d> one = {Eigen::Vector3d(1, 2, 3)};
  EXPECT_THROW(umeyama(one, one, false), Error);
  const std::vector<Eigen::Vector3d> same(5, Eigen::Vector3d(1, 2, 3));
  EXPECT_THROW(umeyama(same, same, true), Error);
  const std::vector<Eigen::Vector3d> two = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0)};
  EXPECT_THROW(umeyama(two, one, false), Error);
  EXPECT_EQ(parse_alignment("sim3"), Alignment::kSim3);
  EXPECT_FALSE(parse_alignment("sim(3)").has_value());
}

}  // namespace
}  // namespace livod::eval
