#pragma once
// IMU forward propagation of the filter state and covariance (fast-livo2-notes.md 1.2), with the
// process noise taken entirely from the configuration (FAST-LIVO2 hard-codes the bias noise).
// Each step uses the mid-point of two consecutive samples:
//   w = (w0 + w1)/2 - b_g,  a = (a0 + a1)/2 - b_a
//   R <- R Exp(w dt);  p <- p + v dt + (R a + g) dt^2 / 2;  v <- v + (R a + g) dt
// and the exact first-order error-state transition of that discrete step (the rotation-bias
// block uses the right Jacobian; the dt^2 position terms are kept).

#include <Eigen/Core>

#include "estimator/filter/state.hpp"
#include "estimator/params.hpp"

namespace livod::estimator {

struct ImuReading {
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
};

// The nominal state after one step of length dt with mean measurement `m`.
State propagate_state(const State& x, const ImuReading& m, double dt);

// d(propagate(x (+) d) (-) propagate(x)) / d d at d = 0.
StateMatrix propagation_jacobian(const State& x, const ImuReading& m, double dt,
                                 const ImuParams& params);

// Process noise added per step: FAST-LIVO2's discrete convention Q dt^2, with the rotation block
// gyr_cov, velocity R diag(acc_cov) R^T, biases b_gyr_cov / b_acc_cov, inverse exposure
// inv_expo_cov, gravity none.
StateMatrix process_noise(const State& x, double dt, const ImuParams& params, double inv_expo_cov);

// One full step of state and covariance.
void propagate(Belief& belief, const ImuReading& m, double dt, const ImuParams& params,
               double inv_expo_cov);

}  // namespace livod::estimator
