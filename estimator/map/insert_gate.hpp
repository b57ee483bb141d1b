#pragma once
// Which scans go into the map: lio.map_min_move_m / map_min_turn_deg. FAST-LIVO2 inserts every
// scan. A sensor standing still (or creeping) then inserts the same view again and again: its
// systematic errors - range walk, range noise growing along grazing rays - are common to all those
// scans, but each plane counts their points as independent and grows confident in a ground and
// walls bent the way the sensor sees them from there. That distortion moves with the sensor, so
// once it drives off, the map pulls it back. A 16-ring LiDAR on a street (its ground seen in
// single rings at fixed ranges) stayed within metres of the start that way (docs/estimator.md,
// "Map insertion from new viewpoints"). With the gate a sweep is inserted only from a new
// viewpoint: after the sensor moved or turned far enough since the last inserted one. The first
// sweep is always inserted (it builds the map).
//
// The decision is per sweep, not per measurement group: with a camera faster than the LiDAR a
// group holds part of a scan, and every group ending within a scan period (plus a tenth, for the
// jitter of image times) of the admitted group's start is admitted with it, so that a sweep goes
// in whole or not at all. With several LiDARs each has its own gate (LioPipeline): their sweeps
// begin at different times, and a group holds parts of each one's; a LiDAR's gate admits a scan
// period of its points, from wherever the admitted group begins.

#include <Eigen/Core>

#include "core/time.hpp"

namespace livod::estimator {

class MapInsertGate {
 public:
  // min_move_m <= 0: every group is inserted (the gate is off), whatever min_turn_rad.
  MapInsertGate(double min_move_m, double min_turn_rad);

  // True when the group measured in (t_begin, t_end], registered at this IMU pose, goes into the
  // map; `period` is the LiDAR's scan period.
  bool admit(MappedTime t_begin, MappedTime t_end, Nanoseconds period,
             const Eigen::Matrix3d& R_world_imu, const Eigen::Vector3d& p_world_imu);

 private:
  double min_move_m_;
  double min_turn_rad_;
  bool inserted_once_ = false;
  MappedTime sweep_end_{};  // groups ending up to here belong to the admitted sweep
  Eigen::Matrix3d R_last_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_last_ = Eigen::Vector3d::Zero();
};

}  // namespace livod::estimator
