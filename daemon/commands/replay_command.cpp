// `livod replay --config CONFIG.yaml -o OUTDIR [--realtime] [NAME=PATH | PATH]...`: replays
// recordings (pcap, candump logs, ROS1 bags, image folders) through the decoders, clock domains and
// the estimator (LIO, and VIO with a camera)
// - as fast as possible, single-threaded and deterministic (default): OUTDIR/trajectory.txt (TUM),
//   map.pcd, timing.txt, timing.json and frames.csv (docs/replay.md);
// - or --realtime: at the recorded pace through the daemon's threads and rings (the runtime of
//   `livod run`): OUTDIR/trajectory.txt, map.pcd and timing.txt.
// Exit codes: 0 done, 1 a configuration with errors (every problem is printed) or a recording that
// cannot be replayed, 2 usage, 3 the replay ran but part of a recording could not be read (every
// lost stretch is printed; the outputs cover only what was read) and --accept-partial-input was
// not given, 130/143 interrupted by SIGINT/SIGTERM (the outputs cover what was replayed).

#include <fmt/core.h>
#include <CLI/CLI.hpp>

#include <exception>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "daemon/commands/command.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/preflight.hpp"
#include "daemon/replay/progress.hpp"
#include "daemon/replay/replay_engine.hpp"
#include "daemon/runtime/daemon.hpp"
#include "daemon/runtime/signals.hpp"
#include "io/input_loss.hpp"

