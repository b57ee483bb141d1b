#include "daemon/replay/replay_engine.hpp"

#include <fmt/core.h>

#include <time.h>

#include <chrono>
#include <fstream>
#include <memory>
#include <optional>

#include "core/error.hpp"
#include "core/image.hpp"
#include "daemon/replay/debug_images.hpp"
#include "daemon/replay/image_sources.hpp"
#include "daemon/replay/input_assignment.hpp"
#include "daemon/replay/map_accumulator.hpp"
#include "daemon/replay/progress.hpp"
#include "daemon/replay/sources.hpp"
#include "daemon/replay/trajectory_writer.hpp"
#include "daemon/runtime/sensor_clock.hpp"
#include "daemon/worker_pool.hpp"
#include "estimator/pipeline.hpp"

namespace livod::daemon::replay {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// CPU time of this process, every thread (s): unlike wall time, it does not count time spent
// preempted by other processes, so per-frame figures stay meaningful on a loaded machine. With
// the worker pool it is the CPU a frame costs in all, which exceeds its wall time when both cores
// work.
double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// One replayed sensor: its recording, its clock and what it gives the estimator.
struct ReplayedSensor {
  const SensorConfig* config = nullptr;
  std::string role;
  std::string file;
  std::unique_ptr<ReplaySource> source;
  std::unique_ptr<runtime::SensorClockMapper> clock;
  bool scans_to_estimator = false;
  bool imu_to_estimator = false;
  bool images_to_estimator = false;
  bool imu_usable =
      false;  // its IMU samples may feed the clock (an enabled internal IMU, or an IMU)
  drivers::DecoderSinks sinks;
  std::uint64_t scans = 0;
  std::uint64_t imu_samples = 0;
  std::uint64_t images = 0;       // handed to the estimator
  std::uint64_t images_seen = 0;  // delivered by the source (camera.decimation counts them)
};

// The per-image columns of the visual update (4 bytes each per image).
struct VioSeries {
  std::vector<float> total, pyramid, selection, update, map, patches;

  void add(const estimator::vio::VioReport& v) {
    total.push_back(static_cast<float>(v.timings.total_ms));
    pyramid.push_back(static_cast<float>(v.timings.pyramid_ms));
    selection.push_back(static_cast<float>(v.timings.selection_ms));
    update.push_back(static_cast<float>(v.timings.update_ms));
    map.push_back(static_cast<float>(v.timings.map_ms));
    patches.push_back(static_cast<float>(v.patches));
  }
};

// The estimator's camera: the first enabled camera, when the visual update is on.
int estimator_camera(const LivodConfig& config) {
  if (!config.estimator.vio.enabled) return -1;
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const auto& s = config.sensors[i];
    if (s.enabled && sensor_kind(s.driver) == SensorKind::camera) return static_cast<int>(i);
  }
  return -1;
}

// The per-frame columns kept for the report's distributions (4 bytes each per frame).
struct FrameSeries {
  std::vector<float> total, cpu, propagate, undistort, downsample, residuals, update, map;
  std::vector<float> raw_points, used_points, matched, iterations;

  void add(const estimator::FrameReport& r, double cpu_ms) {
    const auto& t = r.timings;
    total.push_back(static_cast<float>(t.total_ms));
    cpu.push_back(static_cast<float>(cpu_ms));
    propagate.push_back(static_cast<float>(t.propagate_ms));
    undistort.push_back(static_cast<float>(t.undistort_ms));
    downsample.push_back(static_cast<float>(t.downsample_ms));
    residuals.push_back(static_cast<float>(t.residuals_ms));
    update.push_back(static_cast<float>(t.update_ms));
    map.push_back(static_cast<float>(t.map_ms));
    raw_points.push_back(static_cast<float>(r.raw_points));
    used_points.push_back(static_cast<float>(r.used_points));
    matched.push_back(static_cast<float>(r.matched));
    iterations.push_back(static_cast<float>(r.iterations));
  }
};

