// `livod record --config FILE -o DIR`: the configured live sensors' raw data into DIR, without
// the estimator (docs/record.md). The same capture threads as `livod run` (one per UDP socket,
// kernel receive times; one per camera, CAN or serial IMU) feed the recorder's IO thread; the
// sensors are brought up and supervised as in `livod run` (Livox handshake and heartbeats, Ouster
// re-init); their packets are decoded only for health (rates, STALE, sequence gaps). Runs until
// SIGINT/SIGTERM or --max-duration.
//
// Exit codes: 0 stopped with every file closed (losses are reported in the log and
// DIR/recording.txt); 1 a configuration with errors or one that cannot be recorded (every
// problem listed before anything opens), a sensor that cannot be opened, a folder that holds a
// recording already, or a file that could not be created or closed.

#include <fmt/core.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "daemon/commands/command.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/logging.hpp"
#include "daemon/preflight.hpp"
#include "daemon/record/record_session.hpp"
#include "daemon/runtime/live_camera_source.hpp"
#include "daemon/runtime/live_imu_source.hpp"
#include "daemon/runtime/live_lidar_source.hpp"
#include "daemon/runtime/signals.hpp"

namespace livod::daemon {
namespace {

// The loop of this command's main thread: drain the scheduler-side rings, supervise, signals.
constexpr Nanoseconds kTurn{20'000'000};
constexpr Nanoseconds kStatsLogPeriod{60'000'000'000};

struct RecordArgs {
  std::string config;
  std::string out;
  double max_duration_s = 0.0;
};

// Decodes what the sources queued (for health: rates, gaps) and drops the results.
void drain(std::vector<std::unique_ptr<runtime::MeasurementSource>>& sources,
           const drivers::DecoderSinks& sinks, HostTime now) {
  for (auto& s : sources) {
    while (s->peek_time()) s->deliver(sinks);
    s->supervise(now);
  }
}

int run_record(const RecordArgs& args, const CLI::App& root) {
  ConfigResult loaded = load_checked_config(args.config, /*open_recordings=*/false);
  if (loaded.ok()) {
    for (auto& p : record::record_problems(loaded.config)) loaded.problems.push_back(std::move(p));
  }
  for (const auto& problem : loaded.problems) {
    fmt::print(stderr, "{}\n", format_problem(loaded.source, problem));
  }
  if (!loaded.ok()) {
    fmt::print(stderr, "livod record: {}: {} error(s), {} warning(s); nothing started\n",
               loaded.source, loaded.error_count(), loaded.warning_count());
    return kExitFailure;
  }
  const LivodConfig& config = loaded.config;
  if (root.get_option("--log-level")->count() == 0) set_log_level(config.logging.level);

  try {
    spdlog::default_logger_raw();  // before any thread starts (see run_daemon)
    const runtime::BlockedSignals signals;
    record::RecordSession session(config, args.out);
    runtime::LiveOptions lo;
    if (config.realtime.capture_priority > 0) {
      lo.capture_priority = config.realtime.capture_priority;
    }
    if (config.realtime.capture_cpu >= 0) lo.capture_cpu = config.realtime.capture_cpu;
    lo.stale_after = from_seconds(config.health.stale_after_s);
    lo.recorder = &session.recorder();
    std::vector<std::unique_ptr<runtime::MeasurementSource>> sources;
    for (const SensorConfig& s : config.sensors) {
      if (!record::is_recorded(s)) continue;
      if (is_packet_lidar(s.driver)) {
        sources.push_back(runtime::open_live_lidar(s, lo));
      } else if (sensor_kind(s.driver) == SensorKind::camera) {
        // A camera or IMU that is not there yet is waited for (reported, retried every second),
        // as in `livod run`.
        sources.push_back(runtime::open_live_camera(s, config, nullptr, &session.recorder()));
      } else {
        sources.push_back(runtime::open_live_imu(s, config, nullptr, &session.recorder()));
      }
    }
    session.start();
    spdlog::info("livod record: {} sensor(s) into {}; ready", sources.size(),
                 session.dir().string());

    drivers::DecoderSinks sinks;
    sinks.on_scan = [](const LidarScan&) {};
    sinks.on_imu = [](const ImuSample&) {};
    sinks.on_image = [](const ImageFrame&) {};
    const Nanoseconds health_period = from_seconds(config.health.period_s);
    const HostTime started = host_now();
    HostTime next_health = started + health_period;
    HostTime next_stats = started + kStatsLogPeriod;
    std::vector<std::string> states(sources.size());
    std::string stopped_by;
    while (stopped_by.empty()) {
      const int sig = signals.wait(kTurn);
      if (sig == SIGINT || sig == SIGTERM) stopped_by = sig == SIGINT ? "SIGINT" : "SIGTERM";
      if (sig == SIGHUP) spdlog::info("SIGHUP ignored: livod does not reload its configuration");
      if (sig == SIGUSR1) spdlog::info("SIGUSR1 ignored: livod record has no map to save");
      const HostTime now = host_now();
      drain(sources, sinks, now);
      if (args.max_duration_s > 0 && now - started >= from_seconds(args.max_duration_s)) {
        stopped_by = "--max-duration";
      }
      if (now >= next_health) {
        next_health = now + health_period;
        for (std::size_t i = 0; i < sources.size(); ++i) {
          const auto h = sources[i]->health(now);
          if (!h) continue;
          std::string state;
          for (const auto& st : h->streams) state += std::string(to_string(st.state)) + " ";
          if (state != states[i]) {
            spdlog::info("{}", drivers::capture::format_health(*h));
            states[i] = state;
          }
        }
      }
      if (now >= next_stats) {
        next_stats = now + kStatsLogPeriod;
        for (const auto& s : session.recorder().stats()) {
          spdlog::info("record: {}", record::format_file_stats(s));
        }
      }
    }
    spdlog::info("{}: stopping (closing the recording)", stopped_by);
    for (auto& s : sources) s->stop();
    drain(sources, sinks, host_now());
    const auto problems = session.finish();
    for (const auto& p : problems) spdlog::warn("{}", p);
    for (const auto& s : session.recorder().stats()) {
      spdlog::info("record: {}", record::format_file_stats(s));
    }
    for (auto& s : sources) spdlog::info("{}", s->summary());
    const bool closed = std::none_of(problems.begin(), problems.end(), [](const std::string& p) {
      return p.find(": closing: ") != std::string::npos;
    });
    return closed ? 0 : kExitFailure;
  } catch (const std::exception& e) {
    spdlog::error("livod record: {}", e.what());
    return kExitFailure;
  }
}

}  // namespace

void add_record_command(CLI::App& app, CommandContext& ctx) {
  auto args = std::make_shared<RecordArgs>();
  auto* cmd = app.add_subcommand(
      "record",
      "Record the configured live sensors' raw data (pcap per LiDAR, candump log per CAN IMU, "
      "serial capture per serial IMU, EuRoC folder per camera) and a replayable "
      "configuration into a folder, until SIGINT/SIGTERM");
  cmd->add_option("--config", args->config, "The YAML configuration (its live sensors)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", args->out,
                  "The recording's folder (created; must not hold a "
                  "recording)")
      ->required();
  cmd->add_option("--max-duration", args->max_duration_s, "Stop after this many seconds")
      ->check(CLI::PositiveNumber);
  cmd->callback([&ctx, &app, args] { ctx.exit_code = run_record(*args, app); });
}

}  // namespace livod::daemon
