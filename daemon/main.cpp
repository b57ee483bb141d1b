// livod: one binary, subcommands for live operation, replay, decoding, simulation and tools.

#include <fmt/core.h>
#include <pthread.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "daemon/commands/command.hpp"
#include "daemon/config/problems.hpp"
#include "daemon/logging.hpp"
#include "daemon/runtime/signals.hpp"

namespace livod::daemon {

struct UnknownSubcommand {
  std::string name;
  std::string hint;  // " (did you mean 'x'?); subcommands: a, b, c"
};

// The first word of the command line when it is not an option and names no subcommand.
std::optional<UnknownSubcommand> unknown_subcommand(CLI::App& app, int argc, char** argv) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands({})) names.push_back(sub->get_name());
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.starts_with("-")) {
      if (word == "--log-level") ++i;  // the root's only option with a value
      continue;
    }
    if (std::find(names.begin(), names.end(), word) != names.end()) return std::nullopt;
    UnknownSubcommand u;
    u.name = word;
    if (const std::string close = closest_match(word, names); !close.empty()) {
      u.hint = " (did you mean '" + close + "'?)";
    }
    std::string all;
    for (const auto& n : names) all += (all.empty() ? "" : ", ") + n;
    u.hint += "; subcommands: " + all + " (livod --help)";
    return u;
  }
  return std::nullopt;
}

}  // namespace livod::daemon

int main(int argc, char** argv) {
  CLI::App app{"livod - LiDAR-inertial-visual odometry daemon"};
  app.require_subcommand(1);
  livod::daemon::LoggingConfig log_config;
  app.add_option("--log-level", log_config.level, "trace|debug|info|warn|error|critical|off")
      ->capture_default_str();

  livod::daemon::CommandContext ctx;
  livod::daemon::add_version_command(app, ctx);
  // COMMAND-REGISTRATIONS (one line per subcommand; keep sorted)
  livod::daemon::add_run_command(app, ctx);
  livod::daemon::add_record_command(app, ctx);
  livod::daemon::add_replay_command(app, ctx);
  livod::daemon::add_decode_command(app, ctx);
  livod::daemon::add_inspect_command(app, ctx);
  livod::daemon::add_sim_command(app, ctx);
  livod::daemon::add_check_config_command(app, ctx);
  livod::daemon::add_eval_command(app, ctx);
  livod::daemon::add_save_map_command(app, ctx);

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
    // "A subcommand is required" would hide a mistyped one: name it and the known ones.
    if (const auto unknown = livod::daemon::unknown_subcommand(app, argc, argv)) {
      fmt::print(stderr, "livod: unknown subcommand '{}'{}\n", unknown->name, unknown->hint);
      return livod::daemon::kExitUsage;
    }
    return app.exit(e);
  } catch (const std::exception& e) {
    fmt::print(stderr, "livod: error: {}\n", e.what());
    livod::daemon::shutdown_logging();
    return 1;
  }
  livod::daemon::shutdown_logging();
  return ctx.exit_code;
}
