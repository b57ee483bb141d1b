#include "estimator/imu/initializer.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <sstream>

namespace livod::estimator {

bool ImuInitializer::window_full() const {
  if (window_.size() < 2) return false;
  if (params_.init_time_s > 0.0) {
    return (window_.back().stamp.mapped - window_.front().stamp.mapped).count() * 1e-9 >=
           params_.init_time_s;
  }
  return static_cast<int>(window_.size()) >= std::max(params_.init_samples, 2);
}

bool ImuInitializer::add(const ImuSample& sample) {
  if (result_) return true;
  window_.push_back(sample);
  if (!window_full()) {
    std::ostringstream os;
    os << "collecting IMU samples (" << window_.size() << ")";
    if (!last_rejection_.empty()) os << "; last window rejected: " << last_rejection_;
    status_ = os.str();
    return false;
  }
  const double n = static_cast<double>(window_.size());
  Eigen::Vector3d acc_mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyr_mean = Eigen::Vector3d::Zero();
  for (const auto& s : window_) {
    acc_mean += s.accel_m_s2;
    gyr_mean += s.gyro_rad_s;
  }
  acc_mean /= n;
  gyr_mean /= n;
  double acc_norm_var = 0.0;
  Eigen::Vector3d gyr_var = Eigen::Vector3d::Zero();
  const double acc_mean_norm = acc_mean.norm();
  for (const auto& s : window_) {
    acc_norm_var += std::pow(s.accel_m_s2.norm() - acc_mean_norm, 2);
    gyr_var += (s.gyro_rad_s - gyr_mean).cwiseAbs2();
  }
  const double acc_std = std::sqrt(acc_norm_var / n);
  const double gyr_std = std::sqrt(gyr_var.maxCoeff() / n);

  if (acc_mean_norm < 3.0) {
    std::ostringstream os;
    os << "accelerometer mean |a| = " << acc_mean_norm
       << " m/s^2 is not gravity: the IMU driver must convert g to m/s^2";
    status_ = os.str();
    last_rejection_ = status_;
    window_.pop_front();
    ++rejections_;
    return false;
  }
  const auto& check = params_.static_check;
  if (check.enabled && (acc_std > check.max_acc_std_m_s2 || gyr_std > check.max_gyro_std_rad_s)) {
    std::ostringstream os;
    os << "platform is moving, waiting for it to stand still (|a| std " << acc_std
       << " m/s^2, limit " << check.max_acc_std_m_s2 << "; gyro std " << gyr_std << " rad/s, limit "
       << check.max_gyro_std_rad_s << ")";
    status_ = os.str();
    last_rejection_ = status_;
    ++rejections_;
    // Slide: drop the oldest half so that a platform that comes to rest is picked up quickly.
    const std::size_t drop = window_.size() / 2;
    for (std::size_t i = 0; i < drop; ++i) window_.pop_front();
    return false;
  }

  Belief b;
  const Eigen::Vector3d g_imu = -acc_mean / acc_mean_norm * params_.gravity_m_s2;
  if (params_.gravity_align) {
    // World z up: R_world_imu maps the measured "up" (acc_mean direction) onto +z.
    b.x.R_world_imu =
        Eigen::Quaterniond::FromTwoVectors(acc_mean.normalized(), Eigen::Vector3d::UnitZ())
            .toRotationMatrix();
    b.x.gravity_world = Eigen::Vector3d(0.0, 0.0, -params_.gravity_m_s2);
  } else {
    b.x.R_world_imu.setIdentity();
    b.x.gravity_world = g_imu;
  }
  b.x.bias_gyro = params_.init_gyro_bias ? gyr_mean : Eigen::Vector3d::Zero();
  b.x.inv_exposure = 1.0;
  b.P.setZero();
  b.P.block<3, 3>(kRot, kRot).diagonal().setConstant(cov_.rotation);
  b.P.block<3, 3>(kPos, kPos).diagonal().setConstant(cov_.position);
  b.P(kExpo, kExpo) = cov_.inv_exposure;
  b.P.block<3, 3>(kVel, kVel).diagonal().setConstant(cov_.velocity);
  b.P.block<3, 3>(kBg, kBg).diagonal().setConstant(cov_.bias_gyro);
  b.P.block<3, 3>(kBa, kBa).diagonal().setConstant(cov_.bias_accel);
  b.P.block<3, 3>(kGrav, kGrav).diagonal().setConstant(cov_.gravity);
  result_ = b;
  time_ = window_.back().stamp.mapped;
  std::ostringstream os;
  os << "initialised from " << window_.size() << " static samples (|g| measured " << acc_mean_norm
     << " m/s^2, gyro bias " << b.x.bias_gyro.transpose() << " rad/s)";
  status_ = os.str();
  window_.clear();
  return true;
}

}  // namespace livod::estimator