// Picks the estimator's LiDAR: the body IMU's own LiDAR, else the first enabled LiDAR.
int estimator_lidar(const LivodConfig& config) {
  if (config.body_is_internal_imu) return config.body_sensor_index;
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const auto& s = config.sensors[i];
    if (s.enabled && sensor_kind(s.driver) == SensorKind::lidar) return static_cast<int>(i);
  }
  return -1;
}

ClockSummary clock_summary(const runtime::SensorClockMapper& mapper) {
  const ClockDomainStats s = mapper.domain().stats();
  ClockSummary c;
  c.mode = std::string(to_string(s.mode));
  c.quality = std::string(to_string(s.quality));
  c.offset_s = to_seconds(s.offset);
  c.skew_ppm = s.skew_ppm;
  c.jitter_us = to_seconds(s.jitter) * 1e6;
  c.residual_median_us = to_seconds(s.residual_median) * 1e6;
  c.observations = s.observations;
  c.resets = s.resets;
  c.rejected = s.rejected;
  c.time_offset_s = mapper.time_offset_s();
  return c;
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
  out.flush();
  if (!out) throw Error("cannot write " + path.string());
}

class Replay {
 public:
  Replay(const LivodConfig& config, const ReplayOptions& options)
      : config_(config), options_(options), map_(options.map_cell_m, options.map_max_points) {}

  ReplayResult run();

 private:
  void select_sensors();
  void open_outputs();
  void on_output(const estimator::PipelineOutput& o);
  // Runs the estimator on what is queued; returns its wall time (s) without the outputs'.
  double process();
  [[nodiscard]] ProgressState progress_state() const;
  ReplaySummary summarise(double wall_s) const;

  const LivodConfig& config_;
  const ReplayOptions& options_;
  ReplayResult result_;
  std::vector<std::unique_ptr<ReplayedSensor>> sensors_;  // in configuration order
  std::unique_ptr<WorkerPool> pool_;  // before pipeline_: the pipeline uses it until destroyed
  std::unique_ptr<estimator::LioPipeline> pipeline_;
  Eigen::Isometry3d T_imu_lidar_ = Eigen::Isometry3d::Identity();
  int camera_ = -1;  // index of the estimator's camera in the configuration, -1: none
  VioSeries vio_series_;
  double inv_exposure_ = 1.0;
  std::optional<TrajectoryWriter> trajectory_;
  std::optional<FrameTable> frames_;
  MapAccumulator map_;
  FrameSeries series_;
  // Frames output by the process() call under way: their rows wait for its CPU time.
  struct PendingFrame {
    estimator::FrameReport report;
    std::size_t exported_points = 0;
    std::size_t rss_bytes = 0;
  };
  std::vector<PendingFrame> pending_;
  double output_cpu_s_ = 0.0;
  std::size_t map_bytes_peak_ = 0;
  std::size_t frame_count_ = 0;
  double last_frame_ms_ = 0.0;
  double output_s_ = 0.0;
  std::optional<std::int64_t> first_event_ns_;
  std::int64_t last_event_ns_ = 0;
  std::optional<double> fraction_;
};

