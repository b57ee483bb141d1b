#pragma once
// Subcommands of the single `livod` binary. Each add_*_command() registers one subcommand on the
// root app; its callback stores the process exit code in the context. A subcommand exists only
// when it works end to end.

namespace CLI {
class App;
}

namespace livod::daemon {

// The process's exit statuses shared by the subcommands: 0 success, 1 failure, 2 bad usage (a bad
// command line or configuration), 3 a replay or decode that could not read part of its input
// (docs/replay.md, --accept-partial-input).
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;
inline constexpr int kExitPartialInput = 3;

struct CommandContext {
  int exit_code = 0;
};

void add_version_command(CLI::App& app, CommandContext& ctx);
// COMMAND-DECLARATIONS (one line per subcommand; keep sorted)
void add_run_command(CLI::App& app, CommandContext& ctx);
void add_record_command(CLI::App& app, CommandContext& ctx);
void add_replay_command(CLI::App& app, CommandContext& ctx);
void add_decode_command(CLI::App& app, CommandContext& ctx);
void add_inspect_command(CLI::App& app, CommandContext& ctx);
void add_sim_command(CLI::App& app, CommandContext& ctx);
void add_check_config_command(CLI::App& app, CommandContext& ctx);
void add_eval_command(CLI::App& app, CommandContext& ctx);
void add_save_map_command(CLI::App& app, CommandContext& ctx);

}  // namespace livod::daemon
