#include "daemon/runtime/daemon.hpp"

#include <signal.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <thread>

#include "core/error.hpp"
#include "daemon/record/record_session.hpp"
#include "daemon/replay/input_assignment.hpp"
#include "daemon/replay/sources.hpp"
#include "daemon/runtime/live_camera_source.hpp"
#include "daemon/runtime/live_imu_source.hpp"
#include "daemon/runtime/live_lidar_source.hpp"
#include "daemon/runtime/live_outputs.hpp"
#include "daemon/runtime/paced_sources.hpp"
#include "daemon/runtime/scheduler.hpp"
#include "daemon/runtime/service_notifier.hpp"
#include "daemon/runtime/signals.hpp"
#include "daemon/runtime/thread_scheduling.hpp"
#include "daemon/worker_pool.hpp"
#include "drivers/capture/doorbell.hpp"

namespace livod::daemon::runtime {
namespace {

// How long the scheduler may spend draining the rings once capture stopped: keeps a stop within
// the 2 s systemd and operators expect, with the queued scans still processed.
constexpr Nanoseconds kDrainBudget{1'000'000'000};
// Longest sleep of the scheduler when nothing is queued (a live source rings its doorbell).
constexpr Nanoseconds kIdleWait{100'000'000};
// Recordings released by the scheduler (no doorbell) are checked this often.
constexpr Nanoseconds kPacedPoll{500'000};
// Registered points per frame record when map.pcd is written by the daemon.
constexpr std::size_t kMapPointsPerFrame = 131'072;

struct OpenedSources {
  std::vector<SensorInput> inputs;
  std::vector<std::pair<std::string, std::uint16_t>> ports;
  bool time_released = false;  // some source has no doorbell: poll
};

// "v4l2 /dev/video0", "aravis Basler-123", "can_imu can0", "serial_imu /dev/ttyUSB0".
std::string device_origin(const SensorConfig& s, const DeviceSourceConfig& d) {
  std::string what = d.interface.empty() ? d.path : d.interface;
  if (s.driver == Driver::aravis) what = d.camera_id.empty() ? "(first camera found)" : d.camera_id;
  return std::string(enum_name(s.driver)) + " " + what;
}

OpenedSources open_live(const LivodConfig& config, const SensorRoles& roles,
                        const DaemonOptions& options, drivers::capture::Doorbell& wake,
                        record::Recorder* recorder) {
  OpenedSources out;
  LiveOptions lo;
  if (config.realtime.capture_priority > 0) lo.capture_priority = config.realtime.capture_priority;
  if (config.realtime.capture_cpu >= 0) lo.capture_cpu = config.realtime.capture_cpu;
  lo.stale_after = from_seconds(config.health.stale_after_s);
  lo.ephemeral_ports = options.ephemeral_ports;
  lo.doorbell = &wake;
  lo.recorder = recorder;
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    if (!roles.unused_reason[i].empty()) continue;
    const SensorConfig& s = config.sensors[i];
    const std::string what = "sensor '" + s.name + "' (" + std::string(enum_name(s.driver)) + ")";
    if (std::holds_alternative<ReplaySourceConfig>(s.source)) {
      throw Error(what + " replays a recording: `livod run` reads live sensors (replay it with " +
                  "`livod replay --realtime`)");
    }
    if (const auto* device = std::get_if<DeviceSourceConfig>(&s.source)) {
      // Cameras and external IMUs (live_camera_source.hpp, live_imu_source.hpp): a device that
      // is not there yet is waited for, not fatal.
      SensorInput in;
      in.sensor_index = i;
      in.origin = device_origin(s, *device);
      in.source = sensor_kind(s.driver) == SensorKind::camera
                      ? open_live_camera(s, config, &wake, recorder)
                      : open_live_imu(s, config, &wake, recorder);
      out.inputs.push_back(std::move(in));
      continue;
    }
    if (!is_packet_lidar(s.driver) || !std::holds_alternative<UdpSourceConfig>(s.source)) {
      throw Error(what + ": live operation is implemented for packet LiDARs over UDP (ouster, " +
                  "velodyne, livox_sdk1, livox_sdk2, hesai), cameras (v4l2, aravis) and IMUs " +
                  "(can_imu, serial_imu) with a device source");
    }
    auto source = open_live_lidar(s, lo);
    for (const auto& [stream, port] : source->local_ports()) {
      out.ports.emplace_back(s.name + "." + stream, port);
    }
    const auto* udp = std::get_if<UdpSourceConfig>(&s.source);
    SensorInput in;
    in.sensor_index = i;
    in.origin = "udp " + udp->bind_address + ":" + std::to_string(udp->ports.lidar);
    in.source = std::move(source);
    out.inputs.push_back(std::move(in));
  }
  return out;
}

OpenedSources open_paced(const LivodConfig& config, const SensorRoles& roles,
                         const DaemonOptions& options, drivers::capture::Doorbell& wake) {
  const auto recordings = replay::assign_recordings(config, options.inputs);
  struct Pending {
    std::size_t index;
    std::unique_ptr<MeasurementSource> recorded;
  };
  std::vector<Pending> pending;
  std::optional<std::int64_t> t0;
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    if (!roles.unused_reason[i].empty()) continue;
    const SensorConfig& s = config.sensors[i];
    const auto& r = recordings[i];
    if (!r) {
      throw Error("sensor '" + s.name + "' has no recording to replay: its source is live; give " +
                  "one on the command line (" + s.name + "=PATH)");
    }
    auto recorded = replay::make_source(s, r->replay, r->ports);
    if (const auto t = recorded->peek_time()) t0 = t0 ? std::min(*t0, *t) : *t;
    pending.push_back({i, std::move(recorded)});
  }
  PaceSchedule schedule;
  schedule.t0_record_ns = t0.value_or(0);
  schedule.start = host_now();
  schedule.doorbell = &wake;
  OpenedSources out;
  for (auto& p : pending) {
    const SensorConfig& s = config.sensors[p.index];
    const auto& r = *recordings[p.index];
    SensorInput in;
    in.sensor_index = p.index;
    in.origin = r.replay.file.string() + (r.replay.topic.empty() ? "" : " " + r.replay.topic);
    if (r.replay.format == ReplayFormat::pcap) {
      // The live path: a pacer thread into packet rings, drained by a StreamConsumer.
      p.recorded.reset();
      in.source = open_paced_pcap(s, r.replay.file, r.ports, schedule);
    } else {
      in.source = pace_recording(std::move(p.recorded), schedule);
      out.time_released = true;
    }
    out.inputs.push_back(std::move(in));
  }
  return out;
}

}  // namespace

DaemonResult run_daemon(const LivodConfig& config, const DaemonOptions& options) {
  // spdlog builds its registry on first use, and the prebuilt libspdlog checks that static's guard
  // without telling ThreadSanitizer; built here, before any thread starts, every thread that logs
  // is ordered after it by thread creation.
  spdlog::default_logger_raw();
  DaemonResult result;
  const SensorRoles roles = assign_roles(config);
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    if (!roles.unused_reason[i].empty()) {
      spdlog::info("sensor '{}' is not used: {}", config.sensors[i].name, roles.unused_reason[i]);
    }
  }
  const BlockedSignals signals;  // before any thread starts: they all inherit the mask
  if (config.realtime.lock_memory) {
    if (const auto refused = lock_memory(); !refused.empty()) spdlog::warn("{}", refused);
  }
  // Held until the daemon returns: the threads' hand-overs then never wait for a halted CPU.
  CpuLatencyRequest cpu_latency;
  if (config.realtime.cpu_dma_latency_us >= 0) {
    cpu_latency = CpuLatencyRequest(config.realtime.cpu_dma_latency_us, options.cpu_latency_device);
    if (cpu_latency.active()) {
      spdlog::info("CPU wake-up latency held at <= {} us (realtime.cpu_dma_latency_us)",
                   config.realtime.cpu_dma_latency_us);
    } else {
      spdlog::warn("{}", cpu_latency.refusal());
    }
  }

