#include "estimator/imu/pose_predictor.hpp"

#include "estimator/imu/propagation.hpp"

namespace livod::estimator {

PosePredictor::PosePredictor(ImuParams params, double inv_expo_cov, std::size_t max_buffered)
    : params_(params),
      inv_expo_cov_(inv_expo_cov),
      max_buffered_(max_buffered > 0 ? max_buffered : 1),
      ring_(max_buffered_) {}

void PosePredictor::reset(MappedTime t, const Belief& belief) {
  have_estimate_ = true;
  estimate_t_ = t;
  belief_ = belief;
  t_ = t;
  last_.reset();
  while (size_ > 0 && at(0).stamp.mapped <= t) {
    head_ = (head_ + 1) % ring_.size();
    --size_;
  }
  for (std::size_t i = 0; i < size_; ++i) step(at(i));
}

void PosePredictor::step(const ImuSample& s) {
  const double dt = to_seconds(s.stamp.mapped - t_);
  if (dt <= 0.0) return;
  // The filter's own step: the mean of the two samples bounding the interval. The first interval
  // after an estimate has only the new sample (the estimate's time lies between samples).
  ImuReading m{s.gyro_rad_s, s.accel_m_s2};
  if (last_) {
    m.gyro_rad_s = 0.5 * (last_->gyro_rad_s + s.gyro_rad_s);
    m.accel_m_s2 = 0.5 * (last_->accel_m_s2 + s.accel_m_s2);
  }
  propagate(belief_, m, dt, params_, inv_expo_cov_);
  t_ = s.stamp.mapped;
  last_ = s;
}

std::optional<PredictedPose> PosePredictor::add(const ImuSample& sample) {
  if (size_ > 0 && sample.stamp.mapped <= at(size_ - 1).stamp.mapped) return std::nullopt;
  if (size_ == ring_.size()) {
    head_ = (head_ + 1) % ring_.size();
    --size_;
    ++dropped_;
  }
  ring_[(head_ + size_) % ring_.size()] = sample;
  ++size_;
  if (!have_estimate_ || sample.stamp.mapped <= t_) return std::nullopt;
  step(sample);
  PredictedPose out;
  out.t = t_;
  out.belief = belief_;
  out.omega_imu = sample.gyro_rad_s - belief_.x.bias_gyro;
  out.since_update = t_ - estimate_t_;
  return out;
}

}  // namespace livod::estimator
