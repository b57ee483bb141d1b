#include "estimator/filter/esikf.hpp"

#include <Eigen/Cholesky>

namespace livod::estimator {

UpdateReport iterated_update(Belief& belief, const Linearizer& linearize,
                             const IterationParams& params) {
  UpdateReport report;
  report.information.setZero();
  const State prior = belief.x;
  const StateMatrix P_inv = belief.P.inverse();
  State x = prior;
  NormalEquations eq;
  StateMatrix A = StateMatrix::Zero();
  bool have_solution = false;
  for (int it = 0; it < params.max_iterations; ++it) {
    eq.clear();
    if (!linearize(x, eq)) break;
    report.iterations = it + 1;
    report.measurements = eq.measurements;
    report.information = eq.HtRinvH;
    const StateVector delta = x.boxminus(prior);
    StateMatrix J = StateMatrix::Identity();
    J.block<3, 3>(kRot, kRot) = so3::right_jacobian_inverse(delta.segment<3>(kRot));
    const StateMatrix JtPinv = J.transpose() * P_inv;
    A = eq.HtRinvH + JtPinv * J;
    const StateVector b = eq.HtRinvz - JtPinv * delta;
    const StateVector dx = A.ldlt().solve(b);
    x = x.boxplus(dx);
    have_solution = true;
    if (dx.segment<3>(kRot).norm() < params.converged_rotation_rad &&
        dx.segment<3>(kPos).norm() < params.converged_translation_m) {
      report.converged = true;
      break;
    }
  }
  if (!have_solution) return report;
  belief.x = x;
  // Posterior covariance at the final iterate; symmetrised against round-off.
  StateMatrix P = A.inverse();
  belief.P = 0.5 * (P + P.transpose());
  return report;
}

}  // namespace livod::estimator
