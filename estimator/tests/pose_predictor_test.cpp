// PosePredictor: the IMU-rate pose follows a known motion, and a late filter estimate is carried
// forward through the samples that arrived after it exactly as if they came after it.

#include "estimator/imu/pose_predictor.hpp"

#include <gtest/gtest.h>

#include "core/so3.hpp"

namespace livod::estimator {
namespace {

constexpr double kG = 9.81;
const Eigen::Vector3d kOmega(0.1, -0.2, 0.5);  // rad/s, body frame

// A body at rest in position, turning at kOmega: the accelerometer reads R^T (0, 0, g).
ImuSample turning_sample(std::int64_t t_ns) {
  const double t = static_cast<double>(t_ns) * 1e-9;
  const Eigen::Matrix3d R = so3::exp(kOmega * t);
  ImuSample s;
  s.stamp.mapped = MappedTime(t_ns);
  s.gyro_rad_s = kOmega;
  s.accel_m_s2 = R.transpose() * Eigen::Vector3d(0.0, 0.0, kG);
  return s;
}

Belief start_belief() {
  Belief b;
  b.x.gravity_world = Eigen::Vector3d(0.0, 0.0, -kG);
  b.P = StateMatrix::Identity() * 1e-6;
  return b;
}

TEST(PosePredictor, NothingBeforeTheFirstEstimate) {
  PosePredictor p(ImuParams{});
  EXPECT_FALSE(p.add(turning_sample(0)));
  EXPECT_FALSE(p.has_estimate());
}

TEST(PosePredictor, FollowsAConstantTurn) {
  PosePredictor p(ImuParams{});
  p.reset(MappedTime(0), start_belief());
  std::optional<PredictedPose> last;
  for (std::int64_t i = 1; i <= 400; ++i) {  // 2 s at 200 Hz
    last = p.add(turning_sample(i * 5'000'000));
    ASSERT_TRUE(last);
  }
  const double t = 2.0;
  const Eigen::Matrix3d R_true = so3::exp(kOmega * t);
  EXPECT_LT(so3::log(R_true.transpose() * last->belief.x.R_world_imu).norm(), 1e-9);
  // The filter's step rotates the mean of the two samples with the rotation at the start of the
  // interval: here that leaves a constant world acceleration error of dt/2 |omega x g| =
  // 5.5 mm/s^2, i.e. 11 mm/s and 11 mm after 2 s. Larger errors mean a wrong propagation.
  EXPECT_LT(last->belief.x.v_world.norm(), 0.015);
  EXPECT_LT(last->belief.x.p_world_imu.norm(), 0.015);
  EXPECT_EQ(last->since_update, Nanoseconds(2'000'000'000));
  EXPECT_TRUE(last->omega_imu.isApprox(kOmega));
  // The covariance grows with the propagation (honest IMU-only uncertainty).
  EXPECT_GT(last->belief.P(kPos, kPos), 1e-6);
}

TEST(PosePredictor, LateEstimateIsCarriedThroughNewerSamples) {
  // Samples up to 1.0 s arrive; then an estimate for 0.9 s (a filter update lags the IMU).
  PosePredictor late(ImuParams{});
  late.reset(MappedTime(0), start_belief());
  for (std::int64_t i = 1; i <= 200; ++i) late.add(turning_sample(i * 5'000'000));
  Belief estimate = start_belief();
  estimate.x.p_world_imu = Eigen::Vector3d(1.0, 2.0, 3.0);  // the update moved the pose
  estimate.x.R_world_imu = so3::exp(kOmega * 0.9);
  const MappedTime t_estimate(900'000'000);
  late.reset(t_estimate, estimate);
  const auto a = late.add(turning_sample(1'005'000'000));

  // The same estimate followed by the same samples, one by one.
  PosePredictor fresh(ImuParams{});
  fresh.reset(t_estimate, estimate);
  std::optional<PredictedPose> b;
  for (std::int64_t i = 181; i <= 201; ++i) b = fresh.add(turning_sample(i * 5'000'000));

  ASSERT_TRUE(a);
  ASSERT_TRUE(b);
  EXPECT_EQ(a->t, b->t);
  EXPECT_TRUE(a->belief.x.p_world_imu.isApprox(b->belief.x.p_world_imu, 1e-12));
  EXPECT_TRUE(a->belief.x.R_world_imu.isApprox(b->belief.x.R_world_imu, 1e-12));
  EXPECT_TRUE(a->belief.P.isApprox(b->belief.P, 1e-12));
  EXPECT_EQ(a->since_update, Nanoseconds(105'000'000));
  EXPECT_NEAR(a->belief.x.p_world_imu.x(), 1.0, 1e-3);
}

TEST(PosePredictor, OldSamplesIgnoredAndBufferBounded) {
  PosePredictor p(ImuParams{}, 0.0, 8);
  for (std::int64_t i = 1; i <= 20; ++i) p.add(turning_sample(i * 5'000'000));
  EXPECT_EQ(p.dropped_samples(), 12U);
  p.reset(MappedTime(0), start_belief());
  EXPECT_FALSE(p.add(turning_sample(50'000'000)));  // not newer than the newest sample
  EXPECT_TRUE(p.add(turning_sample(105'000'000)));
}

}  // namespace
}  // namespace livod::estimator
