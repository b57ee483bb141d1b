#pragma once
// C2-smooth analytic trajectories for the simulator. Position and orientation are closed-form
// functions of a warped time tau(t), so velocity, acceleration and body angular rate are exact
// derivatives and a noise-free IMU integrates back to the ground truth.
//
// tau(t) starts at rest (the platform stands still for `static_duration` so that IMU
// initialisation can check for motion), then eases in over `ramp_duration` with a quintic
// smoothstep on tau', after which tau advances at unit rate.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace livod::sim {

// a * sin(omega * tau + phase)
struct Sinusoid {
  double amplitude = 0.0;
  double omega = 0.0;  // rad per unit tau
  double phase = 0.0;
};

// c0 + c1 * tau + sum of sinusoids; value and first two derivatives with respect to tau.
struct SmoothFunction {
  double c0 = 0.0;
  double c1 = 0.0;
  std::vector<Sinusoid> terms;

  [[nodiscard]] double value(double tau) const;
  [[nodiscard]] double d1(double tau) const;
  [[nodiscard]] double d2(double tau) const;
};

struct TrajectorySpec {
  SmoothFunction x, y, z;            // world position of the body (IMU) frame, metres
  SmoothFunction roll, pitch, yaw;   // ZYX Euler angles, rad: R = Rz(yaw) Ry(pitch) Rx(roll)
  bool yaw_follows_heading = false;  // yaw = heading of the horizontal velocity + yaw(tau)
  double static_duration = 2.0;      // s at rest at the start
  double ramp_duration = 2.0;        // s of smooth speed-up
};

struct TrajectoryState {
  double t = 0.0;
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_world = Eigen::Vector3d::Zero();  // kinematic acceleration (no gravity)
  Eigen::Matrix3d R_world_body = Eigen::Matrix3d::Identity();
  Eigen::Vector3d omega_body = Eigen::Vector3d::Zero();  // body angular rate, rad/s

  [[nodiscard]] Eigen::Isometry3d T_world_body() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = R_world_body;
    T.translation() = p_world;
    return T;
  }
};

class Trajectory {
 public:
  explicit Trajectory(TrajectorySpec spec) : spec_(std::move(spec)) {}
  [[nodiscard]] TrajectoryState at(double t) const;
  [[nodiscard]] const TrajectorySpec& spec() const { return spec_; }

  // Warped time and its first two derivatives with respect to t.
  struct Warp {
    double tau = 0.0;
    double d1 = 0.0;
    double d2 = 0.0;
  };
  [[nodiscard]] Warp warp(double t) const;

 private:
  TrajectorySpec spec_;
};

// Ideal specific force and angular rate an IMU rigidly attached to the body frame measures,
// with world gravity g_world (e.g. (0, 0, -9.81)).
struct ImuTruth {
  Eigen::Vector3d gyro_rad_s;
  Eigen::Vector3d accel_m_s2;
};
ImuTruth ideal_imu(const TrajectoryState& s, const Eigen::Vector3d& g_world);

}  // namespace livod::sim
