#include "daemon/replay/replay_engine.hpp"

#include <fmt/core.h>

#include <chrono>
#include <fstream>

#include "core/error.hpp"
#include "daemon/replay/file_outputs.hpp"
#include "daemon/replay/input_assignment.hpp"
#include "daemon/replay/map_accumulator.hpp"
#include "daemon/replay/progress.hpp"
#include "daemon/replay/sources.hpp"
#include "daemon/runtime/scheduler.hpp"
#include "daemon/runtime/signals.hpp"
#include "daemon/worker_pool.hpp"
#include "io/output_file.hpp"

namespace livod::daemon::replay {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
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
  io::write_file(path, text);
}

// The recordings of the sensors the estimator uses, as runtime sources.
std::vector<runtime::SensorInput> open_recordings(const LivodConfig& config,
                                                  const runtime::SensorRoles& roles,
                                                  const std::vector<std::string>& inputs,
                                                  std::vector<std::string>& notes) {
  const auto recordings = assign_recordings(config, inputs);
  std::vector<runtime::SensorInput> out;
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const SensorConfig& s = config.sensors[i];
    if (!roles.unused_reason[i].empty()) {
      notes.push_back(fmt::format("sensor '{}' ({}) is not replayed: {}", s.name,
                                  enum_name(s.driver), roles.unused_reason[i]));
      continue;
    }
    const auto& recording = recordings[i];
    if (!recording) {
      throw Error("sensor '" + s.name + "' has no recording to replay: its source is live; give " +
                  "one on the command line (" + s.name + "=PATH)");
    }
    runtime::SensorInput in;
    in.sensor_index = i;
    in.origin = recording->replay.file.string();
    if (!recording->replay.topic.empty()) in.origin += " " + recording->replay.topic;
    in.source = make_source(s, recording->replay, recording->ports);
    out.push_back(std::move(in));
  }
  return out;
}

ProgressState progress_state(const runtime::Scheduler& scheduler) {
  ProgressState p;
  const auto& st = scheduler.stats();
  if (st.first_event_ns) {
    p.recording_s = to_seconds(Nanoseconds(st.last_event_ns - *st.first_event_ns));
  }
  p.fraction = scheduler.fraction_done();
  p.frames = st.frames;
  p.last_frame_ms = scheduler.last_frame_ms();
  if (!scheduler.pipeline().initialised()) {
    p.status = "IMU init: " + scheduler.pipeline().init_status();
  }
  return p;
}

}  // namespace

