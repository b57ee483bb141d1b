#include "daemon/runtime/publisher.hpp"

#include <fmt/core.h>
#include <spdlog/spdlog.h>

#include <fstream>

#include "core/error.hpp"
#include "daemon/runtime/thread_scheduling.hpp"
#include "io/output_file.hpp"

namespace livod::daemon::runtime {
namespace {

constexpr Nanoseconds kIdleWait{100'000'000};  // bounds how late a stop request is seen

double ms_between(std::int64_t from_ns, std::int64_t to_ns) {
  return static_cast<double>(to_ns - from_ns) * 1e-6;
}

std::string format_report(const PublisherStats& s, std::uint64_t bus_failures) {
  const auto line = [](const char* what, const LatencyHistogram& h) {
    return fmt::format(
        "  {:<28} count {:>8}  mean {:8.3f}  p50 {:8.3f}  p99 {:8.3f}  max {:8.3f}\n", what,
        h.count(), h.mean(), h.percentile(0.5), h.percentile(0.99), h.max());
  };
  std::string out = "livod run: timing report (ms; percentiles to the histogram's bin edge)\n";
  out += line("frame time (wall)", s.frame_ms);
  out += line("frame time (CPU, all threads)", s.frame_cpu_ms);
  out += line("pose latency", s.pose_latency_ms);
  out += line("IMU-rate pose latency", s.imu_latency_ms);
  out += fmt::format("  poses {}, IMU-rate poses {}, health records {}, stale-pose repeats {}\n",
                     s.poses, s.imu_poses, s.health, s.stale_poses);
  out += fmt::format("  messages that could not be sent: {}\n", bus_failures);
  out +=
      "  pose latency: from the kernel receive time of the packet that completed the scan to\n"
      "  the pose leaving the process; IMU: from the IMU packet to its propagated pose.\n";
  return out;
}

}  // namespace

Publisher::Publisher(PublisherChannels& channels, MessageBus* bus, PublisherOptions options)
    : channels_(channels),
      bus_(bus),
      options_(std::move(options)),
      threads_(options_.stuck_after),
      map_saves_(options_.map_saves, channels_.doorbell) {
  if (!options_.trajectory.empty()) trajectory_.emplace(options_.trajectory);
  if (!options_.map_pcd.empty() || options_.map_saves.enabled) {
    map_.emplace(options_.map_cell_m, options_.map_max_points);
    // Saves read the map while it grows (map_save_service.hpp): its points must never move.
    if (options_.map_saves.enabled) map_->reserve_budget();
  }
}

Publisher::~Publisher() {
  if (!stopped_) stop();
}

void Publisher::watch(std::string name, std::function<std::uint64_t()> beats) {
  threads_.add(std::move(name), std::move(beats));
}

void Publisher::start() {
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
}

void Publisher::run(const std::stop_token& stop) {
  if (const auto refused =
          apply_thread_scheduling("livod-publish", options_.priority, options_.cpu);
      !refused.empty()) {
    spdlog::warn("publisher thread: {}", refused);
  }
  while (!stop.stop_requested()) {
    heartbeat_.beat();
    const std::uint32_t token = channels_.doorbell.prepare();
    const bool any = drain();
    map_saves_.turn(map(), bus_);
    if (!any) channels_.doorbell.wait(token, kIdleWait);
  }
}

bool Publisher::publish_imu_poses() {
  bool any = false;
  while (ImuPoseRecord* p = channels_.imu_poses.next()) {
    any = true;
    if (bus_ != nullptr) bus_->publish_pose(p->pose);
    const double ms = ms_between(p->rx_ns, host_now().ns);
    stats_.imu_latency_ms.add(ms);
    window_imu_latency_.add(ms);
    ++stats_.imu_poses;
    channels_.imu_poses.release(p);
  }
  return any;
}

bool Publisher::publish_estimates() {
  bool any = false;
  while (ImuPoseRecord* p = channels_.estimates.next()) {
    any = true;
    if (bus_ != nullptr) {
      bus_->publish_pose(p->pose);
      const double ms = ms_between(p->rx_ns, host_now().ns);
      stats_.pose_latency_ms.add(ms);
      window_pose_latency_.add(ms);
    }
    channels_.estimates.release(p);
  }
  return any;
}

bool Publisher::drain() {
  // Filter poses first: IMU-rate poses queued meanwhile were propagated from them.
  bool any = publish_estimates();
  any = publish_imu_poses() || any;
  while (FrameRecord* f = channels_.frames.next()) {
    any = true;
    on_frame(*f);
    channels_.frames.release(f);
  }
  while (HealthRecord* h = channels_.health.next()) {
    any = true;
    on_health(*h);
    channels_.health.release(h);
  }
  return any;
}

void Publisher::on_frame(FrameRecord& f) {
  if (f.pose.status == PoseStatus::kSensorStale) {
    if (bus_ != nullptr) bus_->publish_pose(f.pose);
    ++stats_.stale_poses;
    return;
  }
  if (bus_ != nullptr) {
    if (!f.pose_published) {
      bus_->publish_pose(f.pose);
      const double ms = ms_between(f.rx_ns, host_now().ns);
      stats_.pose_latency_ms.add(ms);
      window_pose_latency_.add(ms);
    }
    if (options_.publish_cloud) {
      cloud_.t = f.pose.t;
      cloud_.points.resize(f.xyz_world.size() / 3);
      for (std::size_t i = 0; i < cloud_.points.size(); ++i) {
        cloud_.points[i] = {f.xyz_world[3 * i], f.xyz_world[3 * i + 1], f.xyz_world[3 * i + 2],
                            0.0F};
      }
      bus_->publish_cloud(cloud_);
    }
  }
  ++stats_.poses;
  stats_.frame_ms.add(f.report.timings.total_ms);
  stats_.frame_cpu_ms.add(f.cpu_ms);
  if (trajectory_) {
    try {
      trajectory_->write(f.pose.t, f.pose.R_world_body, f.pose.p_world_body);
    } catch (const std::exception& e) {
      errors_.push_back(e.what());
      trajectory_.reset();
    }
  }
  if (map_) {
    // Up to 131 k points per frame, about 60 ns each: IMU-rate poses that arrive meanwhile go out
    // between slices of 512 points (~30 us; 8192-point slices held them ~0.5 ms, the IMU-rate
    // pose's p99 under load). Looking at the rings costs two atomic loads.
    constexpr std::size_t kSlice = 3 * 512;
    for (std::size_t i = 0; i + 2 < f.xyz_world.size(); i += 3) {
      map_->add(Eigen::Vector3d(f.xyz_world[i], f.xyz_world[i + 1], f.xyz_world[i + 2]));
      if (i % kSlice == 0) {
        publish_estimates();
        publish_imu_poses();
      }
    }
  }
}

void Publisher::on_health(HealthRecord& h) {
  const auto beats = threads_.update(h.host_time);
  h.threads.resize(beats.size());
  for (std::size_t i = 0; i < beats.size(); ++i) {
    auto& t = h.threads[i];
    t.name = beats[i].name;
    t.state = beats[i].stuck ? publish::ThreadState::kStuck : publish::ThreadState::kAlive;
    t.heartbeat_age_ns = beats[i].age.count();
    t.heartbeats = beats[i].beats;
    t.stuck_after_ns = options_.stuck_after.count();
  }
  auto& e = h.estimator;
  e.pose_latency_p50_ms = window_pose_latency_.percentile(0.5);
  e.pose_latency_p99_ms = window_pose_latency_.percentile(0.99);
  e.imu_pose_latency_p50_ms = window_imu_latency_.percentile(0.5);
  e.imu_pose_latency_p99_ms = window_imu_latency_.percentile(0.99);
  window_pose_latency_.clear();
  window_imu_latency_.clear();
  // CLOCK_REALTIME follows NTP: the offset to the mapped (monotonic) timeline is re-measured.
  realtime_.refresh();
  h.unix_time_ns = h.host_time.ns + realtime_.offset_ns();
  if (bus_ != nullptr) {
    bus_->set_time_base(publish::TimeBase{realtime_.offset_ns()});
    h.channels = bus_->channel_counters();
    bus_->publish_health(h);
  }
  ++stats_.health;
  log_health(h);
  if (options_.on_health) options_.on_health(h);
}

void Publisher::log_health(const HealthRecord& h) {
  std::string states;
  std::string line;
  bool trouble = false;  // something an operator must look at: logged as a warning
  for (const auto& s : h.sensors) {
    const char* state = s.state == publish::SensorState::kStale       ? "STALE"
                        : s.state == publish::SensorState::kStreaming ? "STREAMING"
                                                                      : "WAITING";
    states += s.name + "=" + state + " ";
    trouble = trouble || s.state == publish::SensorState::kStale;
    line += fmt::format(
        "{} {} {:.0f} pkt/s (kernel drops {}, ring overruns {}, gaps {}, decode errors {}{}{}); ",
        s.name, state, s.packets_per_s, s.kernel_drops, s.ring_overruns, s.sequence_gaps,
        s.decode_errors, s.device_state.empty() ? "" : ", device " + s.device_state,
        s.last_error.empty() ? "" : ", " + s.last_error);
  }
  const auto& e = h.estimator;
  states += to_string(e.status);
  line += fmt::format(
      "estimator {} frames {} p50 {:.1f} ms p99 {:.1f} ms, dropped scans {}, latency p50 {:.2f} "
      "ms p99 {:.2f} ms",
      to_string(e.status), e.scans_processed, e.frame_time_p50_ms, e.frame_time_p99_ms,
      e.scans_dropped_queue, e.pose_latency_p50_ms, e.pose_latency_p99_ms);
  if (e.status == PoseStatus::kInitialising) line += " (" + e.init_status + ")";
  for (const auto& t : h.threads) {
    const bool stuck = t.state == publish::ThreadState::kStuck;
    if (stuck) {
      line += fmt::format("; thread {} stuck for {:.1f} s", t.name,
                          static_cast<double>(t.heartbeat_age_ns) * 1e-9);
    }
    trouble = trouble || stuck;
  }
  trouble = trouble || e.status == PoseStatus::kSensorStale;
  const HostTime now = h.host_time;
  const bool changed = states != last_states_;
  const bool due = !last_log_ || now - *last_log_ >= options_.log_period;
  if (changed || due) {
    if (changed && trouble) {
      spdlog::warn("health: {}", line);
    } else {
      spdlog::info("health: {}", line);
    }
    last_states_ = std::move(states);
    last_log_ = now;
  }
}

std::vector<std::string> Publisher::stop() {
  if (stopped_) return errors_;
  stopped_ = true;
  if (thread_.joinable()) {
    thread_.request_stop();
    channels_.doorbell.ring();
    thread_.join();
  }
  drain();  // what the scheduler published last (it has stopped: this thread owns the channels)
  map_saves_.finish(map(), bus_);
  stats_.map_saves = map_saves_.stats();
  if (trajectory_) {
    try {
      trajectory_->close();
    } catch (const std::exception& e) {
      errors_.push_back(e.what());
    }
  }
  if (map_ && !options_.map_pcd.empty()) {  // the map also exists for map saves alone
    try {
      replay::write_pcd(options_.map_pcd, map_->xyz());
    } catch (const std::exception& e) {
      errors_.push_back(e.what());
    }
  }
  if (!options_.timing_report.empty()) {
    try {
      io::write_file(options_.timing_report,
                     format_report(stats_, bus_ != nullptr ? bus_->failures() : 0));
    } catch (const std::exception& e) {
      errors_.push_back(e.what());
    }
  }
  return errors_;
}

}  // namespace livod::daemon::runtime
