#pragma once
// Subcommands of the single `livod` binary. Each add_*_command() registers one subcommand on the
// root app; its callback stores the process exit code in the context. A subcommand exists only
// when it works end to end.

namespace CLI {
class App;
}

namespace livod::daemon {

struct CommandContext {
  int exit_code = 0;
};

void add_version_command(CLI::App& app, CommandContext& ctx);
// COMMAND-DECLARATIONS (one line per subcommand; keep sorted)
void add_run_command(CLI::App& app, CommandContext& ctx);
void add_replay_command(CLI::App& app, CommandContext& ctx);
void add_decode_command(CLI::App& app, CommandContext& ctx);
void add_inspect_command(CLI::App& app, CommandContext& ctx);
void add_sim_command(CLI::App& app, CommandContext& ctx);
void add_check_config_command(CLI::App& app, CommandContext& ctx);
void add_eval_command(CLI::App& app, CommandContext& ctx);

}  // namespace livod::daemon
