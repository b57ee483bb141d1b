// livod: one binary, subcommands for live operation, replay, decoding, simulation and tools.

#include <fmt/core.h>
#include <pthread.h>
#include <CLI/CLI.hpp>

#include <exception>

#include "daemon/commands/command.hpp"
#include "daemon/logging.hpp"
#include "daemon/runtime/signals.hpp"

int main(int argc, char** argv) {
  CLI::App app{"livod - LiDAR-inertial-visual odometry daemon"};
  app.require_subcommand(1);
  livod::daemon::LoggingConfig log_config;
  app.add_option("--log-level", log_config.level, "trace|debug|info|warn|error|critical|off")
      ->capture_default_str();

  livod::daemon::CommandContext ctx;
  livod::daemon::add_version_command(app, ctx);
  // COMMAND-REGISTRATIONS (one line per subcommand; keep sorted)
  livod::daemon::add_replay_command(app, ctx);
  livod::daemon::add_decode_command(app, ctx);
  livod::daemon::add_inspect_command(app, ctx);
  livod::daemon::add_sim_command(app, ctx);
  livod::daemon::add_check_config_command(app, ctx);
  livod::daemon::add_eval_command(app, ctx);

  app.parse_complete_callback([&log_config] {
    // The logger's thread starts here: with livod's signals blocked, so that it never takes a
    // SIGTERM meant for the thread that handles it (daemon/runtime/signals.hpp).
    sigset_t handled = livod::daemon::runtime::BlockedSignals::handled();
    sigset_t previous;
    pthread_sigmask(SIG_BLOCK, &handled, &previous);
    const bool level_ok = livod::daemon::init_logging(log_config);
    pthread_sigmask(SIG_SETMASK, &previous, nullptr);
    if (!level_ok) {
      fmt::print(stderr, "livod: unknown log level '{}', using info\n", log_config.level);
    }
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    livod::daemon::shutdown_logging();
    return app.exit(e);
  } catch (const std::exception& e) {
    fmt::print(stderr, "livod: error: {}\n", e.what());
    livod::daemon::shutdown_logging();
    return 1;
  }
  livod::daemon::shutdown_logging();
  return ctx.exit_code;
}
