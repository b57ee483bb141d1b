// `livod save-map [--config FILE] [--timeout S]`: asks the running daemon to save its map, over
// LCM (livod.command_t COMMAND_SAVE_MAP on the configuration's command channel), waits for the
// answer and prints where the map was written (docs/deploy.md "Saving the map"). The daemon writes
// the file (as its own user, in its own folder); this command only sends the request.
//
// Exit codes: 0 the map was saved; 1 the save failed or was rejected, no answer in time, or the
// configuration cannot be used.

#include <fmt/core.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <chrono>
#include <exception>
#include <memory>
#include <string>

#include "daemon/commands/command.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/publish/lcm_commands.hpp"

namespace livod::daemon {
namespace {

struct SaveMapArgs {
  std::string config = "/etc/livod/livod.yaml";
  double timeout_s = 30.0;
};

int save_map(const SaveMapArgs& args) {
  const ConfigResult loaded = load_config(args.config);
  if (!loaded.ok()) {
    for (const auto& p : loaded.problems)
      fmt::print(stderr, "{}\n", format_problem(loaded.source, p));
    fmt::print(stderr, "livod save-map: {}: errors in the configuration\n", loaded.source);
    return 1;
  }
  const LcmOutputConfig& lcm = loaded.config.outputs.lcm;
  if (!lcm.enabled) {
    fmt::print(
        stderr,
        "livod save-map: LCM is off in {} (outputs.lcm): send SIGUSR1 to the daemon instead\n",
        loaded.source);
    return 1;
  }
  publish::CommandRecord c;
  // Unique enough among concurrent senders: the time in µs and this process's id.
  c.request_id = (std::chrono::duration_cast<std::chrono::microseconds>(
                      std::chrono::system_clock::now().time_since_epoch())
                      .count()
                  << 16) ^
                 static_cast<std::int64_t>(::getpid());
  c.sender = "livod save-map (pid " + std::to_string(::getpid()) + ")";
  c.command = static_cast<std::int8_t>(publish::Command::kSaveMap);
  const std::string command_channel = lcm.channel(lcm.channels.command);
  const std::string result_channel = lcm.channel(lcm.channels.command_result);
  try {
    const auto r = publish::send_command(lcm.url, command_channel, result_channel, c,
                                         static_cast<int>(args.timeout_s * 1000.0));
    if (!r) {
      fmt::print(stderr,
                 "livod save-map: no answer on {} within {:.0f} s (is livod running with this "
                 "configuration? LCM URL {})\n",
                 result_channel, args.timeout_s, lcm.url);
      return 1;
    }
    if (r->status != publish::CommandStatus::kOk) {
      fmt::print(stderr, "livod save-map: {}: {}\n",
                 r->status == publish::CommandStatus::kRejected ? "rejected" : "failed",
                 r->message);
      return 1;
    }
    fmt::print("{}\n{} points, {} bytes, save {}{}, written in {:.2f} s\n", r->path, r->points,
               r->bytes, r->save_number, r->coalesced ? " (joined a save already in progress)" : "",
               r->duration_s);
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "livod save-map: {}\n", e.what());
    return 1;
  }
}

}  // namespace

void add_save_map_command(CLI::App& app, CommandContext& ctx) {
  auto args = std::make_shared<SaveMapArgs>();
  auto* cmd = app.add_subcommand(
      "save-map", "Ask the running livod to save its map (over LCM) and print the file");
  cmd->add_option("--config", args->config, "The daemon's configuration (its LCM URL and channels)")
      ->capture_default_str()
      ->check(CLI::ExistingFile);
  cmd->add_option("--timeout", args->timeout_s, "Seconds to wait for the answer")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 3600.0));
  cmd->callback([&ctx, args] { ctx.exit_code = save_map(*args); });
}

}  // namespace livod::daemon
