#include "estimator/imu/initializer.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

namespace livod::estimator {
namespace {

ImuSample sample(std::int64_t t_ns, const Eigen::Vector3d& gyro, const Eigen::Vector3d& acc) {
  ImuSample s;
  s.stamp.mapped = MappedTime(t_ns);
  s.gyro_rad_s = gyro;
  s.accel_m_s2 = acc;
  return s;
}

TEST(ImuInitializer, StaticWindowGivesGravityAndGyroBias) {
  ImuParams params;
  ImuInitializer init(params);
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0.0, 0.01);
  const Eigen::Vector3d bias(0.003, -0.002, 0.001);
  const Eigen::Vector3d up = Eigen::Vector3d(0.1, -0.2, 0.97).normalized();
  bool done = false;
  for (int i = 0; i < 30; ++i) {
    done = init.add(sample(i * 5'000'000, bias + Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.1,
                           up * 9.81 + Eigen::Vector3d(n(rng), n(rng), n(rng))));
  }
  ASSERT_TRUE(done) << init.status();
  const auto& b = *init.result();
  EXPECT_LT((b.x.bias_gyro - bias).norm(), 1e-3);
  EXPECT_LT((b.x.gravity_world + up * 9.81).norm(), 0.01);
  EXPECT_EQ(init.time().ns, 29 * 5'000'000);
  EXPECT_EQ(init.rejections(), 0);
}

TEST(ImuInitializer, RefusesWhileMovingAndSaysSo) {
  ImuParams params;
  ImuInitializer init(params);
  for (int i = 0; i < 200; ++i) {
    const double t = i * 0.005;
    init.add(sample(i * 5'000'000, Eigen::Vector3d(0.0, 0.0, 1.5 * std::sin(6.0 * t)),
                    Eigen::Vector3d(2.0 * std::sin(9.0 * t), 0.0, 9.81)));
  }
  EXPECT_FALSE(init.done());
  EXPECT_GT(init.rejections(), 0);
  EXPECT_NE(init.status().find("moving"), std::string::npos) << init.status();
  // Once the platform stops, initialisation completes.
  for (int i = 200; i < 260 && !init.done(); ++i) {
    init.add(sample(i * 5'000'000, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, 9.81)));
  }
  EXPECT_TRUE(init.done());
}

TEST(ImuInitializer, DetectsAccelerometerInG) {
  ImuInitializer init(ImuParams{});
  for (int i = 0; i < 40; ++i) {
    init.add(sample(i * 5'000'000, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, 1.0)));
  }
  EXPECT_FALSE(init.done());
  EXPECT_NE(init.status().find("g to m/s^2"), std::string::npos) << init.status();
}

TEST(ImuInitializer, GravityAlignPutsGravityOnMinusZ) {
  ImuParams params;
  params.gravity_align = true;
  params.init_time_s = 0.1;
  ImuInitializer init(params);
  const Eigen::Vector3d up = Eigen::Vector3d(0.3, 0.1, 0.9).normalized();
  for (int i = 0; i < 40 && !init.done(); ++i) {
    init.add(sample(i * 5'000'000, Eigen::Vector3d::Zero(), up * 9.8));
  }
  ASSERT_TRUE(init.done());
  const auto& x = init.result()->x;
  EXPECT_LT((x.gravity_world - Eigen::Vector3d(0, 0, -9.81)).norm(), 1e-12);
  // The measured specific force, rotated into the world, points straight up.
  EXPECT_LT((x.R_world_imu * up - Eigen::Vector3d::UnitZ()).norm(), 1e-9);
}

}  // namespace
}  // namespace livod::estimator

namespace livod::estimator {
namespace {

// The world frame is the IMU frame at initialisation: the initial pose is exact by definition,
// and the gravity error is the accelerometer bias's part across gravity - the same vector as the
// b_a error, so the two start fully correlated. Checked against the truth the window came from: a
// biased accelerometer makes the initial gravity wrong by the bias's horizontal part, which must
// lie within the covariance the initialiser reports, along the direction it correlates with b_a.
TEST(ImuInitializer, GravityAndAccelBiasStartCorrelatedPoseExact) {
  for (const bool align : {false, true}) {
    ImuParams params;
    params.gravity_align = align;
    ImuInitializer init(params);
    const Eigen::Vector3d up = Eigen::Vector3d(0.05, -0.1, 0.99).normalized();
    const Eigen::Vector3d accel_bias(0.03, -0.02, 0.05);
    bool done = false;
    for (int i = 0; i < 30 && !done; ++i) {
      done = init.add(sample(i * 5'000'000, Eigen::Vector3d::Zero(), up * 9.81 + accel_bias));
    }
    ASSERT_TRUE(done) << init.status();
    const Belief& b = *init.result();
    EXPECT_LT((b.P.block<3, 3>(kRot, kRot).maxCoeff()), 1e-9);
    EXPECT_LT((b.P.block<3, 3>(kPos, kPos).maxCoeff()), 1e-9);
    // True gravity in the estimator's world: R0 (-up |g|).
    const Eigen::Vector3d g_true = b.x.R_world_imu * (-up * 9.81);
    const Eigen::Vector3d g_error = g_true - b.x.gravity_world;
    // The error is R0 times the bias's part across gravity.
    const Eigen::Vector3d across = accel_bias - up * up.dot(accel_bias);
    EXPECT_LT((g_error - b.x.R_world_imu * across).norm(), 5e-4) << g_error.transpose();
    // ... and the covariance expects it: a Mahalanobis distance of a 1-sigma-ish bias, and the
    // cross covariance maps a b_a error onto the same gravity error.
    const Eigen::Matrix3d P_gg = b.P.block<3, 3>(kGrav, kGrav);
    const Eigen::Matrix3d P_gb = b.P.block<3, 3>(kGrav, kBa);
    const Eigen::Matrix3d P_bb = b.P.block<3, 3>(kBa, kBa);
    EXPECT_LT(g_error.dot(P_gg.inverse() * g_error), 9.0);
    const Eigen::Vector3d predicted = P_gb * P_bb.inverse() * accel_bias;  // E[g err | b_a err]
    EXPECT_LT((predicted - g_error).norm(), 5e-4) << predicted.transpose();
    // Positive definite.
    const Eigen::SelfAdjointEigenSolver<StateMatrix> es(b.P);
    EXPECT_GT(es.eigenvalues().minCoeff(), 0.0);
  }
}

}  // namespace
}  // namespace livod::estimator
