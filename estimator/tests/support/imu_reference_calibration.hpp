#pragma once
// Everything IMU propagation needs besides the measurements, estimated from a calibration span
// of the data that lies strictly before the evaluated windows (header-only test support):
//   * R_body_imu and the gyro bias: the reference's rotation increments over 0.1 s against the
//     integrated gyro (Wahba's problem, alternated with the mean residual rate);
//   * the accelerometer bias and the gravity direction in the reference's world frame: the second
//     difference of the reference positions over +-0.1 s is the triangle-weighted mean of the
//     world acceleration, which the IMU gives as R (f - b_a) + g: linear least squares.
//     The gravity magnitude is fixed (livod's ImuParams::gravity_m_s2): with little roll and
//     pitch (EuRoC) it cannot be told from the accelerometer bias along the vertical axis;
//   * noise levels for the initial covariance and the process noise, from the same residuals
//     (nothing is tuned by hand): reference orientation, velocity and position noise, bias and
//     gravity uncertainty (least-squares covariance), per-sample IMU white noise. Only the bias
//     random walks, which one span cannot see, come from outside (BiasRandomWalk).
// The propagation then starts from the reference pose, the reference velocity (central
// difference over +-0.1 s), these biases and this gravity, and runs livod's propagate().

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "estimator/imu/propagation.hpp"
#include "estimator/tests/support/imu_reference_data.hpp"

namespace livod::estimator::test_support {

// Reference step for increments, differences and velocities.
inline constexpr std::int64_t kReferenceStepNs = 100'000'000;

struct ImuCalibration {
  Eigen::Matrix3d R_body_imu = Eigen::Matrix3d::Identity();  // x_body = R_body_imu x_imu
  Eigen::Vector3d bias_gyro = Eigen::Vector3d::Zero();
  Eigen::Vector3d bias_accel = Eigen::Vector3d::Zero();
  Eigen::Vector3d gravity_world = Eigen::Vector3d::Zero();
  double sigma_rot_rad = 0.0;          // reference orientation noise, per axis
  double sigma_vel_m_s = 0.0;          // central-difference velocity error, per axis
  double sigma_pos_m = 0.0;            // reference position noise (upper bound), per axis
  double sigma_bias_gyro_rad_s = 0.0;  // per axis
  Eigen::Matrix3d cov_bias_accel = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d cov_gravity = Eigen::Matrix3d::Zero();
  double accel_noise_var = 0.0;  // per-sample white noise, mean over the axes ((m/s^2)^2)
  double gyro_noise_var = 0.0;   // ((rad/s)^2)
  double imu_period_s = 0.0;
  std::int64_t mid_ns = 0;  // middle of the calibration span: the biases' reference time
};

// Bias random walks (continuous densities). The calibration span cannot measure them (it sees
// one constant bias), yet the biases keep drifting after it: their uncertainty grows with the
// time since the calibration, by these densities.
struct BiasRandomWalk {
  double accel_m_s3_sqrt_hz = 0.0;
  double gyro_rad_s2_sqrt_hz = 0.0;
};

// Mid-point reading between IMU samples j and j + 1 (what propagate() expects) and its length.
inline ImuReading midpoint(const ImuReferenceData& d, std::size_t j) {
  return {0.5 * (d.imu[j].gyro_rad_s + d.imu[j + 1].gyro_rad_s),
          0.5 * (d.imu[j].accel_m_s2 + d.imu[j + 1].accel_m_s2)};
}
inline double step_s(const ImuReferenceData& d, std::size_t j) {
  return seconds_between(d.imu[j].t_ns, d.imu[j + 1].t_ns);
}

// Reference velocity at sample k: central difference over +-kReferenceStepNs.
inline Eigen::Vector3d reference_velocity(const ImuReferenceData& d, std::size_t k) {
  const auto& a = d.reference[d.reference_index(d.reference[k].t_ns - kReferenceStepNs)];
  const auto& b = d.reference[d.reference_index(d.reference[k].t_ns + kReferenceStepNs)];
  return (b.p_world_body - a.p_world_body) / seconds_between(a.t_ns, b.t_ns);
}

// Reference sample indices on the kReferenceStepNs grid within [begin, end].
inline std::vector<std::size_t> reference_grid(const ImuReferenceData& d, std::int64_t begin_ns,
                                               std::int64_t end_ns) {
  std::vector<std::size_t> grid;
  for (std::int64_t t = begin_ns; t <= end_ns; t += kReferenceStepNs) {
    grid.push_back(d.reference_index(t));
  }
  return grid;
}

inline void estimate_rotation_and_gyro_bias(const ImuReferenceData& d,
                                            const std::vector<std::size_t>& grid,
                                            ImuCalibration& c) {
  std::vector<Eigen::Vector3d> ref_inc;  // reference rotation increment per interval
  for (std::size_t n = 0; n + 1 < grid.size(); ++n) {
    const ReferencePose& a = d.reference[grid[n]];
    const ReferencePose& b = d.reference[grid[n + 1]];
    ref_inc.push_back(so3::log(Eigen::Matrix3d(a.R_world_body.transpose() * b.R_world_body)));
  }
  const double interval_s = seconds_between(0, kReferenceStepNs);
  Eigen::Vector3d residual_sum = Eigen::Vector3d::Zero();
  double residual_sq = 0.0;
  for (int iteration = 0; iteration < 5; ++iteration) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    residual_sum.setZero();
    residual_sq = 0.0;
    for (std::size_t n = 0; n + 1 < grid.size(); ++n) {
      const std::size_t ja = d.imu_index(d.reference[grid[n]].t_ns);
      const std::size_t jb = d.imu_index(d.reference[grid[n + 1]].t_ns);
      Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
      for (std::size_t j = ja; j < jb; ++j) {
        R = R * so3::exp(Eigen::Vector3d((midpoint(d, j).gyro_rad_s - c.bias_gyro) * step_s(d, j)));
      }
      const Eigen::Vector3d imu_inc = so3::log(R);
      H += imu_inc * ref_inc[n].transpose();
      const Eigen::Vector3d r = imu_inc - c.R_body_imu.transpose() * ref_inc[n];
      residual_sum += r;
      residual_sq += r.squaredNorm();
    }
    // ref_inc = R_body_imu imu_inc: the rotation maximising sum ref_inc . (R imu_inc).
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d V = svd.matrixV();
    if ((V * svd.matrixU().transpose()).determinant() < 0) V.col(2) *= -1.0;
    c.R_body_imu = V * svd.matrixU().transpose();
    // A gyro bias b shortens every increment by about b * interval.
    c.bias_gyro += residual_sum / (interval_s * static_cast<double>(ref_inc.size()));
  }
  const auto count = static_cast<double>(ref_inc.size());
  const double rms_axis = std::sqrt(residual_sq / (3.0 * count));
  // Each increment difference holds two independent reference orientation errors.
  c.sigma_rot_rad = rms_axis / std::sqrt(2.0);
  c.sigma_bias_gyro_rad_s = rms_axis / (interval_s * std::sqrt(count));
}

