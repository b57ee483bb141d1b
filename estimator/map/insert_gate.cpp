#include "estimator/map/insert_gate.hpp"

#include "core/so3.hpp"

namespace livod::estimator {

MapInsertGate::MapInsertGate(double min_move_m, double min_turn_rad)
    : min_move_m_(min_move_m), min_turn_rad_(min_turn_rad) {}

bool MapInsertGate::admit(MappedTime t_begin, MappedTime t_end, Nanoseconds period,
                          const Eigen::Matrix3d& R_world_imu, const Eigen::Vector3d& p_world_imu) {
  if (min_move_m_ <= 0.0) return true;
  if (inserted_once_) {
    if (t_end <= sweep_end_) return true;  // the rest of the admitted sweep
    const double moved = (p_world_imu - p_last_).norm();
    const double turned = so3::angle(R_last_.transpose() * R_world_imu);
    if (moved < min_move_m_ && turned < min_turn_rad_) return false;
  }
  inserted_once_ = true;
  sweep_end_ = t_begin + period + period / 10;
  R_last_ = R_world_imu;
  p_last_ = p_world_imu;
  return true;
}

}  // namespace livod::estimator
