#pragma once
// Iterated error-state Kalman filter update in information form (FAST-LIO2 / FAST-LIVO2 style).
// Measurements are linearised at the current iterate x_k by a callback that accumulates the
// normal equations H^T R^-1 H and H^T R^-1 z (so a scan of 10^4 points never materialises H).
// Each iteration solves, for the correction dx at x_k (x = x_k (+) dx),
//
//   min  |z - H dx|^2_{R^-1}  +  |(x_k (-) x_prior) + J dx|^2_{P^-1}
//   dx = (H^T R^-1 H + J^T P^-1 J)^-1 (H^T R^-1 z - J^T P^-1 (x_k (-) x_prior))
//
// where J is d((x_k (+) dx) (-) x_prior)/d dx (the inverse right Jacobian on the rotation block,
// identity elsewhere). The prior term keeps every iteration a proper MAP step. After the last
// iteration P <- (H^T R^-1 H + J^T P^-1 J)^-1.

#include <functional>

#include "estimator/filter/state.hpp"

namespace livod::estimator {

// Normal equations of one linearisation. Residual convention: z = measurement - prediction, and
// H = d prediction / d dx, so that z - H dx is the linearised residual after a correction dx.
struct NormalEquations {
  StateMatrix HtRinvH = StateMatrix::Zero();
  StateVector HtRinvz = StateVector::Zero();
  int measurements = 0;
  double weighted_sq_residual = 0.0;  // z^T R^-1 z at the linearisation point

  void clear() {
    HtRinvH.setZero();
    HtRinvz.setZero();
    measurements = 0;
    weighted_sq_residual = 0.0;
  }
};

struct IterationParams {
  int max_iterations = 5;
  double converged_rotation_rad = 0.01 * M_PI / 180.0;
  double converged_translation_m = 0.00015;
};

struct UpdateReport {
  int iterations = 0;
  bool converged = false;
  int measurements = 0;     // at the last linearisation
  StateMatrix information;  // H^T R^-1 H at the last linearisation (for degeneracy checks)
};

// Returns false from the callback to abort (e.g. too few measurements): the belief is left
// unchanged and report.iterations says how far it got.
using Linearizer = std::function<bool(const State& x, NormalEquations& eq)>;

UpdateReport iterated_update(Belief& belief, const Linearizer& linearize,
                             const IterationParams& params);

}  // namespace livod::estimator