void Replay::select_sensors() {
  if (config_.body_sensor_index < 0) {
    throw Error("the configuration names no body IMU (body_frame): the estimator needs one");
  }
  const int lidar = estimator_lidar(config_);
  if (lidar < 0) throw Error("the configuration has no enabled LiDAR: the estimator needs one");
  const auto body = static_cast<std::size_t>(config_.body_sensor_index);
  const auto lidar_index = static_cast<std::size_t>(lidar);
  camera_ = estimator_camera(config_);
  T_imu_lidar_ = config_.sensors[lidar_index].T_body_sensor;

  const auto recordings = assign_recordings(config_, options_.inputs);
  for (std::size_t i = 0; i < config_.sensors.size(); ++i) {
    const SensorConfig& s = config_.sensors[i];
    const bool is_body = i == body;
    const bool is_lidar = i == lidar_index;
    const bool is_camera = static_cast<int>(i) == camera_;
    if (!is_body && !is_lidar && !is_camera) {
      const bool camera = sensor_kind(s.driver) == SensorKind::camera;
      result_.notes.push_back(
          fmt::format("sensor '{}' ({}) is not replayed: {}", s.name, enum_name(s.driver),
                      !s.enabled ? "disabled"
                      : camera && !config_.estimator.vio.enabled
                          ? "estimator.vio.enabled is false (LiDAR-inertial odometry only)"
                      : camera ? "the visual update uses one camera, the first enabled one"
                               : "the estimator takes the body IMU and one LiDAR"));
      continue;
    }
    const auto& recording = recordings[i];
    if (!recording) {
      throw Error("sensor '" + s.name + "' has no recording to replay: its source is live; give " +
                  "one on the command line (" + s.name + "=PATH)");
    }
    auto r = std::make_unique<ReplayedSensor>();
    r->config = &s;
    r->file = recording->replay.file.string();
    if (!recording->replay.topic.empty()) r->file += " " + recording->replay.topic;
    r->scans_to_estimator = is_lidar;
    r->imu_to_estimator = is_body;
    r->images_to_estimator = is_camera;
    r->imu_usable = sensor_kind(s.driver) == SensorKind::imu || s.imu.enabled;
    r->role = is_camera             ? "camera"
              : is_lidar && is_body ? "lidar + body imu"
              : is_lidar            ? "lidar"
                                    : "body imu";
    r->source = make_source(s, recording->replay, recording->ports);
    r->clock = std::make_unique<runtime::SensorClockMapper>(s);
    ReplayedSensor* self = r.get();
    // The sinks run only inside run()'s loop, once pipeline_ exists.
    r->sinks.on_imu = [this, self](const ImuSample& sample) {
      if (!self->imu_usable) return;
      ImuSample m = sample;
      self->clock->map_imu(m);
      ++self->imu_samples;
      if (self->imu_to_estimator) pipeline_->add_imu(m);
    };
    r->sinks.on_scan = [this, self](const LidarScan& scan) {
      if (!self->scans_to_estimator) return;
      // The decoder reuses its scan: one copy, stamped and moved into the estimator's queue.
      LidarScan copy = scan;
      self->clock->map_scan(copy);
      ++self->scans;
      pipeline_->add_scan(std::move(copy));
    };
    r->sinks.on_image = [this, self](const ImageFrame& image) {
      if (!self->images_to_estimator) return;
      // camera.decimation keeps every n-th frame (FAST-LIVO2 hilti_en: 4).
      const auto decimation =
          static_cast<std::uint64_t>(std::max(1, self->config->camera.decimation));
      if (self->images_seen++ % decimation != 0) return;
      ImageFrame frame = image;  // shares the pixels: the source made them for this frame
      self->clock->map_image(frame);
      ++self->images;
      pipeline_->add_image(std::move(frame));
    };
    sensors_.push_back(std::move(r));
  }
}

void Replay::open_outputs() {
  std::filesystem::create_directories(options_.out_dir);
  result_.trajectory = options_.out_dir / "trajectory.txt";
  result_.map = options_.out_dir / "map.pcd";
  result_.timing_text = options_.out_dir / "timing.txt";
  result_.timing_json = options_.out_dir / "timing.json";
  result_.frames_csv = options_.out_dir / "frames.csv";
  trajectory_.emplace(result_.trajectory);
  frames_.emplace(result_.frames_csv);
}

