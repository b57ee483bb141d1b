// `livod replay --config CONFIG.yaml -o OUTDIR [NAME=PATH | PATH]...`: replays recordings (pcap,
// candump logs, ROS1 bags) through the decoders, clock domains and LIO estimator as fast as
// possible, single-threaded and deterministic, and writes OUTDIR/trajectory.txt (TUM), map.pcd,
// timing.txt, timing.json and frames.csv (docs/replay.md). Exit codes: 0 done, 1 a configuration
// with errors (every problem is printed) or a recording that cannot be replayed, 2 usage.

#include <fmt/core.h>
#include <CLI/CLI.hpp>

#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "daemon/commands/command.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/replay/progress.hpp"
#include "daemon/replay/replay_engine.hpp"

namespace livod::daemon {
namespace {

constexpr int kExitFailure = 1;

struct ReplayArgs {
  std::string config;
  std::string out;
  std::vector<std::string> inputs;
  bool quiet = false;
  double max_duration_s = 0.0;
  int threads = -1;
  double map_cell_m = 0.2;
  std::size_t map_max_points = 2'000'000;
  std::string debug_images;
};

void print_result(const replay::ReplayResult& r) {
  const auto& s = r.summary;
  fmt::print("trajectory: {} ({} poses)\n", r.trajectory.string(), s.frames);
  fmt::print("map:        {} ({} points)\n", r.map.string(), s.exported_points);
  fmt::print("timing:     {} (+ {}, {})\n", r.timing_text.string(),
             r.timing_json.filename().string(), r.frames_csv.filename().string());
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

int run(const ReplayArgs& args) {
  const ConfigResult loaded = load_config(args.config);
  for (const auto& problem : loaded.problems) {
    fmt::print(stderr, "{}\n", format_problem(loaded.source, problem));
  }
  if (!loaded.ok()) {
    fmt::print(stderr, "livod replay: {}: {} error(s), {} warning(s); nothing replayed\n",
               loaded.source, loaded.error_count(), loaded.warning_count());
    return kExitFailure;
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
    return 0;
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
  cmd->callback([&ctx, args] { ctx.exit_code = run(*args); });
}

}  // namespace livod::daemon
