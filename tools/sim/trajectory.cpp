#include "tools/sim/trajectory.hpp"

#include <cmath>

namespace livod::sim {

double SmoothFunction::value(double tau) const {
  double v = c0 + c1 * tau;
  for (const auto& s : terms) v += s.amplitude * std::sin(s.omega * tau + s.phase);
  return v;
}

double SmoothFunction::d1(double tau) const {
  double v = c1;
  for (const auto& s : terms) v += s.amplitude * s.omega * std::cos(s.omega * tau + s.phase);
  return v;
}

double SmoothFunction::d2(double tau) const {
  double v = 0.0;
  for (const auto& s : terms) {
    v -= s.amplitude * s.omega * s.omega * std::sin(s.omega * tau + s.phase);
  }
  return v;
}

Trajectory::Warp Trajectory::warp(double t) const {
  const double t0 = spec_.static_duration;
  const double ramp = spec_.ramp_duration;
  Warp w;
  if (t <= t0) return w;
  if (ramp <= 0.0) {
    w.tau = t - t0;
    w.d1 = 1.0;
    return w;
  }
  if (t < t0 + ramp) {
    const double u = (t - t0) / ramp;
    // tau' = smoothstep5(u) = 6u^5 - 15u^4 + 10u^3, whose derivative vanishes at both ends, so
    // the acceleration is continuous (C2 position).
    w.d1 = u * u * u * (u * (u * 6.0 - 15.0) + 10.0);
    w.d2 = 30.0 * u * u * (1.0 - u) * (1.0 - u) / ramp;
    w.tau = ramp * u * u * u * u * (u * (u - 3.0) + 2.5);
    return w;
  }
  w.tau = 0.5 * ramp + (t - t0 - ramp);
  w.d1 = 1.0;
  return w;
}

TrajectoryState Trajectory::at(double t) const {
  const Warp w = warp(t);
  const double tau = w.tau;
  TrajectoryState s;
  s.t = t;
  const Eigen::Vector3d f(spec_.x.value(tau), spec_.y.value(tau), spec_.z.value(tau));
  const Eigen::Vector3d f1(spec_.x.d1(tau), spec_.y.d1(tau), spec_.z.d1(tau));
  const Eigen::Vector3d f2(spec_.x.d2(tau), spec_.y.d2(tau), spec_.z.d2(tau));
  s.p_world = f;
  s.v_world = f1 * w.d1;
  s.a_world = f2 * w.d1 * w.d1 + f1 * w.d2;

  double roll = spec_.roll.value(tau);
  double pitch = spec_.pitch.value(tau);
  double yaw = spec_.yaw.value(tau);
  // Angle rates with respect to tau; multiplied by tau' below.
  const double roll_d = spec_.roll.d1(tau);
  const double pitch_d = spec_.pitch.d1(tau);
  double yaw_d = spec_.yaw.d1(tau);
  if (spec_.yaw_follows_heading) {
    // heading = atan2(fy', fx'), defined along the path even while tau' = 0 at the start.
    const double h2 = f1.x() * f1.x() + f1.y() * f1.y();
    yaw += std::atan2(f1.y(), f1.x());
    if (h2 > 1e-12) yaw_d += (f1.x() * f2.y() - f1.y() * f2.x()) / h2;
  }
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  s.R_world_body = R;
  // Body rates of ZYX Euler angles.
  const double rd = roll_d * w.d1;
  const double pd = pitch_d * w.d1;
  const double yd = yaw_d * w.d1;
  const double sr = std::sin(roll);
  const double cr = std::cos(roll);
  const double sp = std::sin(pitch);
  const double cp = std::cos(pitch);
  s.omega_body = Eigen::Vector3d(rd - yd * sp, pd * cr + yd * cp * sr, -pd * sr + yd * cp * cr);
  return s;
}

ImuTruth ideal_imu(const TrajectoryState& s, const Eigen::Vector3d& g_world) {
  return ImuTruth{s.omega_body, s.R_world_body.transpose() * (s.a_world - g_world)};
}

}  // namespace livod::sim