void Replay::on_output(const estimator::PipelineOutput& o) {
  const auto t0 = Clock::now();
  const double cpu0 = process_cpu_s();
  trajectory_->write(o.t, o.x.R_world_imu, o.x.p_world_imu);
  const Eigen::Matrix3d R_world_lidar = o.x.R_world_imu * T_imu_lidar_.linear();
  const Eigen::Vector3d p_world_lidar =
      o.x.R_world_imu * T_imu_lidar_.translation() + o.x.p_world_imu;
  const auto& points = pipeline_->last_scan_points();
  if (camera_ < 0) {
    for (const auto& p : points) map_.add(R_world_lidar * p + p_world_lidar);
  } else {
    // A camera's map holds the points its images saw, coloured (LIO-only frames add none).
    const auto& rgb = pipeline_->last_scan_colors();
    const auto& seen = pipeline_->last_scan_colored();
    for (std::size_t i = 0; i < points.size() && i < rgb.size(); ++i) {
      if (seen[i] != 0) map_.add(R_world_lidar * points[i] + p_world_lidar, rgb[i]);
    }
  }
  if (o.report.kind == estimator::MeasurementGroup::Kind::image && o.report.vio.ran) {
    vio_series_.add(o.report.vio);
    inv_exposure_ = o.report.vio.inv_exposure;
    if (!options_.debug_images_dir.empty() && pipeline_->vio() != nullptr) {
      write_debug_image(options_.debug_images_dir, o.t, pipeline_->vio()->last_grey(),
                        o.report.vio.debug, config_.estimator.vio.patch_size);
    }
  }
  pending_.push_back(PendingFrame{o.report, map_.size(), current_rss_bytes()});
  map_bytes_peak_ = std::max(map_bytes_peak_, o.report.map.bytes);
  last_frame_ms_ = o.report.timings.total_ms;
  output_cpu_s_ += process_cpu_s() - cpu0;
  output_s_ += seconds_since(t0);
}

double Replay::process() {
  const auto t0 = Clock::now();
  const double output_before = output_s_;
  const double cpu0 = process_cpu_s();
  output_cpu_s_ = 0.0;
  pipeline_->process([this](const estimator::PipelineOutput& o) { on_output(o); });
  if (!pending_.empty()) {
    // One scan per call in practice; when several were due they share the call's CPU time.
    const double cpu_ms =
        1e3 * (process_cpu_s() - cpu0 - output_cpu_s_) / static_cast<double>(pending_.size());
    for (const auto& f : pending_) {
      frames_->add(frame_count_, f.report, cpu_ms, f.exported_points, f.rss_bytes);
      series_.add(f.report, cpu_ms);
      ++frame_count_;
    }
    pending_.clear();
  }
  return seconds_since(t0) - (output_s_ - output_before);
}

ProgressState Replay::progress_state() const {
  ProgressState p;
  if (first_event_ns_) p.recording_s = to_seconds(Nanoseconds(last_event_ns_ - *first_event_ns_));
  p.fraction = fraction_;
  p.frames = frame_count_;
  p.last_frame_ms = last_frame_ms_;
  if (!pipeline_->initialised()) p.status = "IMU init: " + pipeline_->init_status();
  return p;
}

ReplayResult Replay::run() {
  select_sensors();
  estimator::PipelineOptions po;
  po.params = config_.estimator;
  po.T_imu_lidar = T_imu_lidar_;
  // One thread reads, decodes and runs the filter; the estimator spreads residuals and map refits
  // over the pool. Its results do not depend on the pool size (estimator/task_runner.hpp), so the
  // replay stays deterministic.
  const int threads = options_.threads >= 0 ? options_.threads : config_.estimator.threads;
  pool_ = std::make_unique<WorkerPool>(threads > 0 ? threads : WorkerPool::hardware_threads());
  po.runner = pool_.get();
  if (camera_ >= 0) {
    po.camera = vio_camera(config_.sensors[static_cast<std::size_t>(camera_)]);
    po.colorize = true;
    po.vio_debug = !options_.debug_images_dir.empty();
    if (po.vio_debug) std::filesystem::create_directories(options_.debug_images_dir);
  } else if (!options_.debug_images_dir.empty()) {
    throw Error("--debug-images needs a camera and estimator.vio.enabled");
  }
  pipeline_ = std::make_unique<estimator::LioPipeline>(po);
  open_outputs();

  ProgressLine progress(options_.progress);
  const auto wall_start = Clock::now();
  double decode_s = 0.0;
  double estimator_s = 0.0;
  const std::int64_t max_duration_ns =
      options_.max_duration_s > 0.0 ? from_seconds(options_.max_duration_s).count() : 0;

  while (true) {
    // k-way merge: the earliest next event; ties go to the sensor listed first.
    ReplayedSensor* next = nullptr;
    std::int64_t next_ns = 0;
    for (auto& s : sensors_) {
      const auto t = s->source->peek_time();
      if (t && (next == nullptr || *t < next_ns)) {
        next = s.get();
        next_ns = *t;
      }
    }
    if (next == nullptr) break;
    if (!first_event_ns_) first_event_ns_ = next_ns;
    if (max_duration_ns > 0 && next_ns - *first_event_ns_ > max_duration_ns) break;
    last_event_ns_ = std::max(last_event_ns_, next_ns);

    const auto t0 = Clock::now();
    next->source->deliver(next->sinks);
    decode_s += seconds_since(t0);
    estimator_s += process();
    if (const auto f = next->source->fraction_done()) fraction_ = f;
    progress.update(progress_state());
  }
  const auto t0 = Clock::now();
  for (auto& s : sensors_) s->source->finish(s->sinks);
  decode_s += seconds_since(t0);
  estimator_s += process();
  const double wall_s = seconds_since(wall_start);
  progress.finish(progress_state());

  trajectory_->close();
  frames_->close();
  if (camera_ >= 0) {
    write_pcd_rgb(result_.map, map_.xyz(), map_.rgb());
  } else {
    write_pcd(result_.map, map_.xyz());
  }
  result_.summary = summarise(wall_s);
  result_.summary.decode_s = decode_s;
  result_.summary.estimator_s = estimator_s;
  write_text_file(result_.timing_text, format_timing_text(result_.summary));
  write_text_file(result_.timing_json, format_timing_json(result_.summary));
  return std::move(result_);
}