// IMU orientation at sample j: the reference's, interpolated, through R_body_imu.
inline Eigen::Matrix3d R_world_imu_at(const ImuReferenceData& d, const ImuCalibration& c,
                                      std::size_t j) {
  return d.R_world_body(d.imu[j].t_ns) * c.R_body_imu;
}

inline void estimate_accel_bias_and_gravity(const ImuReferenceData& d,
                                            const std::vector<std::size_t>& grid,
                                            double gravity_m_s2, ImuCalibration& c) {
  // Unknowns x = (b_a, g_x, g_y); g_z follows from the fixed magnitude (first order: tilts are
  // below 0.01 rad, where the z change is < 5e-4 m/s^2).
  using Mat5 = Eigen::Matrix<double, 5, 5>;
  using Vec5 = Eigen::Matrix<double, 5, 1>;
  const Eigen::Vector3d g0(0.0, 0.0, -gravity_m_s2);
  std::vector<Eigen::Matrix<double, 3, 5>> rows_A;
  std::vector<Eigen::Vector3d> rows_y;
  for (std::size_t n = 1; n + 1 < grid.size(); ++n) {
    const ReferencePose& pm = d.reference[grid[n - 1]];
    const ReferencePose& p0 = d.reference[grid[n]];
    const ReferencePose& pp = d.reference[grid[n + 1]];
    const double h = 0.5 * seconds_between(pm.t_ns, pp.t_ns);
    const Eigen::Vector3d second_difference =
        (pp.p_world_body - 2.0 * p0.p_world_body + pm.p_world_body) / (h * h);
    Eigen::Vector3d Rf = Eigen::Vector3d::Zero();
    Eigen::Matrix3d R_mean = Eigen::Matrix3d::Zero();
    double weight_sum = 0.0;
    for (std::size_t j = d.imu_index(pm.t_ns); j <= d.imu_index(pp.t_ns); ++j) {
      const double w = std::max(0.0, 1.0 - std::abs(seconds_between(p0.t_ns, d.imu[j].t_ns)) / h);
      const Eigen::Matrix3d R = R_world_imu_at(d, c, j);
      Rf += w * R * d.imu[j].accel_m_s2;
      R_mean += w * R;
      weight_sum += w;
    }
    Eigen::Matrix<double, 3, 5> A = Eigen::Matrix<double, 3, 5>::Zero();
    A.leftCols<3>() = -R_mean / weight_sum;
    A(0, 3) = 1.0;
    A(1, 4) = 1.0;
    rows_A.push_back(A);
    rows_y.push_back(second_difference - Rf / weight_sum - g0);
  }
  Mat5 H = Mat5::Zero();
  Vec5 b = Vec5::Zero();
  for (std::size_t i = 0; i < rows_A.size(); ++i) {
    H += rows_A[i].transpose() * rows_A[i];
    b += rows_A[i].transpose() * rows_y[i];
  }
  const Vec5 x = H.ldlt().solve(b);
  double residual_sq = 0.0;
  for (std::size_t i = 0; i < rows_A.size(); ++i) {
    residual_sq += (rows_A[i] * x - rows_y[i]).squaredNorm();
  }
  const double row_var = residual_sq / (3.0 * static_cast<double>(rows_A.size()) - 5.0);
  const Mat5 cov = row_var * H.inverse();
  c.bias_accel = x.head<3>();
  c.gravity_world = Eigen::Vector3d(
      x(3), x(4), -std::sqrt(gravity_m_s2 * gravity_m_s2 - x(3) * x(3) - x(4) * x(4)));
  c.cov_bias_accel = cov.topLeftCorner<3, 3>();
  c.cov_gravity.setZero();
  c.cov_gravity.topLeftCorner<2, 2>() = cov.bottomRightCorner<2, 2>();
  // The second difference of a position noise sigma_p has variance 6 sigma_p^2 / h^4; the
  // residual also holds IMU noise and model error, so this bounds the reference noise above.
  const double h = seconds_between(0, kReferenceStepNs);
  c.sigma_pos_m = std::sqrt(row_var / 6.0) * h * h;
}

