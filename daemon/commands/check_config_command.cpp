// `livod check-config FILE`: loads the configuration exactly as the run would, reads the files it
// names as the run reads them (Ouster metadata, Velodyne calibration, the recordings a replay
// would open: daemon/preflight.hpp), prints every problem (one per line, compiler style, so
// editors can jump to them) and, when there is no error, a short summary of the sensors and
// outputs. No socket and no device is opened.

#include <fmt/core.h>
#include <CLI/CLI.hpp>

#include <memory>
#include <string>

#include "daemon/commands/command.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/config/summary.hpp"
#include "daemon/preflight.hpp"

namespace livod::daemon {

void add_check_config_command(CLI::App& app, CommandContext& ctx) {
  struct Options {
    std::string file;
    bool strict = false;
  };
  auto options = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "check-config", "Validate a configuration file: list every problem, or summarise it");
  cmd->add_option("FILE", options->file, "The YAML configuration file")->required();
  cmd->add_flag("--strict", options->strict, "Treat warnings as errors (exit status 1)");
  cmd->callback([&ctx, options] {
    ConfigResult result = load_config(options->file);
    if (result.ok()) {
      for (auto& p : check_config_files(result.config, /*open_recordings=*/true)) {
        result.problems.push_back(std::move(p));
      }
    }
    for (const auto& problem : result.problems) {
      fmt::print(stderr, "{}\n", format_problem(result.source, problem));
    }
    const std::size_t errors = result.error_count();
    const std::size_t warnings = result.warning_count();
    if (errors > 0 || (options->strict && warnings > 0)) {
      fmt::print(stderr, "{}: {} error(s), {} warning(s)\n", result.source, errors, warnings);
      ctx.exit_code = 1;
      return;
    }
    fmt::print("{}: OK ({} warning(s))\n{}", result.source, warnings,
               summarize_config(result.config));
    ctx.exit_code = 0;
  });
}

}  // namespace livod::daemon