ReplaySummary Replay::summarise(double wall_s) const {
  ReplaySummary s;
  s.config_file = config_.source_file.string();
  s.frames = trajectory_->poses();
  s.init_status = pipeline_->init_status();
  s.counters = pipeline_->counters();
  s.degenerate_frames = s.counters.degenerate_frames;
  s.frame_ms = distribution(series_.total);
  s.frame_cpu_ms = distribution(series_.cpu);
  s.propagate_ms = distribution(series_.propagate);
  s.undistort_ms = distribution(series_.undistort);
  s.downsample_ms = distribution(series_.downsample);
  s.residuals_ms = distribution(series_.residuals);
  s.update_ms = distribution(series_.update);
  s.map_ms = distribution(series_.map);
  s.raw_points = distribution(series_.raw_points);
  s.used_points = distribution(series_.used_points);
  s.matched = distribution(series_.matched);
  s.iterations = distribution(series_.iterations);
  s.recording_s =
      first_event_ns_ ? to_seconds(Nanoseconds(last_event_ns_ - *first_event_ns_)) : 0.0;
  s.wall_s = wall_s;
  s.output_s = output_s_;
  s.realtime_factor = wall_s > 0.0 ? s.recording_s / wall_s : 0.0;
  s.peak_rss_bytes = peak_rss_bytes();
  s.final_rss_bytes = current_rss_bytes();
  s.map = pipeline_->map().stats();
  s.map_bytes_peak = std::max(map_bytes_peak_, s.map.bytes);
  s.exported_points = map_.size();
  s.exported_dropped = map_.dropped_full();
  s.vio_ms = distribution(vio_series_.total);
  s.vio_pyramid_ms = distribution(vio_series_.pyramid);
  s.vio_selection_ms = distribution(vio_series_.selection);
  s.vio_update_ms = distribution(vio_series_.update);
  s.vio_map_ms = distribution(vio_series_.map);
  s.vio_patches = distribution(vio_series_.patches);
  if (pipeline_->vio() != nullptr) s.visual_map = pipeline_->vio()->map().stats();
  s.inv_exposure = inv_exposure_;
  for (const auto& r : sensors_) {
    SensorSummary sensor;
    sensor.name = r->config->name;
    sensor.role = r->role;
    sensor.file = r->file;
    sensor.counters = r->source->summary();
    sensor.scans = r->scans;
    sensor.imu_samples = r->imu_samples;
    sensor.images = r->images;
    sensor.clock = clock_summary(*r->clock);
    s.sensors.push_back(std::move(sensor));
  }
  return s;
}

}  // namespace

ReplayResult run_replay(const LivodConfig& config, const ReplayOptions& options) {
  Replay replay(config, options);
  return replay.run();
}

}  // namespace livod::daemon::replay