// Consecutive reference velocities against the IMU's velocity change between them.
inline void estimate_velocity_noise(const ImuReferenceData& d, const std::vector<std::size_t>& grid,
                                    ImuCalibration& c) {
  double sq = 0.0;
  int count = 0;
  for (std::size_t n = 1; n + 2 < grid.size(); ++n) {
    const std::size_t ja = d.imu_index(d.reference[grid[n]].t_ns);
    const std::size_t jb = d.imu_index(d.reference[grid[n + 1]].t_ns);
    Eigen::Vector3d dv = Eigen::Vector3d::Zero();
    for (std::size_t j = ja; j < jb; ++j) {
      const Eigen::Matrix3d R = 0.5 * (R_world_imu_at(d, c, j) + R_world_imu_at(d, c, j + 1));
      dv += (R * (midpoint(d, j).accel_m_s2 - c.bias_accel) + c.gravity_world) * step_s(d, j);
    }
    const Eigen::Vector3d r =
        reference_velocity(d, grid[n + 1]) - reference_velocity(d, grid[n]) - dv;
    sq += r.squaredNorm();
    count += 3;
  }
  c.sigma_vel_m_s = std::sqrt(sq / count / 2.0);  // two independent velocity errors
}

// Per-sample white noise: x_j - (x_{j-1} + x_{j+1}) / 2 has 1.5 sigma^2 for white noise, and
// the smooth motion contributes little at the IMU rate.
inline void estimate_white_noise(const ImuReferenceData& d, std::int64_t begin_ns,
                                 std::int64_t end_ns, ImuCalibration& c) {
  double acc = 0.0;
  double gyro = 0.0;
  int count = 0;
  for (std::size_t j = d.imu_index(begin_ns) + 1; j + 1 < d.imu.size() && d.imu[j].t_ns < end_ns;
       ++j) {
    acc += (d.imu[j].accel_m_s2 - 0.5 * (d.imu[j - 1].accel_m_s2 + d.imu[j + 1].accel_m_s2))
               .squaredNorm();
    gyro += (d.imu[j].gyro_rad_s - 0.5 * (d.imu[j - 1].gyro_rad_s + d.imu[j + 1].gyro_rad_s))
                .squaredNorm();
    ++count;
  }
  c.accel_noise_var = acc / (1.5 * 3.0 * count);
  c.gyro_noise_var = gyro / (1.5 * 3.0 * count);
}

inline ImuCalibration calibrate(const ImuReferenceData& d, std::int64_t begin_ns,
                                std::int64_t end_ns, double gravity_m_s2) {
  ImuCalibration c;
  const std::vector<std::size_t> grid = reference_grid(d, begin_ns, end_ns);
  estimate_rotation_and_gyro_bias(d, grid, c);
  estimate_accel_bias_and_gravity(d, grid, gravity_m_s2, c);
  estimate_velocity_noise(d, grid, c);
  estimate_white_noise(d, begin_ns, end_ns, c);
  c.imu_period_s = seconds_between(d.imu.front().t_ns, d.imu.back().t_ns) /
                   static_cast<double>(d.imu.size() - 1);
  c.mid_ns = begin_ns + (end_ns - begin_ns) / 2;
  return c;
}

