// `livod run --config FILE`: the daemon. Live sensors -> capture threads -> one scheduler thread
// -> estimator -> poses, IMU-rate poses, health and (optionally) registered clouds over LCM, and
// the configured outputs (trajectory, map, timing report) at stop. Runs until SIGINT or SIGTERM
// (docs/daemon.md).
//
// Exit codes: 0 stopped by a signal with every output written; 1 a configuration with errors
// (every problem is printed before any socket opens), a sensor that cannot be opened, or an
// output that could not be written.

#include <fmt/core.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <exception>
#include <memory>
#include <string>

#include "daemon/commands/command.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/logging.hpp"
#include "daemon/preflight.hpp"
#include "daemon/record/record_session.hpp"
#include "daemon/runtime/daemon.hpp"
#include "daemon/runtime/lcm_bus.hpp"

namespace livod::daemon {
namespace {

struct RunArgs {
  std::string config;
  int threads = -1;
  std::string record;
};

int run(const RunArgs& args, const CLI::App& root) {
  // The same file checks as check-config (recordings are opened by the run itself).
  ConfigResult loaded = load_checked_config(args.config, /*open_recordings=*/false);
  if (loaded.ok() && !args.record.empty()) {
    for (auto& p : record::record_problems(loaded.config)) {
      p.message = "--record: " + p.message;
      loaded.problems.push_back(std::move(p));
    }
  }
  for (const auto& problem : loaded.problems) {
    fmt::print(stderr, "{}\n", format_problem(loaded.source, problem));
  }
  if (!loaded.ok()) {
    fmt::print(stderr, "livod run: {}: {} error(s), {} warning(s); nothing started\n",
               loaded.source, loaded.error_count(), loaded.warning_count());
    return kExitFailure;
  }
  const LivodConfig& config = loaded.config;
  // The configuration's logging level, unless --log-level was given.
  if (root.get_option("--log-level")->count() == 0) set_log_level(config.logging.level);

  try {
    std::unique_ptr<runtime::MessageBus> bus;
    if (config.outputs.lcm.enabled)
      bus = runtime::make_lcm_bus(config.outputs.lcm, config.body_frame);
    runtime::DaemonOptions options;
    options.bus = bus.get();
    options.threads = args.threads;
    options.record_dir = args.record;
    options.notify_systemd = true;  // READY/STATUS/WATCHDOG/STOPPING when run by systemd
    const runtime::DaemonResult r = runtime::run_daemon(config, options);
    for (const auto& s : r.sensor_summaries) spdlog::info("{}", s);
    const auto& p = r.publisher;
    spdlog::info(
        "stopped by {}: {} frames, frame time p50 {:.2f} ms p99 {:.2f} ms, pose latency p50 "
        "{:.2f} ms p99 {:.2f} ms",
        r.stopped_by, r.frames, p.frame_ms.percentile(0.5), p.frame_ms.percentile(0.99),
        p.pose_latency_ms.percentile(0.5), p.pose_latency_ms.percentile(0.99));
    for (const auto& e : r.errors) spdlog::error("{}", e);
    return r.exit_code;
  } catch (const std::exception& e) {
    spdlog::error("livod run: {}", e.what());
    return kExitFailure;
  }
}

}  // namespace

void add_run_command(CLI::App& app, CommandContext& ctx) {
  auto args = std::make_shared<RunArgs>();
  auto* cmd = app.add_subcommand(
      "run", "Run the odometry on live sensors, publishing over LCM, until SIGINT/SIGTERM");
  cmd->add_option("--config", args->config, "The YAML configuration (e.g. /etc/livod/livod.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--threads", args->threads,
                  "Estimator threads (default: the configuration's estimator.threads, 0 = one per "
                  "core)")
      ->check(CLI::Range(0, 256));
  cmd->add_option(
      "--record", args->record,
      "Also record the live sensors' raw data, into a new subfolder of this folder (like "
      "outputs.record; docs/record.md)");
  cmd->callback([&ctx, &app, args] { ctx.exit_code = run(*args, app); });
}

}  // namespace livod::daemon
