#pragma once
// IMU initialisation (fast-livo2-notes.md 1.2, with its defect 12 fixed): a window of samples
// that must be static - the initialiser refuses to start while the platform moves and says why -
// gives gravity (from the mean specific force) and the gyro bias (from the mean rate). Units are
// checked instead of silently rescaled: a mean |accel| near 1 means the driver forgot g -> m/s^2.

#include <deque>
#include <optional>
#include <string>

#include "core/measurement.hpp"
#include "estimator/filter/state.hpp"
#include "estimator/params.hpp"

namespace livod::estimator {

struct InitialCovariance {
  double rotation = 0.01;
  double position = 0.01;
  double inv_exposure = 1e-5;
  double velocity = 0.01;
  double bias_gyro = 1e-5;
  double bias_accel = 1e-3;  // larger than FAST-LIVO2's 1e-5: b_a is not set from the window
  double gravity = 1e-5;
};

class ImuInitializer {
 public:
  explicit ImuInitializer(const ImuParams& params, InitialCovariance cov = {})
      : params_(params), cov_(cov) {}

  // Adds a sample; returns true once initialised (further samples are ignored).
  bool add(const ImuSample& sample);

  [[nodiscard]] bool done() const { return result_.has_value(); }
  // The initial belief, with the state at the time of the last window sample.
  [[nodiscard]] const std::optional<Belief>& result() const { return result_; }
  [[nodiscard]] MappedTime time() const { return time_; }
  // Why initialisation has not happened yet ("collecting 12/30 samples", "moving: ...").
  [[nodiscard]] const std::string& status() const { return status_; }
  // Times the window was rejected because the platform moved.
  [[nodiscard]] int rejections() const { return rejections_; }

 private:
  [[nodiscard]] bool window_full() const;

  ImuParams params_;
  InitialCovariance cov_;
  std::deque<ImuSample> window_;
  std::optional<Belief> result_;
  MappedTime time_;
  std::string status_ = "waiting for IMU samples";
  std::string last_rejection_;
  int rejections_ = 0;
};

}  // namespace livod::estimator
