#pragma once
// The odometry loop: LiDAR-inertial (fast-livo2-notes.md 1.1-1.3) and, with a camera, visual too
// (1.4). Per measurement group (sync/measurement_sync.hpp): IMU initialisation, forward
// propagation to the update time, backward undistortion, downsampling, the iterated
// point-to-plane update and map insertion; in an image group then the photometric update at the
// same instant (vio/vio_processor.hpp). Without a camera (or with estimator.vio.enabled false)
// every group is a scan and this is the LIO of before, unchanged. Inputs carry mapped times
// (every per-sensor offset already applied once, by the clock domain); outputs are stamped with
// measurement time (the scan end or the image's mid-exposure), never wall-clock time.
//
// Several LiDARs (PipelineOptions::T_imu_more_lidars): every scan end of any LiDAR is an update,
// with the points of every LiDAR measured since the last update (sync/measurement_sync.hpp), each
// undistorted and downsampled in its own LiDAR's frame with its own extrinsic, then one iterated
// update over all of them (docs/estimator.md "Several LiDARs"). LIO only: no camera then.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "core/image.hpp"
#include "core/measurement.hpp"
#include "estimator/filter/esikf.hpp"
#include "estimator/imu/initializer.hpp"
#include "estimator/imu/undistortion.hpp"
#include "estimator/lio/downsample.hpp"
#include "estimator/lio/point_budget.hpp"
#include "estimator/lio/point_to_plane.hpp"
#include "estimator/lio/spatial_order.hpp"
#include "estimator/map/insert_gate.hpp"
#include "estimator/map/voxel_map.hpp"
#include "estimator/params.hpp"
#include "estimator/sync/measurement_sync.hpp"
#include "estimator/task_runner.hpp"
#include "estimator/vio/recent_sweep.hpp"
#include "estimator/vio/vio_processor.hpp"

namespace livod::estimator {

struct PipelineOptions {
  EstimatorParams params;
  Eigen::Isometry3d T_imu_lidar = Eigen::Isometry3d::Identity();  // LiDAR 0's (the reference)
  // Further LiDARs: LiDAR i >= 1 (add_scan's `lidar`) is at T_imu_more_lidars[i - 1]. At most
  // kMaxLidars in all; with any, `camera` must be unset or VIO disabled (the constructor throws).
  std::vector<Eigen::Isometry3d> T_imu_more_lidars;
  // Each LiDAR's own point settings, by the same index (0: the reference LiDAR); missing entries
  // are the defaults (params.lio's noise, building the map).
  std::vector<LidarLioParams> lidar_lio;
  double lidar_wait_s = 0.05;  // SyncParams::lidar_wait_s
  // Runs residual rows, point covariances and map refits in parallel (the daemon's worker pool);
  // nullptr: everything on the caller's thread. Results are the same either way. Must outlive the
  // pipeline.
  TaskRunner* runner = nullptr;
  int min_matches = 30;            // fewer matched points: keep the propagated state
  double degeneracy_ratio = 0.02;  // translation information ratio below which a frame is flagged
  std::size_t max_queued_scans = 20;  // bounded input queues (oldest dropped, counted)
  std::size_t max_queued_imu = 4000;
  // The camera of the visual update; none: LIO only. Used when params.vio.enabled.
  std::optional<vio::VioCamera> camera;
  bool colorize = false;   // colour the scan from the image in image groups (PipelineOutput)
  bool vio_debug = false;  // fill FrameReport::vio.debug with every patch (--debug-images)
};

struct FrameTimings {
  double propagate_ms = 0.0;
  double undistort_ms = 0.0;
  double downsample_ms = 0.0;
  double residuals_ms = 0.0;  // point covariances, association and residual rows, all iterations
  double update_ms = 0.0;     // the iterated update without its residuals (solves, covariance)
  double map_ms = 0.0;
  double vio_ms = 0.0;  // the visual update of an image group (split in FrameReport::vio)
  double total_ms = 0.0;
};

struct FrameReport {
  MeasurementGroup::Kind kind = MeasurementGroup::Kind::lidar;
  MappedTime t;
  std::uint32_t scan_sequence = 0;
  int lidar = 0;  // the LiDAR whose scan end is t (several LiDARs; 0 otherwise)
  int raw_points = 0;
  int used_points = 0;             // after blind/point_filter_num and downsampling
  double downsample_cell_m = 0.0;  // the voxel-grid cell used (adapts with lio.point_budget)
  int matched = 0;
  int iterations = 0;
  bool converged = false;
  bool updated = false;  // false: first frame (map seeded) or too few matches
  DegeneracyReport degeneracy;
  FrameTimings timings;
  VoxelMapStats map;   // the map after this frame
  vio::VioReport vio;  // image groups
};

struct PipelineOutput {
  MappedTime t;
  State x;
  StateMatrix P;
  FrameReport report;
  // The frame's points as the update used them (undistorted to t, downsampled), registered in the
  // world frame with their world covariances (pose uncertainty included). Valid during the
  // output callback only.
  std::span<const CovPoint> registered_world;
  // The (reference) LiDAR's pose at t (after both updates in an image group):
  // T_world_imu * T_imu_lidar.
  Eigen::Isometry3d T_world_lidar = Eigen::Isometry3d::Identity();
  // Image groups with PipelineOptions::colorize: the same points (in registered_world's order)
  // placed with the pose after the visual update, their colours (0x00RRGGBB) sampled from the
  // image and whether each fell inside it (1) or not (0). Empty otherwise. Valid during the output
  // callback only.
  std::span<const Eigen::Vector3d> colored_world;
  std::span<const std::uint32_t> colors;
  std::span<const std::uint8_t> in_image;
  // Image groups with PipelineOptions::vio_debug: the grey image the visual update used (its
  // patches are in report.vio.debug); empty otherwise.
  cv::Mat vio_grey;
};

// A group's estimate as soon as it is final, before the rest of the frame's work: after the LIO
// update of a LiDAR group (the map insertion that follows does not change it), after the visual
// update of an image group. The daemon publishes the pose from it, so that a pose does not wait
// for the map insertion (half of a frame). Valid during the callback only.
struct FilterEstimate {
  MappedTime t;
  const State& x;
  const StateMatrix& P;
  bool updated = false;  // as FrameReport::updated
  DegeneracyReport degeneracy;
};
using EstimateCallback = std::function<void(const FilterEstimate&)>;

struct PipelineCounters {
  std::uint64_t scans_in = 0;
  std::uint64_t scans_processed = 0;
  std::uint64_t scans_before_init = 0;  // dropped while IMU initialisation was pending
  std::uint64_t scans_out_of_order = 0;
  std::uint64_t scans_queue_overflow = 0;
  std::uint64_t scans_late = 0;   // several LiDARs: a LiDAR's scan that ended before the filter
  std::uint64_t points_late = 0;  // ... and points of partly late scans (SyncCounters)
  std::uint64_t imu_in = 0;
  std::uint64_t imu_out_of_order = 0;
  std::uint64_t imu_queue_overflow = 0;
  std::uint64_t frames_without_update = 0;
  std::uint64_t degenerate_frames = 0;
  // Groups whose points (of one LiDAR at least) were held back: no new viewpoint
  // (lio.map_min_move_m).
  std::uint64_t scans_not_mapped = 0;
  std::uint64_t images_in = 0;
  // No camera configured, VIO disabled, before the IMU initialisation or the first scan's end.
  std::uint64_t images_unused = 0;
  std::uint64_t images_late = 0;      // arrived after the estimator passed their time
  std::uint64_t images_dropped = 0;   // out of order or queue overflow
  std::uint64_t images_rejected = 0;  // wrong size or format (VioReport::problem)
  std::uint64_t image_groups = 0;     // LIO + VIO at an image time
  std::uint64_t vio_updates = 0;      // image groups whose visual update corrected the state
};

class LioPipeline {
 public:
  explicit LioPipeline(PipelineOptions options);
  ~LioPipeline();

