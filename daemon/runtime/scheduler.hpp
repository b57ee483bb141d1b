#pragma once
// The scheduler loop: the one loop behind `livod replay`, `livod replay --realtime` and
// `livod run` (DESIGN.md "Runtime"). It owns the sensors' sources, their clock domains and the
// estimator, and runs on one thread:
//
//   sources ──(earliest ready event first: merge on receive time, ties in configuration order)──▶
//   the source decodes it ──▶ the sensor's clock domain (+ time_offset_s, once) ──▶ the estimator's
//   measurement sync ──▶ LioPipeline ──▶ OutputSink (frames; IMU-rate poses)
//
// Replay calls step() until every source is exhausted: one thread, deterministic (the same input
// gives the same bytes out, for any worker-pool size). The daemon's scheduler thread calls step()
// whenever events are ready and waits otherwise; it hands one estimator group at a time to the
// update thread (SchedulerOptions::update_thread) and keeps delivering events meanwhile, holding
// what is for the estimator until the update is collected: IMU-rate poses never wait for a scan
// update, and when the estimator falls behind whole scans are dropped at its bounded scan queue
// (and counted), never packets. The estimator sees the same measurements in the same order
// either way, so its output does not depend on which thread ran it.
//
// The estimator takes the body IMU (body_frame) and every enabled LiDAR (at most
// estimator::kMaxLidars). The reference LiDAR - the body IMU's own LiDAR when the body is an
// internal IMU ("<lidar>.imu"), else the first enabled LiDAR - is the estimator's LiDAR 0 (its
// pose is the frame output's T_world_lidar); the others follow in configuration order. Each
// LiDAR's scans go through its own clock domain and carry its own T_imu_lidar = its
// T_body_sensor; the scans of different LiDARs need not be synchronised (estimator/sync: every
// scan end is an update, docs/estimator.md "Several LiDARs"). With estimator.vio.enabled (one
// LiDAR only) it also takes the first enabled camera, whose frames go through that camera's
// clock domain into the visual update (LIO then VIO at the image time, estimator/sync); T_imu_cam
// is its T_body_sensor. A live camera's frames arrive already on the common timeline and
// decimated (MeasurementSource::delivers_mapped_images: the camera driver's clock maps them to
// mid-exposure) and go to the estimator as they are. The body IMU may be a LiDAR's internal IMU
// or an external one (CAN, serial: live or replayed). A LiDAR's internal IMU, when enabled, feeds
// its clock domain even when it is not the body IMU.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "core/time.hpp"
#include "daemon/config/config.hpp"
#include "daemon/runtime/output_sink.hpp"
#include "daemon/runtime/sensor_clock.hpp"
#include "daemon/runtime/source.hpp"
#include "daemon/runtime/update_thread.hpp"
#include "estimator/imu/pose_predictor.hpp"
#include "estimator/pipeline.hpp"
#include "estimator/task_runner.hpp"