// Process noise from the calibration: FAST-LIVO2's discrete convention (Q = cov dt^2 per step)
// makes acc_cov / gyr_cov per-sample variances, and a random walk density sigma (per sqrt(s))
// a per-step variance sigma^2 dt, i.e. b_*_cov = sigma^2 / dt.
inline ImuParams process_noise_from(const ImuCalibration& c, const BiasRandomWalk& walk) {
  ImuParams p;
  p.acc_cov = c.accel_noise_var;
  p.gyr_cov = c.gyro_noise_var;
  p.b_acc_cov = walk.accel_m_s3_sqrt_hz * walk.accel_m_s3_sqrt_hz / c.imu_period_s;
  p.b_gyr_cov = walk.gyro_rad_s2_sqrt_hz * walk.gyro_rad_s2_sqrt_hz / c.imu_period_s;
  return p;
}

struct WindowError {
  double position_m = 0.0;
  double rotation_rad = 0.0;
  // e^T (P + end reference noise)^-1 e: chi^2 with 3 degrees of freedom if P is consistent.
  double nees_position = 0.0;
  double nees_rotation = 0.0;
};

// Propagates from the reference at t over `horizon` and compares with the reference there, for
// windows starting every `stride` from `begin`. `use_biases` false starts with zero biases (the
// control that shows the calibration matters).
inline std::vector<WindowError> propagate_windows(const ImuReferenceData& d,
                                                  const ImuCalibration& c, std::int64_t begin_ns,
                                                  std::int64_t horizon_ns, std::int64_t stride_ns,
                                                  const BiasRandomWalk& walk, bool use_biases) {
  const ImuParams params = process_noise_from(c, walk);
  std::vector<WindowError> errors;
  const std::int64_t last_ns =
      std::min(d.reference.back().t_ns, d.imu.back().t_ns) - horizon_ns - kReferenceStepNs;
  for (std::int64_t t = begin_ns; t <= last_ns; t += stride_ns) {
    const std::size_t k0 = d.reference_index(t);
    const std::size_t k1 = d.reference_index(d.reference[k0].t_ns + horizon_ns);
    const std::size_t j0 = d.imu_index(d.reference[k0].t_ns);
    const std::size_t j1 = d.imu_index(d.reference[k1].t_ns);
    const ReferencePose& start = d.reference[k0];
    const ReferencePose& end = d.reference[k1];
    Belief b;
    b.x.R_world_imu = start.R_world_body * c.R_body_imu;
    b.x.p_world_imu = start.p_world_body;
    b.x.v_world = reference_velocity(d, k0);
    b.x.bias_gyro = use_biases ? c.bias_gyro : Eigen::Vector3d::Zero();
    b.x.bias_accel = use_biases ? c.bias_accel : Eigen::Vector3d::Zero();
    b.x.gravity_world = c.gravity_world;
    b.P.setZero();
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    b.P.block<3, 3>(kRot, kRot) = I * c.sigma_rot_rad * c.sigma_rot_rad;
    b.P.block<3, 3>(kPos, kPos) = I * c.sigma_pos_m * c.sigma_pos_m;
    b.P.block<3, 3>(kVel, kVel) = I * c.sigma_vel_m_s * c.sigma_vel_m_s;
    const double drift_s = seconds_between(c.mid_ns, start.t_ns);
    b.P.block<3, 3>(kBg, kBg) = I * (c.sigma_bias_gyro_rad_s * c.sigma_bias_gyro_rad_s +
                                     walk.gyro_rad_s2_sqrt_hz * walk.gyro_rad_s2_sqrt_hz * drift_s);
    b.P.block<3, 3>(kBa, kBa) =
        c.cov_bias_accel + I * walk.accel_m_s3_sqrt_hz * walk.accel_m_s3_sqrt_hz * drift_s;
    b.P.block<3, 3>(kGrav, kGrav) = c.cov_gravity;
    for (std::size_t j = j0; j < j1; ++j) propagate(b, midpoint(d, j), step_s(d, j), params, 0.0);
    const Eigen::Vector3d e = b.x.p_world_imu - end.p_world_body;
    const Eigen::Vector3d e_rot =
        so3::log(Eigen::Matrix3d((end.R_world_body * c.R_body_imu).transpose() * b.x.R_world_imu));
    const Eigen::Matrix3d S_pos = b.P.block<3, 3>(kPos, kPos) + I * c.sigma_pos_m * c.sigma_pos_m;
    const Eigen::Matrix3d S_rot =
        b.P.block<3, 3>(kRot, kRot) + I * c.sigma_rot_rad * c.sigma_rot_rad;
    errors.push_back({e.norm(), e_rot.norm(), e.dot(S_pos.ldlt().solve(e)),
                      e_rot.dot(S_rot.ldlt().solve(e_rot))});
  }
  return errors;
}

}  // namespace livod::estimator::test_support
