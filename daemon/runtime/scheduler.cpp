#include "daemon/runtime/scheduler.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>

#include "core/error.hpp"
#include "core/image.hpp"

namespace livod::daemon::runtime {
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

std::string unused_reason(const LivodConfig& config, const SensorConfig& s) {
  if (!s.enabled) return "disabled";
  if (sensor_kind(s.driver) == SensorKind::camera) {
    return config.estimator.vio.enabled
               ? "the visual update uses one camera, the first enabled one"
               : "estimator.vio.enabled is false (LiDAR-inertial odometry only)";
  }
  return "the estimator takes the body IMU and one LiDAR";
}

}  // namespace

SensorRoles assign_roles(const LivodConfig& config) {
  SensorRoles roles;
  if (config.body_sensor_index < 0) {
    throw Error("the configuration names no body IMU (body_frame): the estimator needs one");
  }
  roles.body_imu = config.body_sensor_index;
  if (config.body_is_internal_imu) {
    roles.lidar = config.body_sensor_index;
  } else {
    for (std::size_t i = 0; i < config.sensors.size(); ++i) {
      const auto& s = config.sensors[i];
      if (s.enabled && sensor_kind(s.driver) == SensorKind::lidar) {
        roles.lidar = static_cast<int>(i);
        break;
      }
    }
  }
  if (roles.lidar < 0)
    throw Error("the configuration has no enabled LiDAR: the estimator needs one");
  roles.T_imu_lidar = config.sensors[static_cast<std::size_t>(roles.lidar)].T_body_sensor;
  if (config.estimator.vio.enabled) {
    for (std::size_t i = 0; i < config.sensors.size(); ++i) {
      const auto& s = config.sensors[i];
      if (s.enabled && sensor_kind(s.driver) == SensorKind::camera) {
        roles.camera = static_cast<int>(i);
        break;
      }
    }
  }
  roles.unused_reason.resize(config.sensors.size());
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const auto n = static_cast<int>(i);
    const bool used = n == roles.body_imu || n == roles.lidar || n == roles.camera;
    if (!used) roles.unused_reason[i] = unused_reason(config, config.sensors[i]);
  }
  return roles;
}

estimator::vio::VioCamera vio_camera(const SensorConfig& sensor) {
  const CameraConfig& c = sensor.camera;
  estimator::vio::VioCamera cam;
  auto& k = cam.intrinsics;
  k.model = c.model == CameraModel::equidistant ? CameraIntrinsics::Model::kEquidistant
                                                : CameraIntrinsics::Model::kPinholeRadtan;
  k.width = c.width;
  k.height = c.height;
  k.fx = c.intrinsics[0];
  k.fy = c.intrinsics[1];
  k.cx = c.intrinsics[2];
  k.cy = c.intrinsics[3];
  for (std::size_t i = 0; i < 4 && i < c.distortion.size(); ++i) k.distortion[i] = c.distortion[i];
  if (c.distortion.size() == 5) k.radtan_k3 = c.distortion[4];
  cam.scale = c.scale;
  cam.T_imu_cam = sensor.T_body_sensor;
  return cam;
}

Scheduler::Scheduler(const LivodConfig& config, std::vector<SensorInput> inputs,
                     estimator::TaskRunner* runner, OutputSink& sink, SchedulerOptions options)
    : config_(config),
      options_(options),
      sink_(sink),
      roles_(assign_roles(config)),
      predictor_(config.estimator.imu, config.estimator.vio.inv_expo_cov) {
  estimator::PipelineOptions po;
  po.params = config_.estimator;
  po.T_imu_lidar = roles_.T_imu_lidar;
  po.runner = runner;
  po.max_queued_scans = options_.max_queued_scans;
  if (roles_.camera >= 0) {
    po.camera = vio_camera(config_.sensors[static_cast<std::size_t>(roles_.camera)]);
    po.colorize = options_.vio_colorize;
    po.vio_debug = options_.vio_debug;
  }
  pipeline_ = std::make_unique<estimator::LioPipeline>(po);
  want_imu_poses_ = sink_.wants_imu_poses();
  build_sensors(std::move(inputs));
}

Scheduler::~Scheduler() = default;