namespace livod::daemon {
namespace {

struct ReplayArgs {
  std::string config;
  std::string out;
  std::vector<std::string> inputs;
  bool quiet = false;
  double max_duration_s = 0.0;
  int threads = -1;
  double map_cell_m = 0.2;
  std::size_t map_max_points = 2'000'000;
  bool realtime = false;
  bool accept_partial_input = false;
  std::string debug_images;
};

// Everything the console must say about map.pcd that the numbers alone would hide: an empty map,
// points dropped for the budget or outside the cell grid.
void print_map_warnings(const replay::ReplaySummary& s) {
  if (s.exported_dropped > 0) {
    fmt::print(stderr,
               "livod replay: warning: map.pcd reached its budget of {} points: {} later points "
               "in new cells were dropped, so the map covers only the first part of the run "
               "(raise --map-max-points or --map-cell)\n",
               s.exported_budget, s.exported_dropped);
  }
  if (s.exported_outside > 0) {
    fmt::print(stderr,
               "livod replay: warning: {} points lay outside the map.pcd cell grid (+-{:.6g} m "
               "per axis at this --map-cell) and were not mapped\n",
               s.exported_outside, s.exported_grid_half_extent_m);
  }
  if (s.frames > 0 && s.exported_points == 0) {
    fmt::print(stderr, "livod replay: warning: map.pcd is empty although {} poses were estimated\n",
               s.frames);
  }
}

// Prints every lost stretch; returns the exit status the losses call for.
int report_losses(const io::InputLossLog& losses, bool accepted) {
  if (losses.empty()) return 0;
  for (const auto& loss : losses.entries()) {
    fmt::print(stderr, "livod replay: input lost: {}\n", io::format_loss(loss));
  }
  if (losses.not_listed() > 0) {
    fmt::print(stderr, "livod replay: input lost: {} more damaged stretches not listed\n",
               losses.not_listed());
  }
  fmt::print(stderr,
             "livod replay: {} damaged stretch(es) of the recordings were skipped ({} bytes, {} "
             "records known lost, {:.3f} s of recording known missing): the outputs cover only "
             "what could be read\n",
             losses.count(), losses.bytes(), losses.records(), losses.seconds());
  if (accepted) {
    fmt::print(stderr, "livod replay: partial input accepted (--accept-partial-input)\n");
    return 0;
  }
  fmt::print(stderr,
             "livod replay: failing because input was lost (exit status {}); "
             "--accept-partial-input accepts a partial replay\n",
             kExitPartialInput);
  return kExitPartialInput;
}

void print_result(const replay::ReplayResult& r) {
  const auto& s = r.summary;
  fmt::print("trajectory: {} ({} poses)\n", r.trajectory.string(), s.frames);
  fmt::print("map:        {} ({} points)\n", r.map.string(), s.exported_points);
  fmt::print("timing:     {} (+ {}, {})\n", r.timing_text.string(),
             r.timing_json.filename().string(), r.frames_csv.filename().string());
  for (const auto& p : r.configured_outputs) {
    fmt::print("also:       {} (the configuration's outputs)\n", p.string());
  }
  fmt::print(
      "frame time (wall) p50 {:.2f} ms, p95 {:.2f} ms, p99 {:.2f} ms, max {:.2f} ms; CPU (all "
      "threads) "
      "p50 {:.2f} ms, p99 {:.2f} ms; points per scan after downsampling p50 {:.0f}\n",
      s.frame_ms.p50, s.frame_ms.p95, s.frame_ms.p99, s.frame_ms.max, s.frame_cpu_ms.p50,
      s.frame_cpu_ms.p99, s.used_points.p50);
  fmt::print("{:.1f} s of recording in {:.1f} s ({:.2f}x real time), peak RSS {:.1f} MiB\n",
             s.recording_s, s.wall_s, s.realtime_factor,
             static_cast<double>(s.peak_rss_bytes) / (1024.0 * 1024.0));
  if (s.degenerate_frames > 0) {
    fmt::print("degenerate frames: {} (see frames.csv)\n", s.degenerate_frames);
  }
  if (s.vio_ms.count > 0) {
    fmt::print(
        "visual update: {} of {} images updated the state; per image p50 {:.2f} ms, p99 {:.2f} ms "
        "(pyramid {:.2f}, selection {:.2f}, update {:.2f}, map {:.2f} ms p50); {} patches p50; "
        "visual map {} points\n",
        s.counters.vio_updates, s.counters.images_in, s.vio_ms.p50, s.vio_ms.p99,
        s.vio_pyramid_ms.p50, s.vio_selection_ms.p50, s.vio_update_ms.p50, s.vio_map_ms.p50,
        s.vio_patches.p50, s.visual_map.points);
  }
  if (s.frames == 0) {
    fmt::print("no pose was estimated: IMU initialisation {}; scans in {}, before init {}\n",
               s.init_status, s.counters.scans_in, s.counters.scans_before_init);
  }
}

int run_realtime(const LivodConfig& config, const ReplayArgs& args) {
  runtime::DaemonOptions options;
  options.paced_replay = true;
  options.inputs = args.inputs;
  options.out_dir = args.out;
  options.threads = args.threads;
  options.max_duration = from_seconds(args.max_duration_s);
  options.map_cell_m = args.map_cell_m;
  options.map_max_points = args.map_max_points;
  const runtime::DaemonResult r = runtime::run_daemon(config, options);
  for (const auto& s : r.sensor_summaries) fmt::print("{}\n", s);
  const auto& p = r.publisher;
  fmt::print("stopped by {}: {} frames; frame time p50 {:.2f} ms, p99 {:.2f} ms\n", r.stopped_by,
             r.frames, p.frame_ms.percentile(0.5), p.frame_ms.percentile(0.99));
  fmt::print("outputs: {}/trajectory.txt, map.pcd, timing.txt\n", args.out);
  for (const auto& e : r.errors) fmt::print(stderr, "livod replay: {}\n", e);
  if (r.exit_code != 0) return r.exit_code;
  const int losses = report_losses(r.losses, args.accept_partial_input);
  // The configuration's outputs, honoured as in the fast replay: copies of OUTDIR's files.
  const std::filesystem::path out(args.out);
  const std::pair<std::filesystem::path, std::filesystem::path> copies[] = {
      {out / "trajectory.txt", config.outputs.trajectory},
      {out / "map.pcd", config.outputs.map_pcd},
      {out / "timing.txt", config.outputs.timing_report}};
  for (const auto& [from, to] : copies) {
    if (to.empty()) continue;
    std::error_code ec;
    std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing, ec);
    if (ec) {
      fmt::print(stderr, "livod replay: cannot write {}: {}\n", to.string(), ec.message());
      return kExitFailure;
    }
    fmt::print("also: {} (the configuration's outputs)\n", to.string());
  }
  if (r.stop_signal != 0) {
    fmt::print(stderr, "livod replay: interrupted by {}: the outputs cover what was replayed\n",
               r.stopped_by);
    return runtime::exit_status_for(r.stop_signal);
  }
  return losses;
}

int run(const ReplayArgs& args) {
  // The same file checks as check-config (recordings are opened by the run itself).
  ConfigResult loaded = load_checked_config(args.config, /*open_recordings=*/false);
  for (const auto& problem : loaded.problems) {
    fmt::print(stderr, "{}\n", format_problem(loaded.source, problem));
  }
  if (!loaded.ok()) {
    fmt::print(stderr, "livod replay: {}: {} error(s), {} warning(s); nothing replayed\n",
               loaded.source, loaded.error_count(), loaded.warning_count());
    return kExitFailure;
  }
  if (args.realtime) {
    if (!args.debug_images.empty()) {
      fmt::print(stderr, "livod replay: --debug-images is written by the fast replay only\n");
      return kExitFailure;
    }
    try {
      return run_realtime(loaded.config, args);
    } catch (const std::exception& e) {
      fmt::print(stderr, "livod replay: {}\n", e.what());
      return kExitFailure;
    }
  }
  replay::ReplayOptions options;
  options.out_dir = args.out;
  options.inputs = args.inputs;
  options.progress = !args.quiet && replay::stderr_is_tty();
  options.max_duration_s = args.max_duration_s;
  options.threads = args.threads;
  options.map_cell_m = args.map_cell_m;
  options.map_max_points = args.map_max_points;
  options.debug_images_dir = args.debug_images;
  try {
    const replay::ReplayResult result = replay::run_replay(loaded.config, options);
    for (const auto& note : result.notes) fmt::print(stderr, "livod replay: note: {}\n", note);
    print_result(result);
    print_map_warnings(result.summary);
    const int losses = report_losses(result.losses, args.accept_partial_input);
    if (result.interrupted_by != 0) {
      fmt::print(stderr,
                 "livod replay: interrupted by {} after {:.1f} s of recording: the outputs cover "
                 "what was replayed until then\n",
                 result.interrupted_by == SIGINT ? "SIGINT" : "SIGTERM",
                 result.summary.recording_s);
      return runtime::exit_status_for(result.interrupted_by);
    }
    return losses;
  } catch (const std::exception& e) {
    fmt::print(stderr, "livod replay: {}\n", e.what());
    return kExitFailure;
  }
}

}  // namespace