ReplayResult run_replay(const LivodConfig& config, const ReplayOptions& options) {
  ReplayResult result;
  const runtime::SensorRoles roles = runtime::assign_roles(config);
  auto inputs = open_recordings(config, roles, options.inputs, result.notes);

  std::filesystem::create_directories(options.out_dir);
  result.trajectory = options.out_dir / "trajectory.txt";
  result.map = options.out_dir / "map.pcd";
  result.timing_text = options.out_dir / "timing.txt";
  result.timing_json = options.out_dir / "timing.json";
  result.frames_csv = options.out_dir / "frames.csv";
  const bool camera = roles.camera >= 0;
  if (!camera && !options.debug_images_dir.empty()) {
    throw Error(
        "--debug-images needs a camera that the visual update uses (an enabled camera and "
        "estimator.vio.enabled)");
  }
  FileOutputs::CameraOutputs camera_outputs;
  camera_outputs.colored_map = camera;
  camera_outputs.debug_images = options.debug_images_dir;
  camera_outputs.patch_size = config.estimator.vio.patch_size;
  FileOutputs outputs({result.trajectory, result.frames_csv}, options.map_cell_m,
                      options.map_max_points, camera_outputs);

  // One thread reads, decodes and runs the filter; the estimator spreads residuals and map refits
  // over the pool. Its results do not depend on the pool size (estimator/task_runner.hpp), so the
  // replay stays deterministic.
  const int threads = options.threads >= 0 ? options.threads : config.estimator.threads;
  WorkerPool pool(threads > 0 ? threads : WorkerPool::hardware_threads());
  runtime::SchedulerOptions so;
  so.max_recording =
      options.max_duration_s > 0.0 ? from_seconds(options.max_duration_s) : Nanoseconds(0);
  so.vio_colorize = camera;
  so.vio_debug = !options.debug_images_dir.empty();
  runtime::Scheduler scheduler(config, std::move(inputs), &pool, outputs, so);

  ProgressLine progress(options.progress);
  const auto wall_start = Clock::now();
  // SIGINT / SIGTERM stop the replay cleanly: what was read is processed and written.
  const runtime::BlockedSignals signals;
  constexpr std::uint64_t kSignalCheckPeriod = 256;  // events between two looks
  for (std::uint64_t n = 0; !scheduler.exhausted(); ++n) {
    scheduler.step();
    progress.update(progress_state(scheduler));
    if (n % kSignalCheckPeriod == 0) {
      if (const int sig = signals.wait(Nanoseconds(0)); sig == SIGINT || sig == SIGTERM) {
        result.interrupted_by = sig;
        break;
      }
    }
  }
  scheduler.finish();
  const double wall_s = seconds_since(wall_start);
  progress.finish(progress_state(scheduler));

  outputs.close();
  if (outputs.colored_map()) {
    write_pcd_rgb(result.map, outputs.map().xyz(), outputs.map().rgb());
  } else {
    write_pcd(result.map, outputs.map().xyz());
  }

  ReplaySummary& s = result.summary;
  const auto& st = scheduler.stats();
  const auto& pipeline = scheduler.pipeline();
  s.config_file = config.source_file.string();
  s.frames = outputs.poses();
  s.init_status = pipeline.init_status();
  s.counters = pipeline.counters();
  s.degenerate_frames = s.counters.degenerate_frames;
  outputs.series().summarise(s);
  outputs.vio_series().summarise(s);
  if (pipeline.vio() != nullptr) s.visual_map = pipeline.vio()->map().stats();
  s.inv_exposure = outputs.inv_exposure();
  s.recording_s =
      st.first_event_ns ? to_seconds(Nanoseconds(st.last_event_ns - *st.first_event_ns)) : 0.0;
  s.wall_s = wall_s;
  s.output_s = st.output_s;
  s.decode_s = st.decode_s;
  s.estimator_s = st.estimator_s;
  s.realtime_factor = wall_s > 0.0 ? s.recording_s / wall_s : 0.0;
  s.peak_rss_bytes = peak_rss_bytes();
  s.final_rss_bytes = current_rss_bytes();
  s.map = pipeline.map().stats();
  s.map_bytes_peak = std::max(outputs.map_bytes_peak(), s.map.bytes);
  s.exported_points = outputs.map().size();
  s.exported_dropped = outputs.map().dropped_full();
  s.exported_outside = outputs.map().dropped_outside();
  s.exported_grid_half_extent_m = outputs.map().grid_half_extent_m();
  s.exported_budget = options.map_max_points;
  for (const auto& r : scheduler.sensors()) {
    SensorSummary sensor;
    sensor.name = r->config->name;
    sensor.role = r->role;
    sensor.file = r->origin;
    sensor.counters = r->source->summary();
    sensor.scans = r->scans;
    sensor.imu_samples = r->imu_samples;
    sensor.images = r->images;
    sensor.clock = clock_summary(*r->clock);
    s.sensors.push_back(std::move(sensor));
  }
  write_text_file(result.timing_text, format_timing_text(s));
  write_text_file(result.timing_json, format_timing_json(s));
  for (const auto& r : scheduler.sensors()) {
    result.losses.merge(r->source->input_losses());
    for (auto& note : r->source->notes()) result.notes.push_back(std::move(note));
  }

  // The configuration's outputs, honoured as `livod run` honours them: copies of OUTDIR's files.
  const auto copy_to = [&](const std::filesystem::path& from, const std::filesystem::path& to) {
    if (to.empty()) return;
    std::error_code ec;
    if (to.has_parent_path()) std::filesystem::create_directories(to.parent_path(), ec);
    std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing, ec);
    if (ec)
      throw Error("cannot write " + to.string() +
                  " (outputs in the configuration): " + ec.message());
    result.configured_outputs.push_back(to);
  };
  copy_to(result.trajectory, config.outputs.trajectory);
  copy_to(result.map, config.outputs.map_pcd);
  copy_to(result.timing_text, config.outputs.timing_report);
  return result;
}

}  // namespace livod::daemon::replay
