#pragma once
// The IMU-rate pose (LIVOD_POSE_IMU): the latest filter estimate propagated through every body-IMU
// sample that arrived after it, so that a controller gets a pose at the IMU rate, with a latency
// of one sample, between the LiDAR-rate updates.
//
// The filter publishes an estimate for time t only once IMU samples beyond t have arrived (it
// needs them to close the scan), so a new estimate is older than the newest sample: reset()
// re-propagates the buffered samples newer than t, and the next add() continues from there. The
// propagation is the filter's own (state and covariance), so the IMU-rate pose carries an honest,
// growing covariance. The buffer is bounded (oldest dropped, counted).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/measurement.hpp"
#include "estimator/filter/state.hpp"
#include "estimator/params.hpp"

namespace livod::estimator {

struct PredictedPose {
  MappedTime t;
  Belief belief;                // propagated state and covariance at t
  Eigen::Vector3d omega_imu;    // bias-corrected angular rate at t (rad/s, IMU frame)
  Nanoseconds since_update{0};  // t - time of the filter estimate it was propagated from
};

class PosePredictor {
 public:
  // max_buffered: samples kept for re-propagation (2 s at 2 kHz by default).
  explicit PosePredictor(ImuParams params, double inv_expo_cov = 0.0,
                         std::size_t max_buffered = 4096);

  // A new filter estimate at t. Samples buffered with later stamps are propagated again from it.
  void reset(MappedTime t, const Belief& belief);
  // A body-IMU sample (mapped time). Returns the propagated pose at its time, or nullopt before
  // the first estimate and for a sample not newer than the last one used.
  std::optional<PredictedPose> add(const ImuSample& sample);

  [[nodiscard]] bool has_estimate() const { return have_estimate_; }
  [[nodiscard]] std::uint64_t dropped_samples() const { return dropped_; }

 private:
  void step(const ImuSample& sample);

  ImuParams params_;
  double inv_expo_cov_;
  std::size_t max_buffered_;
  // Samples newer than the last estimate, in time order: a ring allocated once (no allocation
  // per sample on the scheduler thread).
  [[nodiscard]] const ImuSample& at(std::size_t i) const {
    return ring_[(head_ + i) % ring_.size()];
  }
  std::vector<ImuSample> ring_;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  bool have_estimate_ = false;
  MappedTime estimate_t_;
  Belief belief_;
  MappedTime t_;                   // time of belief_
  std::optional<ImuSample> last_;  // the sample belief_ was propagated with last
  std::uint64_t dropped_ = 0;
};

}  // namespace livod::estimator