namespace livod::daemon::runtime {

// Which configured sensors the estimator uses, and how.
struct SensorRoles {
  int body_imu = -1;  // index into config.sensors
  int lidar = -1;     // the estimator's reference LiDAR (its LiDAR 0)
  int camera = -1;    // the visual update's camera; -1: none (no camera, or VIO disabled)
  Eigen::Isometry3d T_imu_lidar = Eigen::Isometry3d::Identity();  // the reference LiDAR's
  // Every LiDAR the estimator takes, by its estimator index (lidars[0] == lidar), and their
  // extrinsics (T_body_sensor).
  std::vector<int> lidars;
  std::vector<Eigen::Isometry3d> T_imu_lidars;
  // Per sensor: why it is not used (empty when used). Disabled sensors and sensors the estimator
  // does not take.
  std::vector<std::string> unused_reason;
};

// Throws livod::Error when the configuration names no body IMU, has no enabled LiDAR, more than
// estimator::kMaxLidars, or several LiDARs and a camera with estimator.vio.enabled.
SensorRoles assign_roles(const LivodConfig& config);

// The estimator's camera from a camera sensor's configuration: model, size and distortion at full
// resolution, the configured scale and T_imu_cam = the sensor's T_body_sensor (the body frame is
// the IMU's).
estimator::vio::VioCamera vio_camera(const SensorConfig& sensor);

// A source for one configured sensor.
struct SensorInput {
  std::size_t sensor_index = 0;  // into config.sensors
  std::unique_ptr<MeasurementSource> source;
  std::string origin;  // the file, topic or address it reads, for reports
};

struct SchedulerOptions {
  std::size_t max_groups_per_step = SIZE_MAX;  // the daemon: 1
  std::size_t max_queued_scans = 20;           // the estimator's scan queue (oldest dropped)
  // Replay only: stop once this much recording (receive time after the first event) has been
  // delivered; 0 = everything.
  Nanoseconds max_recording{0};
  // With a camera: colour the registered scan of image groups from the image
  // (PipelineOutput::colors; replay's map.pcd) and keep the visual update's patches and image for
  // drawing (--debug-images).
  bool vio_colorize = false;
  bool vio_debug = false;
  // The daemon: run each estimator group on an UpdateThread (update_thread.hpp) while this thread
  // keeps delivering events and publishing IMU-rate poses; measurements that arrive during an
  // update are queued here (bounded) and handed to the estimator after it. `update_doorbell` is
  // rung when an update ends. Off (replay): every group runs on the calling thread.
  bool update_thread = false;
  drivers::capture::Doorbell* update_doorbell = nullptr;
  UpdateThreadOptions update_thread_options;
};

// What health reports of the estimator, as of the last time the scheduler thread owned it (an
// update running on the update thread must not be read).
struct EstimatorStatus {
  bool initialised = false;
  std::string init_status;
  estimator::PipelineCounters counters;
  std::size_t queued_scans = 0;  // in the estimator and waiting for it
  std::size_t queued_imu = 0;
  std::uint64_t held_scans_dropped = 0;  // queued during an update beyond the bound
  std::uint64_t held_imu_dropped = 0;
};

// One sensor as the scheduler runs it.
struct ScheduledSensor {
  const SensorConfig* config = nullptr;
  std::size_t index = 0;
  std::string role;  // "lidar + body imu", "lidar", "body imu", "camera"
  std::string origin;
  std::unique_ptr<MeasurementSource> source;
  std::unique_ptr<SensorClockMapper> clock;
  bool scans_to_estimator = false;
  std::size_t lidar_slot = 0;  // the estimator's index of this LiDAR (SensorRoles::lidars)
  bool imu_to_estimator = false;
  bool images_to_estimator = false;
  bool imu_usable = false;  // its IMU samples may feed the clock (an internal IMU, or an IMU)
  drivers::DecoderSinks sinks;
  std::uint64_t scans = 0;
  std::uint64_t imu_samples = 0;
  std::uint64_t images = 0;       // frames handed to the estimator
  std::uint64_t images_seen = 0;  // frames the source delivered (camera.decimation counts them)
  std::optional<HostTime> last_event;  // receive time of the newest delivered event
};

struct SchedulerStats {
  double decode_s = 0.0;     // reading + decoding + clock mapping (wall)
  double estimator_s = 0.0;  // LioPipeline::process without the outputs (wall)
  double output_s = 0.0;     // OutputSink calls (wall)
  std::uint64_t events = 0;
  std::uint64_t frames = 0;
  std::uint64_t imu_poses = 0;
  std::optional<std::int64_t> first_event_ns;
  std::int64_t last_event_ns = 0;
};

class Scheduler {
 public:
  // `inputs`: the sources of the used sensors (see assign_roles); a used sensor without a source
  // is an error (livod::Error naming it). `runner` (may be null) and `sink` must outlive the
  // scheduler.
  Scheduler(const LivodConfig& config, std::vector<SensorInput> inputs,
            estimator::TaskRunner* runner, OutputSink& sink, SchedulerOptions options = {});
  ~Scheduler();
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  // Delivers the earliest ready event of any source, then runs up to max_groups_per_step
  // estimator groups. Returns false when there was nothing to do (no event ready, no group due).
  bool step();
  // Every source exhausted (recordings at their end; live sources stopped and drained).
  [[nodiscard]] bool exhausted();
  // Stops the live sources' threads (their rings can still be drained by step()).
  void stop_sources();
  // End of input: flushes the decoders' partial scans and runs every remaining group.
  void finish();
  // Runs every queued group the IMU data covers (used when draining at shutdown).
  void process_all();
  // Like step() without delivering an event: with the update thread, collects a finished update
  // and starts the next due group. Returns whether a frame was completed.
  bool process_due() { return process(options_.max_groups_per_step) > 0; }