  // Recording beside the estimator (outputs.record, run --record): the same capture threads also
  // feed the recorder's taps; it writes on its own IO thread (daemon/record/).
  const std::filesystem::path record_dir =
      options.record_dir.empty() ? config.outputs.record : options.record_dir;
  std::optional<record::RecordSession> recording;
  if (!record_dir.empty() && options.paced_replay) {
    spdlog::warn("outputs.record: not recording: replay --realtime reads recordings already");
  } else if (!record_dir.empty()) {
    recording.emplace(config, record::new_recording_folder(record_dir));
  }

  drivers::capture::Doorbell wake;  // capture/pacer threads -> scheduler
  OpenedSources opened =
      options.paced_replay
          ? open_paced(config, roles, options, wake)
          : open_live(config, roles, options, wake, recording ? &recording->recorder() : nullptr);
  if (recording) {
    // open_live() opens only the sensors the estimator uses: the others are not recorded either.
    for (std::size_t i = 0; i < config.sensors.size(); ++i) {
      if (!roles.unused_reason[i].empty() && record::is_recorded(config.sensors[i])) {
        recording->leave_out(config.sensors[i].name,
                             "`livod run` does not open it (" + roles.unused_reason[i] + ")");
      }
    }
  }

  std::vector<SourceThread> source_threads;
  for (const auto& in : opened.inputs) {
    for (auto& t : in.source->threads()) source_threads.push_back(std::move(t));
  }