  void add_imu(const ImuSample& sample);
  // Taken by value (it is queued): move a scan in when the caller is done with it. `lidar`: which
  // LiDAR (0: T_imu_lidar; i >= 1: T_imu_more_lidars[i - 1]); other indices are ignored.
  void add_scan(LidarScan scan, std::size_t lidar = 0);
  [[nodiscard]] std::size_t lidars() const { return T_imu_lidars_.size(); }
  // An image stamped with its mid_exposure (core/image.hpp). The pipeline keeps a reference to
  // the pixels until the image is processed: the producer must not write into them afterwards.
  // Ignored (counted) without a camera or with VIO disabled.
  void add_image(ImageFrame image);
  [[nodiscard]] bool vio_active() const { return vio_ != nullptr; }
  // Runs the groups whose update time (scan end or image time) is covered by IMU data, at most
  // `max_groups` of them (the daemon runs one at a time so that it can drain its rings in
  // between); returns how many ran.
  std::size_t process(const std::function<void(const PipelineOutput&)>& on_output,
                      std::size_t max_groups = SIZE_MAX);
  // process() in two steps, for a caller that runs the update on another thread while it keeps
  // receiving (the daemon): take_group() moves the next due group out of the measurement queues
  // (cheap) and process_taken() runs it. Between take_group() returning true and the end of
  // process_taken() the caller makes no other call: the update owns the whole pipeline.
  // process(f, n) is exactly n rounds of both.
  // `on_estimate` (may be empty) is called once per group, before `on_output`, as soon as the
  // estimate is final (FilterEstimate).
  bool take_group();
  void process_taken(const std::function<void(const PipelineOutput&)>& on_output,
                     const EstimateCallback& on_estimate = {});
  // Scans queued for the estimator (waiting for IMU data or for their turn).
  [[nodiscard]] std::size_t queued_scans() const { return sync_.queued_scans(); }
  [[nodiscard]] std::size_t queued_imu() const { return sync_.queued_imu(); }

