#include "daemon/runtime/scheduler.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>

#include "core/error.hpp"
#include "core/image.hpp"
#include "estimator/lidars.hpp"

namespace livod::daemon::runtime {
namespace {

using Clock = std::chrono::steady_clock;

// Body-IMU samples held during one update: 8 s at 1 kHz (an update never takes that long unless
// the machine is starved; beyond it the oldest are dropped and counted).
constexpr std::size_t kHeldImuMax = 8192;

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
  return "the estimator takes one IMU, the body IMU";
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
  // The reference LiDAR first, then every other enabled LiDAR in configuration order.
  roles.lidars.push_back(roles.lidar);
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const auto& s = config.sensors[i];
    if (static_cast<int>(i) != roles.lidar && s.enabled &&
        sensor_kind(s.driver) == SensorKind::lidar) {
      roles.lidars.push_back(static_cast<int>(i));
    }
  }
  for (const int l : roles.lidars) {
    roles.T_imu_lidars.push_back(config.sensors[static_cast<std::size_t>(l)].T_body_sensor);
  }
  if (roles.lidars.size() > estimator::kMaxLidars) {
    throw Error(std::to_string(roles.lidars.size()) + " LiDARs are enabled: the estimator fuses " +
                "at most " + std::to_string(estimator::kMaxLidars));
  }
  if (config.estimator.vio.enabled) {
    for (std::size_t i = 0; i < config.sensors.size(); ++i) {
      const auto& s = config.sensors[i];
      if (s.enabled && sensor_kind(s.driver) == SensorKind::camera) {
        roles.camera = static_cast<int>(i);
        break;
      }
    }
  }
  if (roles.lidars.size() > 1 && roles.camera >= 0) {
    throw Error("a camera with estimator.vio.enabled and " + std::to_string(roles.lidars.size()) +
                " LiDARs: the visual update runs with one LiDAR only");
  }
  roles.unused_reason.resize(config.sensors.size());
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const auto n = static_cast<int>(i);
    const bool used = n == roles.body_imu || n == roles.camera ||
                      std::find(roles.lidars.begin(), roles.lidars.end(), n) != roles.lidars.end();
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
  po.T_imu_more_lidars.assign(roles_.T_imu_lidars.begin() + 1, roles_.T_imu_lidars.end());
  for (const int l : roles_.lidars) {
    po.lidar_lio.push_back(config_.sensors[static_cast<std::size_t>(l)].lio);
  }
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
  if (options_.update_thread) {
    held_.reserve(kHeldImuMax + options_.max_queued_scans * roles_.lidars.size() + 8);
    update_thread_ = std::make_unique<UpdateThread>(
        [this] { run_update(); }, options_.update_doorbell, options_.update_thread_options);
  }
  refresh_status();
}

// Stops the update thread before the pipeline it may be running goes.
Scheduler::~Scheduler() {
  update_thread_.reset();
}

void Scheduler::to_estimator(const ImuSample& m) {
  if (!update_thread_ || !update_thread_->busy()) {
    pipeline_->add_imu(m);
    return;
  }
  if (held_imu_ >= kHeldImuMax) {
    const auto it = std::find_if(held_.begin(), held_.end(), [](const auto& v) {
      return std::holds_alternative<ImuSample>(v);
    });
    held_.erase(it);
    --held_imu_;
    ++status_.held_imu_dropped;
  }
  held_.emplace_back(m);
  ++held_imu_;
}

void Scheduler::to_estimator(LidarScan scan, std::size_t lidar) {
  if (!update_thread_ || !update_thread_->busy()) {
    pipeline_->add_scan(std::move(scan), lidar);
    return;
  }
  if (held_scans_ >= std::max<std::size_t>(1, options_.max_queued_scans) * roles_.lidars.size()) {
    const auto it = std::find_if(held_.begin(), held_.end(),
                                 [](const auto& v) { return std::holds_alternative<HeldScan>(v); });
    held_.erase(it);
    --held_scans_;
    ++status_.held_scans_dropped;
  }
  held_.emplace_back(HeldScan{std::move(scan), lidar});
  ++held_scans_;
}

void Scheduler::to_estimator(ImageFrame frame) {
  if (!update_thread_ || !update_thread_->busy()) {
    pipeline_->add_image(std::move(frame));
    return;
  }
  held_.emplace_back(std::move(frame));
}

void Scheduler::release_held() {
  for (auto& v : held_) {
    if (auto* imu = std::get_if<ImuSample>(&v)) {
      pipeline_->add_imu(*imu);
    } else if (auto* held = std::get_if<HeldScan>(&v)) {
      pipeline_->add_scan(std::move(held->scan), held->lidar);
    } else {
      pipeline_->add_image(std::move(std::get<ImageFrame>(v)));
    }
  }
  held_.clear();
  held_scans_ = 0;
  held_imu_ = 0;
}

void Scheduler::refresh_status() {
  status_.initialised = pipeline_->initialised();
  status_.init_status = status_.initialised ? std::string() : pipeline_->init_status();
  status_.counters = pipeline_->counters();
  status_.queued_scans = pipeline_->queued_scans();
  status_.queued_imu = pipeline_->queued_imu();
}