void add_replay_command(CLI::App& app, CommandContext& ctx) {
  auto args = std::make_shared<ReplayArgs>();
  auto* cmd = app.add_subcommand(
      "replay", "Replay recordings through the decoders and the estimator, as fast as possible");
  cmd->add_option("--config", args->config, "The YAML configuration")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", args->out, "Output folder (created)")->required();
  cmd->add_option("inputs", args->inputs,
                  "Recordings replacing the configured ones: NAME=PATH, or PATH assigned by format "
                  "(.pcap -> packet LiDARs, .log -> CAN IMUs, .bag -> bag sensors)");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress line (it is drawn only on a terminal)");
  cmd->add_flag("--realtime", args->realtime,
                "At the recorded pace, through the daemon's capture rings and threads (as "
                "`livod run`), instead of as fast as possible");
  cmd->add_option("--max-duration", args->max_duration_s,
                  "Stop after this many seconds of recording (0: all)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--threads", args->threads,
                  "Estimator threads (default: the configuration's estimator.threads, 0 = one per "
                  "core); the trajectory is the same for any value")
      ->check(CLI::Range(0, 256));
  cmd->add_option("--debug-images", args->debug_images,
                  "Write every image of the visual update with its patches drawn to this folder "
                  "(created; off by default)");
  cmd->add_option("--map-cell", args->map_cell_m, "map.pcd voxel filter cell (m)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--map-max-points", args->map_max_points, "map.pcd point budget")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--accept-partial-input", args->accept_partial_input,
                "Exit 0 even when part of a recording could not be read (the losses are still "
                "printed); without it such a replay exits with status 3");
  cmd->callback([&ctx, args] { ctx.exit_code = run(*args); });
}

}  // namespace livod::daemon