  [[nodiscard]] bool initialised() const { return initializer_.done(); }
  [[nodiscard]] const std::string& init_status() const { return initializer_.status(); }
  [[nodiscard]] PipelineCounters counters() const;
  [[nodiscard]] const VoxelMap& map() const { return *map_; }
  [[nodiscard]] const Belief& belief() const { return belief_; }
  // The points of the scan processed last, as the update used them: undistorted to the scan end
  // and downsampled, in the LiDAR frame (several LiDARs: each in its own LiDAR's frame, in LiDAR
  // order). Valid until the next process() (map export in replay).
  [[nodiscard]] const std::vector<Eigen::Vector3d>& last_scan_points() const {
    return undistorted_;
  }
  // The visual half, when active (debug drawing, map statistics).
  [[nodiscard]] const vio::VioProcessor* vio() const { return vio_.get(); }

 private:
  void process_group(const MeasurementGroup& group,
                     const std::function<void(const PipelineOutput&)>& on_output,
                     const EstimateCallback& on_estimate);
  // Propagates the belief through the group's IMU samples to its update time, recording the IMU
  // poses along the way (for undistortion).
  void propagate_to(const MeasurementGroup& group, ImuPoseTrack& track);
  // The visual update of an image group, after the LIO update and map insertion.
  // `t_begin`: the previous update time (the group holds the points measured since).
  void visual_update(const MeasurementGroup& group, MappedTime t_begin, bool lio_matched,
                     FrameReport& report);
  // Selects, undistorts (to t) and downsamples one LiDAR's points, appending them to
  // undistorted_ and point_lidar_.
  void prepare_points(const LidarScan& scan, std::size_t lidar, MappedTime t,
                      FrameTimings& timings);
  // fn(begin, end) over [0, n), on the runner when there is one.
  void for_points(std::size_t n, const std::function<void(std::size_t, std::size_t)>& fn) const;

  PipelineOptions options_;
  std::vector<Eigen::Isometry3d> T_imu_lidars_;  // every LiDAR's, by index
  ImuInitializer initializer_;
  MeasurementSync sync_;
  MeasurementGroup group_;  // the group being processed (its IMU vector keeps its capacity)
  std::unique_ptr<VoxelMap> map_;
  std::unique_ptr<PointToPlane> p2p_;
  std::array<PointNoise, kMaxLidars> noise_{};  // each LiDAR's point noise model
  std::vector<CovPoint> map_points_;            // the points that do (when not all LiDARs build)
  VoxelGridDownsampler downsampler_;
  std::optional<PointBudget> point_budget_;
  std::vector<Eigen::Vector3d> raw_points_;  // the selected points in the LiDAR's frame
  std::vector<std::uint32_t> kept_;          // indices the voxel grid keeps
  SpatialOrder spatial_order_;
  Belief belief_;
  MappedTime state_time_;
  bool have_prev_imu_ = false;
  ImuSample prev_imu_;
  PipelineCounters counters_;  // the pipeline's own; counters() adds the sync's
  struct {
    std::uint64_t scans_in = 0;
    std::uint64_t imu_in = 0;
    std::uint64_t imu_out_of_order = 0;
  } init_counters_;  // input while the IMU initialisation is pending
  // Scans that arrived while the initialisation was pending and end after every IMU sample seen:
  // whether they precede the initialisation is only known once it ends (live, the LiDAR and the
  // IMU arrive through different sockets, so arrival order is not time order).
  struct EarlyScan {
    LidarScan scan;
    std::size_t lidar = 0;
  };
  std::deque<EarlyScan> early_scans_;
  MappedTime init_time_;  // when the initialisation ended: scans must begin after it
  ImuPoseTrack track_;
  std::vector<std::uint32_t> indices_;
  std::vector<Eigen::Vector3d> undistorted_;
  std::vector<Eigen::Vector3d> lidar_points_;  // one LiDAR's, before joining undistorted_
  std::vector<std::uint32_t> point_lidar_;     // per point of undistorted_: its LiDAR
  std::vector<ScanPoint> scan_points_;
  std::vector<CovPoint> world_points_;
  std::unique_ptr<vio::VioProcessor> vio_;
  std::vector<Eigen::Vector3d> scan_world_;  // the scan in the world after the LIO update
  std::vector<Eigen::Vector3d> no_normals_;
  // Which sweeps go into the map (lio.map_min_move_m): one gate per LiDAR, each admitting a scan
  // period of its own points, since the LiDARs' sweeps begin at different times.
  std::vector<MapInsertGate> map_gates_;
  std::array<Nanoseconds, kMaxLidars> scan_periods_{};  // each LiDAR's newest scan span
  vio::RecentSweep recent_sweep_;  // what the visual update looks at: a whole sweep
  std::vector<std::uint32_t> colors_;
  std::vector<std::uint8_t> colored_;
  std::uint64_t images_unused_ = 0;
  std::uint64_t images_rejected_ = 0;
  std::uint64_t vio_updates_ = 0;
};

}  // namespace livod::estimator
