#include "tools/sim/trajectory.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

namespace livod::sim {
namespace {

TrajectorySpec aggressive_spec() {
  TrajectorySpec s;
  s.x = {0.0, 0.3, {{1.5, 0.7, 0.1}, {0.2, 2.3, 1.0}}};
  s.y = {1.0, 0.0, {{1.0, 0.9, 0.4}, {0.1, 3.1, 0.0}}};
  s.z = {1.2, 0.0, {{0.15, 1.7, 0.3}}};
  s.roll = {0.0, 0.0, {{0.4, 2.0, 0.0}}};
  s.pitch = {0.0, 0.0, {{0.3, 2.6, 0.5}}};
  s.yaw = {0.2, 0.0, {{1.2, 3.0, 0.0}}};  // peak yaw rate 3.6 rad/s ~ 206 deg/s
  s.static_duration = 1.0;
  s.ramp_duration = 1.5;
  return s;
}

Eigen::Vector3d log_so3(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

TEST(Trajectory, DerivativesMatchFiniteDifferences) {
  const Trajectory traj(aggressive_spec());
  const double h = 1e-5;
  for (double t : {0.5, 1.2, 1.9, 2.4, 3.0, 7.3, 20.0}) {
    const auto s = traj.at(t);
    const auto sp = traj.at(t + h);
    const auto sm = traj.at(t - h);
    const Eigen::Vector3d v_fd = (sp.p_world - sm.p_world) / (2 * h);
    const Eigen::Vector3d a_fd = (sp.v_world - sm.v_world) / (2 * h);
    EXPECT_LT((v_fd - s.v_world).norm(), 1e-6) << "t=" << t;
    EXPECT_LT((a_fd - s.a_world).norm(), 1e-5) << "t=" << t;
    // omega_body = Log(R(t)^T R(t+h)) / h (central version)
    const Eigen::Vector3d w_fd = log_so3(sm.R_world_body.transpose() * sp.R_world_body) / (2 * h);
    EXPECT_LT((w_fd - s.omega_body).norm(), 1e-5) << "t=" << t;
  }
}

TEST(Trajectory, StartsAtRestAndIsC2AcrossTheRamp) {
  const Trajectory traj(aggressive_spec());
  const auto s0 = traj.at(0.0);
  const auto s1 = traj.at(0.99);
  EXPECT_EQ(s0.p_world, s1.p_world);
  EXPECT_EQ(s1.v_world.norm(), 0.0);
  EXPECT_EQ(s1.omega_body.norm(), 0.0);
  // Acceleration is continuous at the start and end of the ramp.
  for (double edge : {1.0, 2.5}) {
    const auto before = traj.at(edge - 1e-7);
    const auto after = traj.at(edge + 1e-7);
    EXPECT_LT((before.a_world - after.a_world).norm(), 1e-4) << "edge " << edge;
  }
}

TEST(Trajectory, HeadingFollowingYawPointsAlongTheVelocity) {
  TrajectorySpec s;
  s.x = {0.0, 10.0, {}};
  s.y = {0.0, 0.0, {{3.0, 0.2, 0.0}}};
  s.yaw_follows_heading = true;
  const Trajectory traj(s);
  for (double t : {5.0, 9.0, 14.0}) {
    const auto st = traj.at(t);
    const Eigen::Vector3d forward = st.R_world_body.col(0);
    EXPECT_NEAR(forward.head<2>().normalized().dot(st.v_world.head<2>().normalized()), 1.0, 1e-12);
    const double h = 1e-5;
    const Eigen::Vector3d w_fd =
        log_so3(traj.at(t - h).R_world_body.transpose() * traj.at(t + h).R_world_body) / (2 * h);
    EXPECT_LT((w_fd - st.omega_body).norm(), 1e-6);
  }
}

// Integrates ideal IMU samples (RK4 on samples at t, t + dt/2, t + dt) and compares with the
// trajectory: the simulator's IMU must be the exact derivative of its ground truth.
TEST(Trajectory, NoiseFreeImuIntegratesToTheGroundTruthOver60s) {
  const Trajectory traj(aggressive_spec());
  const Eigen::Vector3d g(0.0, 0.0, -9.81);
  const double dt = 0.002;  // 500 Hz integration steps (samples at 1 kHz for the midpoints)
  auto s0 = traj.at(0.0);
  Eigen::Quaterniond q(s0.R_world_body);
  Eigen::Vector3d p = s0.p_world;
  Eigen::Vector3d v = s0.v_world;
  auto imu_at = [&](double t) { return ideal_imu(traj.at(t), g); };
  // State derivative for RK4: q' = q * (0, w/2), v' = R a + g, p' = v.
  struct D {
    Eigen::Vector4d q;
    Eigen::Vector3d v, p;
  };
  auto deriv = [&](const Eigen::Quaterniond& qq, const Eigen::Vector3d& vv, const ImuTruth& m) {
    const Eigen::Quaterniond w(0.0, 0.5 * m.gyro_rad_s.x(), 0.5 * m.gyro_rad_s.y(),
                               0.5 * m.gyro_rad_s.z());
    const Eigen::Quaterniond dq = qq * w;
    return D{dq.coeffs(), qq.toRotationMatrix() * m.accel_m_s2 + g, vv};
  };
  auto add = [](const Eigen::Quaterniond& qq, const Eigen::Vector4d& dq, double h) {
    Eigen::Quaterniond r;
    r.coeffs() = qq.coeffs() + h * dq;
    return r;
  };
  const int steps = static_cast<int>(60.0 / dt);
  for (int k = 0; k < steps; ++k) {
    const double t = k * dt;
    const auto m0 = imu_at(t);
    const auto mh = imu_at(t + dt / 2);
    const auto m1 = imu_at(t + dt);
    const D k1 = deriv(q, v, m0);
    const D k2 = deriv(add(q, k1.q, dt / 2), v + dt / 2 * k1.v, mh);
    const D k3 = deriv(add(q, k2.q, dt / 2), v + dt / 2 * k2.v, mh);
    const D k4 = deriv(add(q, k3.q, dt), v + dt * k3.v, m1);
    const Eigen::Vector3d v_new = v + dt / 6 * (k1.v + 2 * k2.v + 2 * k3.v + k4.v);
    p += dt / 6 * (k1.p + 2 * (v + dt / 2 * k1.v) + 2 * (v + dt / 2 * k2.v) + (v + dt * k3.v));
    q.coeffs() += dt / 6 * (k1.q + 2 * k2.q + 2 * k3.q + k4.q);
    q.normalize();
    v = v_new;
  }
  const auto truth = traj.at(steps * dt);
  const double pos_err = (p - truth.p_world).norm();
  const double rot_err_deg =
      log_so3(q.toRotationMatrix().transpose() * truth.R_world_body).norm() * 180.0 / M_PI;
  EXPECT_LT(pos_err, 1e-3) << "position error " << pos_err << " m";
  EXPECT_LT(rot_err_deg, 0.01) << "rotation error " << rot_err_deg << " deg";
}

}  // namespace
}  // namespace livod::sim