const EstimatorStatus& Scheduler::estimator_status() {
  if (!update_thread_ || !update_thread_->busy()) refresh_status();
  EstimatorStatus& s = status_;
  // What waits for the running update is queued too.
  if (update_thread_ && update_thread_->busy()) {
    s.queued_scans = held_scans_;
    s.queued_imu = held_imu_;
  }
  return s;
}

void Scheduler::build_sensors(std::vector<SensorInput> inputs) {
  const auto body = static_cast<std::size_t>(roles_.body_imu);
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
    const auto slot = std::find(roles_.lidars.begin(), roles_.lidars.end(), static_cast<int>(i));
    const bool is_lidar = slot != roles_.lidars.end();
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
    r->lidar_slot = is_lidar ? static_cast<std::size_t>(slot - roles_.lidars.begin()) : 0;
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
      to_estimator(m);
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
      to_estimator(std::move(copy), self->lidar_slot);
    };
    r->sinks.on_image = [this, self](const ImageFrame& image) {
      if (!self->images_to_estimator) return;
      if (self->source->delivers_mapped_images()) {
        // A live camera: mapped by its own clock domain and decimated by its capture thread.
        ++self->images_seen;
        ++self->images;
        to_estimator(ImageFrame(image));  // shares the pixels: the source made them for it
        return;
      }
      // camera.decimation keeps every n-th frame (FAST-LIVO2 hilti_en: 4).
      const auto decimation =
          static_cast<std::uint64_t>(std::max(1, self->config->camera.decimation));
      if (self->images_seen++ % decimation != 0) return;
      ImageFrame frame = image;  // shares the pixels: the source made them for this frame
      self->clock->map_image(frame);
      ++self->images;
      to_estimator(std::move(frame));
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

void Scheduler::emit_frame(const estimator::PipelineOutput& out, std::int64_t rx_ns, double cpu_s,
                           bool estimate_sent) {
  // After emit_estimate() the predictor already starts from this state (the same one).
  if (!estimate_sent) predictor_.reset(out.t, estimator::Belief{out.x, out.P});
  sink_.on_frame(FrameOutput{out, stats_.frames, rx_ns, 1e3 * cpu_s, last_body_imu_.gyro_rad_s,
                             last_body_imu_.accel_m_s2, estimate_sent});
  ++stats_.frames;
  last_frame_t_ = out.t;
  last_frame_ms_ = out.report.timings.total_ms;
}

void Scheduler::run_update() {
  const auto t0 = Clock::now();
  const double cpu0 = process_cpu_s();
  update_out_.reset();
  pipeline_->process_taken(
      [this](const estimator::PipelineOutput& o) { update_out_.emplace(o); },
      [this](const estimator::FilterEstimate& e) {
        update_estimate_ = UpdateEstimate{e.t, e.x, e.P, e.updated, e.degeneracy};
        estimate_ready_.store(true, std::memory_order_release);
        if (options_.update_doorbell != nullptr) options_.update_doorbell->ring();
      });
  update_cpu_s_ = process_cpu_s() - cpu0;
  update_wall_s_ = seconds_since(t0);
}

void Scheduler::emit_estimate_if_ready() {
  if (estimate_emitted_ || !estimate_ready_.load(std::memory_order_acquire)) return;
  estimate_emitted_ = true;
  const UpdateEstimate& u = update_estimate_;  // not written again by this job
  const auto o0 = Clock::now();
  predictor_.reset(u.t, estimator::Belief{u.x, u.P});
  const estimator::FilterEstimate e{u.t, u.x, u.P, u.updated, u.degeneracy};
  sink_.on_estimate(EstimateOutput{e, stats_.frames, update_rx_ns_, last_body_imu_.gyro_rad_s,
                                   last_body_imu_.accel_m_s2});
  stats_.output_s += seconds_since(o0);
}

void Scheduler::finish_update() {
  emit_estimate_if_ready();
  release_held();
  stats_.estimator_s += update_wall_s_;
  if (update_out_) {
    const auto o0 = Clock::now();
    emit_frame(*update_out_, update_rx_ns_, update_cpu_s_, estimate_emitted_);
    stats_.output_s += seconds_since(o0);
  }
}

std::size_t Scheduler::process_on_update_thread() {
  std::size_t done = 0;
  if (update_thread_->busy()) {
    if (!update_thread_->done()) {
      // The pose goes out as soon as the update ended; the map insertion is still running.
      emit_estimate_if_ready();
      return 0;
    }
    update_thread_->collect();
    finish_update();
    ++done;
  }
  if (pipeline_->take_group()) {
    update_rx_ns_ = current_rx_ns_;
    estimate_ready_.store(false, std::memory_order_relaxed);  // start() publishes it
    estimate_emitted_ = false;
    update_thread_->start();
  } else {
    refresh_status();
  }
  return done;
}

std::size_t Scheduler::process(std::size_t max_groups) {
  if (update_thread_ && max_groups != SIZE_MAX) return process_on_update_thread();
  if (update_thread_) {
    // Draining at the end: the running update first, then everything on this thread.
    if (update_thread_->busy()) {
      update_thread_->wait_and_collect();
      finish_update();
    }
  }
  std::size_t done = 0;
  for (; done < max_groups; ++done) {
    const auto t0 = Clock::now();
    const double cpu0 = process_cpu_s();
    double output_s = 0.0;
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
      emit_frame(*out, current_rx_ns_, frame_cpu_s);
      output_s = seconds_since(o0);
    }
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