  const auto& lcm = config.outputs.lcm;
  PublisherOptions po;
  if (options.out_dir) {
    std::filesystem::create_directories(*options.out_dir);
    po.trajectory = *options.out_dir / "trajectory.txt";
    po.map_pcd = *options.out_dir / "map.pcd";
    po.timing_report = *options.out_dir / "timing.txt";
  } else {
    po.trajectory = config.outputs.trajectory;
    po.map_pcd = config.outputs.map_pcd;
    po.timing_report = config.outputs.timing_report;
  }
  // Map saves on request: the folder per map_save_service.hpp (configured, OUTDIR/maps,
  // $STATE_DIRECTORY/maps, ./maps).
  const auto& saves = config.outputs.map_saves;
  po.map_saves.enabled = saves.enabled;
  po.map_saves.at_stop = saves.at_stop;
  po.map_saves.saver =
      map_saver_options(saves.directory, options.out_dir.value_or(std::filesystem::path()),
                        std::getenv("STATE_DIRECTORY"), saves.overwrite);
  po.map_saves.saver.before_write = options.map_save_hook;
  po.map_cell_m = options.map_cell_m;
  po.map_max_points = options.map_max_points;
  po.publish_cloud = options.bus != nullptr && lcm.publish_cloud;
  if (config.realtime.scheduler_priority > 0) {
    po.priority = std::max(1, config.realtime.scheduler_priority - 1);
  }
  // systemd: a no-op unless asked for and NOTIFY_SOCKET is set.
  ServiceNotifier notifier =
      options.notify_systemd
          ? ServiceNotifier::from_environment()
          : ServiceNotifier([](const std::string&) { return true; }, std::nullopt);
  if (options.notify_systemd) {
    // The publisher thread formats the STATUS= line at each health record; the main thread sends
    // it (set_status only stores it under a lock).
    po.on_health = [&notifier,
                    previous = std::optional<HealthRecord>()](const HealthRecord& h) mutable {
      notifier.set_status(service_status_line(h, previous ? &*previous : nullptr));
      previous = h;
    };
  }
  PublisherChannels::Sizes sizes;
  if (po.publish_cloud) sizes.cloud_points = static_cast<std::size_t>(lcm.cloud_max_points);
  if (!po.map_pcd.empty() || po.map_saves.enabled)
    sizes.cloud_points = std::max(sizes.cloud_points, kMapPointsPerFrame);
  PublisherChannels channels(sizes);
  LiveOutputsOptions lo;
  lo.imu_poses = options.bus != nullptr && lcm.publish_imu_rate;
  lo.stale_after = from_seconds(config.health.stale_after_s);
  lo.version = LIVOD_VERSION;
  LiveOutputs outputs(channels, lo);

