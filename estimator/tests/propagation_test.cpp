#include "estimator/imu/propagation.hpp"

#include <gtest/gtest.h>

#include <random>

#include "estimator/filter/esikf.hpp"

namespace livod::estimator {
namespace {

State random_state(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  State x;
  x.R_world_imu = so3::exp(Eigen::Vector3d(n(rng), n(rng), n(rng)));
  x.p_world_imu = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 3.0;
  x.v_world = Eigen::Vector3d(n(rng), n(rng), n(rng));
  x.bias_gyro = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.01;
  x.bias_accel = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.05;
  x.gravity_world = Eigen::Vector3d(0.1 * n(rng), 0.1 * n(rng), -9.81);
  x.inv_exposure = 1.2;
  return x;
}

TEST(Propagation, JacobianMatchesFiniteDifferences) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  ImuParams params;
  for (int trial = 0; trial < 20; ++trial) {
    const State x = random_state(rng);
    const ImuReading m{Eigen::Vector3d(n(rng), n(rng), n(rng)) * 2.0,
                       Eigen::Vector3d(n(rng), n(rng), 9.81 + n(rng))};
    const double dt = 0.005 + 0.02 * trial / 20.0;
    const StateMatrix F = propagation_jacobian(x, m, dt, params);
    const State y = propagate_state(x, m, dt);
    StateMatrix F_fd;
    const double h = 1e-6;
    for (int i = 0; i < kStateDim; ++i) {
      StateVector d = StateVector::Zero();
      d(i) = h;
      const StateVector plus = propagate_state(x.boxplus(d), m, dt).boxminus(y);
      const StateVector minus = propagate_state(x.boxplus(-d), m, dt).boxminus(y);
      F_fd.col(i) = (plus - minus) / (2 * h);
    }
    EXPECT_LT((F - F_fd).cwiseAbs().maxCoeff(), 1e-6) << "trial " << trial << "\n" << (F - F_fd);
  }
}

TEST(Propagation, BiasAndGravityCouplingsFollowTheSwitches) {
  ImuParams params;
  params.bias_est = false;
  params.gravity_est = false;
  const StateMatrix F = propagation_jacobian(State{}, ImuReading{}, 0.01, params);
  EXPECT_EQ((F.block<3, 3>(kVel, kBa).norm()), 0.0);
  EXPECT_EQ((F.block<3, 3>(kRot, kBg).norm()), 0.0);
  EXPECT_EQ((F.block<3, 3>(kVel, kGrav).norm()), 0.0);
  const StateMatrix Q = process_noise(State{}, 0.01, params, 0.1);
  EXPECT_EQ((Q.block<3, 3>(kBg, kBg).norm()), 0.0);
}

TEST(Propagation, BiasNoiseComesFromTheConfiguration) {
  ImuParams params;
  params.b_gyr_cov = 3e-3;
  params.b_acc_cov = 7e-2;
  const StateMatrix Q = process_noise(State{}, 0.01, params, 0.0);
  EXPECT_DOUBLE_EQ(Q(kBg, kBg), 3e-3 * 1e-4);
  EXPECT_DOUBLE_EQ(Q(kBa + 2, kBa + 2), 7e-2 * 1e-4);
}

// A linear-Gaussian check of the iterated update: observing position directly with known noise
// must give the Kalman posterior exactly, in one iteration.
TEST(IteratedUpdate, DirectPositionObservationGivesTheKalmanPosterior) {
  Belief b;
  b.P = StateMatrix::Identity() * 0.04;
  const Eigen::Vector3d z_pos(0.3, -0.2, 0.1);
  const double r = 0.01;
  auto lin = [&](const State& x, NormalEquations& eq) {
    Eigen::Matrix<double, 3, kStateDim> H = Eigen::Matrix<double, 3, kStateDim>::Zero();
    H.block<3, 3>(0, kPos).setIdentity();
    const Eigen::Vector3d z = z_pos - x.p_world_imu;
    eq.HtRinvH += H.transpose() * H / r;
    eq.HtRinvz += H.transpose() * z / r;
    eq.measurements += 3;
    return true;
  };
  IterationParams params;
  const auto report = iterated_update(b, lin, params);
  EXPECT_TRUE(report.converged);
  EXPECT_LE(report.iterations, 2);
  const double k = 0.04 / (0.04 + r);
  EXPECT_LT((b.x.p_world_imu - k * z_pos).norm(), 1e-12);
  EXPECT_NEAR(b.P(kPos, kPos), 0.04 * r / (0.04 + r), 1e-12);
  EXPECT_NEAR(b.P(kVel, kVel), 0.04, 1e-12);  // unobserved states keep their prior
}

// A nonlinear rotation observation: the iterations converge to the MAP estimate.
TEST(IteratedUpdate, ConvergesOnANonlinearRotationMeasurement) {
  Belief b;
  b.P = StateMatrix::Identity() * 1.0;  // weak prior
  const Eigen::Matrix3d R_true = so3::exp(Eigen::Vector3d(0.3, -0.4, 0.5));
  const std::vector<Eigen::Vector3d> dirs = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}};
  auto lin = [&](const State& x, NormalEquations& eq) {
    for (const auto& d : dirs) {
      const Eigen::Vector3d pred = x.R_world_imu * d;
      // d pred / d dth for R Exp(dth) d = -R [d]x
      Eigen::Matrix<double, 3, kStateDim> H = Eigen::Matrix<double, 3, kStateDim>::Zero();
      H.block<3, 3>(0, kRot) = -x.R_world_imu * so3::hat(d);
      const Eigen::Vector3d z = R_true * d - pred;
      eq.HtRinvH += H.transpose() * H / 1e-6;
      eq.HtRinvz += H.transpose() * z / 1e-6;
      eq.measurements += 3;
    }
    return true;
  };
  IterationParams params;
  params.max_iterations = 10;
  const auto report = iterated_update(b, lin, params);
  EXPECT_TRUE(report.converged);
  EXPECT_GT(report.iterations, 1);
  EXPECT_LT(so3::log(R_true.transpose() * b.x.R_world_imu).norm(), 1e-5);
}

}  // namespace
}  // namespace livod::estimator
