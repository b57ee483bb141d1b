#pragma once
// The filter state of FAST-LIVO2 (fast-livo2-notes.md 1.2): 19 error-state dimensions on the
// manifold SO(3) x R^16, in FAST-LIVO2's index order (inverse exposure at 6):
//
//   index  0-2   3-5        6               7-9        10-12  13-15  16-18
//   state  R     p          tau             v          b_g    b_a    g
//          R_world_imu, p_world_imu, inverse exposure, v_world, gyro/accel biases, gravity_world
//
// Rotation uses the right perturbation R (+) d = R Exp(d); everything else is additive.

#include <Eigen/Core>

#include "core/so3.hpp"

namespace livod::estimator {

inline constexpr int kStateDim = 19;
inline constexpr int kRot = 0;
inline constexpr int kPos = 3;
inline constexpr int kExpo = 6;
inline constexpr int kVel = 7;
inline constexpr int kBg = 10;
inline constexpr int kBa = 13;
inline constexpr int kGrav = 16;

using StateVector = Eigen::Matrix<double, kStateDim, 1>;
using StateMatrix = Eigen::Matrix<double, kStateDim, kStateDim>;

struct State {
  Eigen::Matrix3d R_world_imu = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_world_imu = Eigen::Vector3d::Zero();
  double inv_exposure = 1.0;  // tau, relative to the first frame (tau_0 = 1 fixes the scale)
  Eigen::Vector3d v_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d bias_gyro = Eigen::Vector3d::Zero();
  Eigen::Vector3d bias_accel = Eigen::Vector3d::Zero();
  Eigen::Vector3d gravity_world{0.0, 0.0, -9.81};

  // x (+) dx
  [[nodiscard]] State boxplus(const StateVector& dx) const {
    State s = *this;
    s.R_world_imu = R_world_imu * so3::exp(dx.segment<3>(kRot));
    s.p_world_imu += dx.segment<3>(kPos);
    s.inv_exposure += dx(kExpo);
    s.v_world += dx.segment<3>(kVel);
    s.bias_gyro += dx.segment<3>(kBg);
    s.bias_accel += dx.segment<3>(kBa);
    s.gravity_world += dx.segment<3>(kGrav);
    return s;
  }

  // this (-) other, so that other.boxplus(this.boxminus(other)) == this
  [[nodiscard]] StateVector boxminus(const State& other) const {
    StateVector d;
    d.segment<3>(kRot) = so3::log(other.R_world_imu.transpose() * R_world_imu);
    d.segment<3>(kPos) = p_world_imu - other.p_world_imu;
    d(kExpo) = inv_exposure - other.inv_exposure;
    d.segment<3>(kVel) = v_world - other.v_world;
    d.segment<3>(kBg) = bias_gyro - other.bias_gyro;
    d.segment<3>(kBa) = bias_accel - other.bias_accel;
    d.segment<3>(kGrav) = gravity_world - other.gravity_world;
    return d;
  }
};

// State with its error-state covariance.
struct Belief {
  State x;
  StateMatrix P = StateMatrix::Identity() * 0.01;
};

}  // namespace livod::estimator
