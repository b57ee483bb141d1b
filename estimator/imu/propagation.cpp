#include "estimator/imu/propagation.hpp"

namespace livod::estimator {

State propagate_state(const State& x, const ImuReading& m, double dt) {
  const Eigen::Vector3d w = m.gyro_rad_s - x.bias_gyro;
  const Eigen::Vector3d a = m.accel_m_s2 - x.bias_accel;
  const Eigen::Vector3d acc_world = x.R_world_imu * a + x.gravity_world;
  State y = x;
  y.R_world_imu = x.R_world_imu * so3::exp(w * dt);
  y.p_world_imu = x.p_world_imu + x.v_world * dt + 0.5 * acc_world * dt * dt;
  y.v_world = x.v_world + acc_world * dt;
  return y;
}

StateMatrix propagation_jacobian(const State& x, const ImuReading& m, double dt,
                                 const ImuParams& params) {
  const Eigen::Vector3d w = m.gyro_rad_s - x.bias_gyro;
  const Eigen::Vector3d a = m.accel_m_s2 - x.bias_accel;
  const Eigen::Matrix3d R = x.R_world_imu;
  const Eigen::Matrix3d Ra_hat = R * so3::hat(a);
  StateMatrix F = StateMatrix::Identity();
  // Rotation: R Exp(dth) Exp((w - dbg) dt) = R Exp(w dt) Exp(Exp(-w dt) dth - Jr(w dt) dt dbg)
  F.block<3, 3>(kRot, kRot) = so3::exp(-w * dt);
  if (params.bias_est) F.block<3, 3>(kRot, kBg) = -so3::right_jacobian(w * dt) * dt;
  // Position and velocity: R Exp(dth) (a - dba) ~ R a - R [a]x dth - R dba
  F.block<3, 3>(kPos, kVel) = Eigen::Matrix3d::Identity() * dt;
  F.block<3, 3>(kPos, kRot) = -0.5 * Ra_hat * dt * dt;
  F.block<3, 3>(kVel, kRot) = -Ra_hat * dt;
  if (params.bias_est) {
    F.block<3, 3>(kPos, kBa) = -0.5 * R * dt * dt;
    F.block<3, 3>(kVel, kBa) = -R * dt;
  }
  if (params.gravity_est) {
    F.block<3, 3>(kPos, kGrav) = 0.5 * Eigen::Matrix3d::Identity() * dt * dt;
    F.block<3, 3>(kVel, kGrav) = Eigen::Matrix3d::Identity() * dt;
  }
  return F;
}

StateMatrix process_noise(const State& x, double dt, const ImuParams& params, double inv_expo_cov) {
  StateMatrix Q = StateMatrix::Zero();
  const double dt2 = dt * dt;
  Q.block<3, 3>(kRot, kRot) = Eigen::Matrix3d::Identity() * params.gyr_cov * dt2;
  Q.block<3, 3>(kVel, kVel) = x.R_world_imu * (Eigen::Matrix3d::Identity() * params.acc_cov) *
                              x.R_world_imu.transpose() * dt2;
  Q(kExpo, kExpo) = inv_expo_cov * dt2;
  if (params.bias_est) {
    Q.block<3, 3>(kBg, kBg) = Eigen::Matrix3d::Identity() * params.b_gyr_cov * dt2;
    Q.block<3, 3>(kBa, kBa) = Eigen::Matrix3d::Identity() * params.b_acc_cov * dt2;
  }
  return Q;
}

void propagate(Belief& belief, const ImuReading& m, double dt, const ImuParams& params,
               double inv_expo_cov) {
  const StateMatrix F = propagation_jacobian(belief.x, m, dt, params);
  const StateMatrix Q = process_noise(belief.x, dt, params, inv_expo_cov);
  belief.x = propagate_state(belief.x, m, dt);
  belief.P = F * belief.P * F.transpose() + Q;
}

}  // namespace livod::estimator
