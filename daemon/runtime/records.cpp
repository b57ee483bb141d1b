#include "daemon/runtime/records.hpp"

namespace livod::daemon::runtime {

const char* to_string(PoseStatus s) {
  switch (s) {
    case PoseStatus::kInitialising:
      return "INITIALISING";
    case PoseStatus::kOk:
      return "OK";
    case PoseStatus::kDegenerate:
      return "DEGENERATE";
    case PoseStatus::kImuOnly:
      return "IMU_ONLY";
    case PoseStatus::kSensorStale:
      return "SENSOR_STALE";
  }
  return "?";
}

void fill_pose(PoseRecord& r, std::int64_t t_ns, const estimator::State& x,
               const estimator::StateMatrix& P, const Eigen::Vector3d& omega_body,
               const Eigen::Vector3d& accel_body) {
  static_assert(estimator::kRot == 0 && estimator::kPos == 3,
                "the pose covariance is the leading 6x6 block of P");
  r.t_ns = t_ns;
  r.q_world_body = Eigen::Quaterniond(x.R_world_imu).normalized();
  r.p_world_body = x.p_world_imu;
  r.v_world = x.v_world;
  r.omega_body = omega_body;
  r.accel_body = accel_body;
  r.covariance = P.block<6, 6>(0, 0);
}

}  // namespace livod::daemon::runtime