void Scheduler::build_sensors(std::vector<SensorInput> inputs) {
  const auto body = static_cast<std::size_t>(roles_.body_imu);
  const auto lidar = static_cast<std::size_t>(roles_.lidar);
  const int camera = roles_.camera;
  std::vector<std::optional<SensorInput>> by_index(config_.sensors.size());
  for (auto& in : inputs) {
    if (in.sensor_index >= config_.sensors.size()) {
      throw Error("internal: a source for sensor index " + std::to_string(in.sensor_index));
    }
    by_index[in.sensor_index] = std::move(in);
  }
  for (std::size_t i = 0; i < config_.sensors.size(); ++i) {
    const SensorConfig& s = config_.sensors[i];
    const bool is_body = i == body;
    const bool is_lidar = i == lidar;
    const bool is_camera = static_cast<int>(i) == camera;
    if (!is_body && !is_lidar && !is_camera) continue;
    if (!by_index[i] || !by_index[i]->source) {
      throw Error("sensor '" + s.name + "' has no source");
    }
    auto r = std::make_unique<ScheduledSensor>();
    r->config = &s;
    r->index = i;
    r->origin = by_index[i]->origin;
    r->source = std::move(by_index[i]->source);
    r->scans_to_estimator = is_lidar;
    r->imu_to_estimator = is_body;
    r->images_to_estimator = is_camera;
    r->imu_usable = sensor_kind(s.driver) == SensorKind::imu || s.imu.enabled;
    r->role = is_camera             ? "camera"
              : is_lidar && is_body ? "lidar + body imu"
              : is_lidar            ? "lidar"
                                    : "body imu";
    r->clock = std::make_unique<SensorClockMapper>(s);
    ScheduledSensor* self = r.get();
    r->sinks.on_imu = [this, self](const ImuSample& sample) {
      if (!self->imu_usable) return;
      ImuSample m = sample;
      self->clock->map_imu(m);
      ++self->imu_samples;
      if (!self->imu_to_estimator) return;
      last_body_imu_ = m;
      pipeline_->add_imu(m);
      if (!want_imu_poses_) return;
      if (const auto pose = predictor_.add(m)) {
        const auto t0 = Clock::now();
        sink_.on_imu_pose(ImuPoseOutput{*pose, m, current_rx_ns_});
        ++stats_.imu_poses;
        stats_.output_s += seconds_since(t0);
      }
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

bool Scheduler::step() {
  // The earliest ready event; ties go to the sensor listed first.
  ScheduledSensor* next = nullptr;
  std::int64_t next_ns = 0;
  for (auto& s : sensors_) {
    const auto t = s->source->peek_time();
    if (t && (next == nullptr || *t < next_ns)) {
      next = s.get();
      next_ns = *t;
    }
  }
  if (next != nullptr && options_.max_recording.count() > 0 && stats_.first_event_ns &&
      next_ns - *stats_.first_event_ns > options_.max_recording.count()) {
    cut_ = true;
  }
  if (next == nullptr || cut_) {
    // Nothing new, but frames may still be due (the daemon runs one group per step).
    return process(options_.max_groups_per_step) > 0;
  }
  if (!stats_.first_event_ns) stats_.first_event_ns = next_ns;
  stats_.last_event_ns = std::max(stats_.last_event_ns, next_ns);
  ++stats_.events;

  const auto t0 = Clock::now();
  current_rx_ns_ = next_ns;
  next->source->deliver(next->sinks);
  next->last_event = HostTime(next_ns);
  next->source->supervise(HostTime(next_ns));
  stats_.decode_s += seconds_since(t0);
  process(options_.max_groups_per_step);
  if (const auto f = next->source->fraction_done()) fraction_ = f;
  return true;
}

std::size_t Scheduler::process(std::size_t max_groups) {
  std::size_t done = 0;
  for (; done < max_groups; ++done) {
    const auto t0 = Clock::now();
    const double cpu0 = process_cpu_s();
    double output_s = 0.0;
    double output_cpu_s = 0.0;
    bool produced = false;
    // The pipeline's output is copied out of the callback's scope only as far as the sink needs;
    // its CPU time is known once the pipeline call returns.
    std::optional<estimator::PipelineOutput> out;
    const std::size_t ran = pipeline_->process(
        [&](const estimator::PipelineOutput& o) {
          out.emplace(o);
          produced = true;
        },
        1);
    if (ran == 0) break;
    const double frame_cpu_s = process_cpu_s() - cpu0;
    const double frame_wall_s = seconds_since(t0);
    if (produced) {
      const auto o0 = Clock::now();
      const double ocpu0 = process_cpu_s();
      predictor_.reset(out->t, estimator::Belief{out->x, out->P});
      sink_.on_frame(FrameOutput{*out, stats_.frames, current_rx_ns_, 1e3 * frame_cpu_s,
                                 last_body_imu_.gyro_rad_s, last_body_imu_.accel_m_s2});
      ++stats_.frames;
      last_frame_t_ = out->t;
      last_frame_ms_ = out->report.timings.total_ms;
      output_s = seconds_since(o0);
      output_cpu_s = process_cpu_s() - ocpu0;
    }
    (void)output_cpu_s;
    stats_.estimator_s += frame_wall_s;
    stats_.output_s += output_s;
  }
  return done;
}

bool Scheduler::exhausted() {
  if (cut_) return true;
  for (auto& s : sensors_) {
    if (!s->source->exhausted()) return false;
  }
  return true;
}

void Scheduler::stop_sources() {
  for (auto& s : sensors_) s->source->stop();
}

void Scheduler::process_all() {
  process(SIZE_MAX);
}

void Scheduler::finish() {
  const auto t0 = Clock::now();
  for (auto& s : sensors_) s->source->finish(s->sinks);
  stats_.decode_s += seconds_since(t0);
  process(SIZE_MAX);
}

}  // namespace livod::daemon::runtime