  const int threads = options.threads >= 0 ? options.threads : config.estimator.threads;
  // The estimator's workers are part of the update: under SCHED_FIFO they take the update
  // thread's priority (two below the scheduler), else a parallel loop waits for its slowest part
  // behind every other process on the machine.
  std::optional<int> worker_priority;
  if (config.realtime.scheduler_priority > 0) {
    worker_priority = std::max(1, config.realtime.scheduler_priority - 2);
  }
  WorkerPool pool(threads > 0 ? threads : WorkerPool::hardware_threads(), [worker_priority] {
    if (const auto refused = apply_thread_scheduling("livod-worker", worker_priority, {});
        !refused.empty()) {
      spdlog::warn("estimator worker thread: {}", refused);
    }
  });
  std::optional<int> priority;
  if (config.realtime.scheduler_priority > 0) priority = config.realtime.scheduler_priority;
  std::optional<int> cpu;
  if (config.realtime.scheduler_cpu >= 0) cpu = config.realtime.scheduler_cpu;
  SchedulerOptions so;
  so.max_groups_per_step = 1;
  so.max_queued_scans = options.max_queued_scans;
  // The filter update runs on its own thread so that the scheduler thread keeps publishing
  // IMU-rate poses during a scan update (update_thread.hpp). Under SCHED_FIFO the IMU-rate pose's
  // path (capture, scheduler, then publisher one below it) preempts the update thread (two
  // below the scheduler) whenever an IMU packet arrives.
  so.update_thread = true;
  so.update_doorbell = &wake;
  if (priority) so.update_thread_options.priority = std::max(1, *priority - 2);
  so.update_thread_options.cpu = cpu;
  Scheduler scheduler(config, std::move(opened.inputs), &pool, outputs, so);

  Publisher publisher(channels, options.bus, po);
  Heartbeat scheduler_beat;
  publisher.watch("scheduler", [&scheduler_beat] { return scheduler_beat.beats(); });
  publisher.watch("publisher", [&publisher] { return publisher.heartbeat().beats(); });
  for (auto& t : source_threads) publisher.watch(t.name, t.beats);
  notifier.watch("scheduler", [&scheduler_beat] { return scheduler_beat.beats(); });
  publisher.watch("update", [&scheduler] { return scheduler.update_beats(); });
  notifier.watch("update", [&scheduler] { return scheduler.update_beats(); });
  notifier.watch("publisher", [&publisher] { return publisher.heartbeat().beats(); });
  for (auto& t : source_threads) notifier.watch(t.name, t.beats);
  if (recording) {
    // In health, not in the watchdog: a slow disk loses recorded data (counted), it must not get
    // the odometry restarted.
    record::Recorder* recorder = &recording->recorder();
    publisher.watch("recorder", [recorder] { return recorder->heartbeat().beats(); });
    recording->start();
    spdlog::info("recording the live sensors into {}", recording->dir().string());
  }
  publisher.start();

  const Nanoseconds health_period = from_seconds(config.health.period_s);
  const Nanoseconds idle = opened.time_released ? kPacedPoll : kIdleWait;
  std::atomic<bool> scheduler_done{false};
  std::string scheduler_error;
  std::string end_reason;

