#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <fmt/core.h>

#include "daemon/commands/command.hpp"

namespace livod::daemon {

void add_version_command(CLI::App& app, CommandContext& ctx) {
  auto* cmd = app.add_subcommand("version", "Print the livod version and build settings");
  cmd->callback([&ctx] {
    fmt::print("livod {}\n", LIVOD_VERSION);
    fmt::print("eigen {}.{}.{}\n", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION);
    ctx.exit_code = 0;
  });
}

}  // namespace livod::daemon