  [[nodiscard]] const std::vector<std::unique_ptr<ScheduledSensor>>& sensors() const {
    return sensors_;
  }
  // Not while an update runs on the update thread (replay and tests without it).
  [[nodiscard]] const estimator::LioPipeline& pipeline() const { return *pipeline_; }
  // The estimator's counters and queues for health, safe to call between steps.
  [[nodiscard]] const EstimatorStatus& estimator_status();
  // The update thread's heartbeat (0 without one).
  [[nodiscard]] std::uint64_t update_beats() const {
    return update_thread_ ? update_thread_->beats() : 0;
  }
  [[nodiscard]] bool has_update_thread() const { return update_thread_ != nullptr; }
  // A group is on the update thread (measurements arriving now are held).
  [[nodiscard]] bool update_running() const { return update_thread_ && update_thread_->busy(); }
  [[nodiscard]] const SchedulerStats& stats() const { return stats_; }
  [[nodiscard]] const SensorRoles& roles() const { return roles_; }
  // The fraction of the recording replayed, when a source can tell.
  [[nodiscard]] std::optional<double> fraction_done() const { return fraction_; }
  // The newest filter output's time (nullopt before the first frame).
  [[nodiscard]] std::optional<MappedTime> last_frame_time() const { return last_frame_t_; }
  [[nodiscard]] double last_frame_ms() const { return last_frame_ms_; }

 private:
  void build_sensors(std::vector<SensorInput> inputs);
  // Runs up to `max_groups` estimator groups, one pipeline call per group so that each frame's
  // CPU time is its own.
  std::size_t process(std::size_t max_groups);
  // With the update thread: collects a finished update and starts the next due group.
  std::size_t process_on_update_thread();
  // The update thread's job: the taken group through the pipeline.
  void run_update();
  // After a collected update: hands over the held measurements, publishes its frame.
  void finish_update();
  // Publishes a finished frame (scheduler thread).
  void emit_frame(const estimator::PipelineOutput& out, std::int64_t rx_ns, double cpu_s,
                  bool estimate_sent = false);
  // Scheduler thread, update running or just collected: hands the update's estimate to the sink
  // (OutputSink::on_estimate) once the job has copied it, once per update.
  void emit_estimate_if_ready();
  // Hands what arrived during an update to the estimator, in arrival order.
  void release_held();
  void refresh_status();
  // Measurement delivery: straight into the estimator, or held while an update runs.
  void to_estimator(const ImuSample& m);
  void to_estimator(LidarScan scan, std::size_t lidar);
  void to_estimator(ImageFrame frame);

  const LivodConfig& config_;
  SchedulerOptions options_;
  OutputSink& sink_;
  SensorRoles roles_;
  std::vector<std::unique_ptr<ScheduledSensor>> sensors_;  // used sensors, in configuration order
  std::unique_ptr<estimator::LioPipeline> pipeline_;
  estimator::PosePredictor predictor_;
  bool want_imu_poses_ = false;
  SchedulerStats stats_;
  std::optional<double> fraction_;
  std::optional<MappedTime> last_frame_t_;
  double last_frame_ms_ = 0.0;
  std::int64_t current_rx_ns_ = 0;  // receive time of the event being delivered
  ImuSample last_body_imu_;         // the newest body-IMU sample (mapped)
  bool cut_ = false;                // max_recording reached

  // The update thread (options_.update_thread) and what it hands back.
  std::unique_ptr<UpdateThread> update_thread_;
  std::optional<estimator::PipelineOutput> update_out_;  // written by the job
  double update_wall_s_ = 0.0;                           // written by the job
  double update_cpu_s_ = 0.0;                            // written by the job
  std::int64_t update_rx_ns_ = 0;  // receive time of the event that completed the group
  // The group's estimate, copied by the job as soon as the update ended (before the map
  // insertion) and then left alone until the next start(); estimate_ready_ publishes it.
  struct UpdateEstimate {
    MappedTime t;
    estimator::State x;
    estimator::StateMatrix P;
    bool updated = false;
    estimator::DegeneracyReport degeneracy;
  };
  UpdateEstimate update_estimate_;
  std::atomic<bool> estimate_ready_{false};
  bool estimate_emitted_ = false;  // scheduler thread
  // Measurements that arrived during an update, in arrival order; bounded (oldest scan or sample
  // dropped, counted) so that an estimator stuck for long cannot grow memory.
  struct HeldScan {
    LidarScan scan;
    std::size_t lidar = 0;  // the estimator's LiDAR slot
  };
  std::vector<std::variant<ImuSample, HeldScan, ImageFrame>> held_;
  std::size_t held_scans_ = 0;
  std::size_t held_imu_ = 0;
  EstimatorStatus status_;
};

}  // namespace livod::daemon::runtime