  std::jthread scheduler_thread([&](const std::stop_token& stop) {
    if (const auto refused = apply_thread_scheduling("livod-sched", priority, cpu);
        !refused.empty()) {
      spdlog::warn("scheduler thread: {}", refused);
    }
    try {
      HostTime next_health = host_now() + health_period;
      while (!stop.stop_requested()) {
        if (options.scheduler_turn_hook) options.scheduler_turn_hook();
        scheduler_beat.beat();
        const std::uint32_t token = wake.prepare();
        const bool did = scheduler.step();
        const HostTime now = host_now();
        if (now >= next_health) {
          outputs.publish_health(scheduler, now);
          next_health = now + health_period;
        }
        if (options.paced_replay && !did && scheduler.exhausted()) {
          end_reason = "end of the recordings";
          break;
        }
        if (!did) wake.wait(token, std::min(idle, next_health - now));
      }
      // Stop capturing, drain what the rings hold (bounded), flush the decoders, run the queue.
      scheduler.stop_sources();
      const HostTime deadline = host_now() + kDrainBudget;
      while (host_now() < deadline && scheduler.step()) scheduler_beat.beat();
      scheduler.finish();
      outputs.publish_health(scheduler, host_now());
    } catch (const std::exception& e) {
      scheduler_error = e.what();
    }
    scheduler_done.store(true, std::memory_order_release);
  });

  if (options.on_ready) options.on_ready(opened.ports);
  spdlog::info("livod {}: {} sensor(s) {}", options.paced_replay ? "replay --realtime" : "run",
               scheduler.sensors().size(),
               options.paced_replay ? "paced from their recordings" : "live; ready");
  {
    std::string names;
    for (const auto& s : scheduler.sensors())
      names += (names.empty() ? "" : ", ") + s->config->name;
    notifier.ready(host_now(), "started: " + names + "; waiting for data");
  }

  // The watchdog is pinged from this thread, not from a thread it watches: the main thread does
  // nothing but wait for signals (waking every 100 ms), so it stays responsive whatever the
  // pipeline does, and each ping is gated on every other thread's heartbeat having advanced since
  // the previous one. Pinging from the scheduler (or the publisher) would prove only that thread
  // alive; pinging from here unconditionally would keep a stuck scheduler's service running.
  const HostTime started = host_now();
  while (!scheduler_done.load(std::memory_order_acquire)) {
    notifier.tick(host_now());
    if (options.stop.stop_requested()) {
      result.stopped_by = "stop request";
      break;
    }
    if (options.max_duration.count() > 0 && host_now() - started >= options.max_duration) {
      result.stopped_by = "--max-duration";
      break;
    }
    const int s = signals.wait(Nanoseconds(100'000'000));
    if (s == SIGINT || s == SIGTERM) {
      result.stopped_by = s == SIGINT ? "SIGINT" : "SIGTERM";
      result.stop_signal = s;
      spdlog::info("{}: stopping (draining the rings, writing the outputs)", result.stopped_by);
      break;
    }
    if (s == SIGHUP) spdlog::info("SIGHUP ignored: livod does not reload its configuration");
    if (s == SIGUSR1) publisher.request_map_save();  // written on the IO side, never here
  }
  notifier.stopping(result.stopped_by.empty() ? "the scheduler stopped" : result.stopped_by);
  scheduler_thread.request_stop();
  wake.ring();
  scheduler_thread.join();
  if (result.stopped_by.empty()) result.stopped_by = end_reason.empty() ? "error" : end_reason;
  if (recording) {
    // The capture threads have stopped: the recorder drains its taps and closes the files.
    for (const auto& problem : recording->finish()) spdlog::warn("{}", problem);
    for (const auto& s : recording->recorder().stats()) {
      spdlog::info("record: {}", record::format_file_stats(s));
    }
  }

  result.errors = publisher.stop();
  if (!scheduler_error.empty()) result.errors.insert(result.errors.begin(), scheduler_error);
  result.frames = scheduler.stats().frames;
  result.estimator = scheduler.pipeline().counters();
  result.publisher = publisher.stats();
  for (const auto& s : scheduler.sensors()) {
    result.sensor_summaries.push_back(s->config->name + ": " + s->source->summary());
    result.losses.merge(s->source->input_losses());
  }
  result.exit_code = result.errors.empty() ? 0 : 1;
  return result;
}

}  // namespace livod::daemon::runtime
