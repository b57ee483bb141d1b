#pragma once
// What the scheduler loop hands to its outputs, on the scheduler thread. `livod replay` writes
// files synchronously (replay/file_outputs.hpp: deterministic, nothing dropped); `livod run` and
// `replay --realtime` copy into pre-allocated records and hand them to the publisher thread
// (runtime/publisher.hpp), never blocking the scheduler.
//
// References passed to these calls are valid during the call only.

#include <Eigen/Geometry>
#include <cstdint>
#include <span>

#include "core/time.hpp"
#include "estimator/imu/pose_predictor.hpp"
#include "estimator/pipeline.hpp"

namespace livod::daemon::runtime {

struct FrameOutput {
  const estimator::PipelineOutput& estimate;  // t, state, covariance, report, registered scan
  std::uint64_t index = 0;                    // frames output so far, from 0
  // Host receive time (ns) of the packet whose decoding completed the scan: the latency of a pose
  // is measured from it.
  std::int64_t completed_rx_ns = 0;
  double cpu_ms = 0.0;  // CPU time of the frame, every thread of the process
  // The newest body-IMU reading when the frame was output (raw: biases not removed), for the
  // angular rate and acceleration published with the pose.
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
  // on_estimate() was called for this frame before (the daemon's update thread): its pose went
  // out then.
  bool estimate_sent = false;
};

// A frame's estimate as soon as the update ended (estimator::FilterEstimate), before the frame's
// remaining work (map insertion): the daemon publishes the pose from it. Same index, receive time
// and IMU reading as the FrameOutput that follows.
struct EstimateOutput {
  const estimator::FilterEstimate& estimate;
  std::uint64_t index = 0;
  std::int64_t completed_rx_ns = 0;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
};

struct ImuPoseOutput {
  const estimator::PredictedPose& pose;
  const ImuSample& sample;  // the body-IMU sample it was propagated to (mapped)
  std::int64_t rx_ns = 0;   // host receive time of the IMU sample
};

class OutputSink {
 public:
  virtual ~OutputSink() = default;
  virtual void on_frame(const FrameOutput& frame) = 0;
  // Before on_frame() of the same frame, when the scheduler runs updates on the update thread.
  // Default: nothing (on_frame has everything).
  virtual void on_estimate(const EstimateOutput& /*estimate*/) {}
  // One per body-IMU sample once the filter runs (IMU-rate pose). Default: not wanted.
  virtual void on_imu_pose(const ImuPoseOutput& /*pose*/) {}
  // Whether on_imu_pose is wanted at all (the scheduler then skips the propagation).
  [[nodiscard]] virtual bool wants_imu_poses() const { return false; }
};

}  // namespace livod::daemon::runtime
