#include "daemon/publish/pose_from_estimator.hpp"

namespace livod::daemon::publish {

Eigen::Matrix<double, 6, 6> pose_covariance(const estimator::StateMatrix& P) {
  using estimator::kPos;
  using estimator::kRot;
  Eigen::Matrix<double, 6, 6> C;
  C.block<3, 3>(0, 0) = P.block<3, 3>(kRot, kRot);
  C.block<3, 3>(0, 3) = P.block<3, 3>(kRot, kPos);
  C.block<3, 3>(3, 0) = P.block<3, 3>(kPos, kRot);
  C.block<3, 3>(3, 3) = P.block<3, 3>(kPos, kPos);
  return C;
}

PoseRecord pose_record_from_state(const estimator::State& x, const estimator::StateMatrix& P,
                                  MappedTime t, PoseSource source, PoseStatus status,
                                  std::optional<MappedTime> filter_t, const ImuSample* imu) {
  PoseRecord r;
  r.t = t;
  r.has_filter_update = filter_t.has_value();
  if (filter_t) r.filter_t = *filter_t;
  r.source = source;
  r.status = status;
  r.R_world_body = x.R_world_imu;
  r.p_world_body = x.p_world_imu;
  r.v_world = x.v_world;
  if (imu != nullptr) {
    r.omega_body = imu->gyro_rad_s - x.bias_gyro;
    r.accel_world = x.R_world_imu * (imu->accel_m_s2 - x.bias_accel) + x.gravity_world;
  }
  r.covariance = pose_covariance(P);
  return r;
}

}  // namespace livod::daemon::publish
