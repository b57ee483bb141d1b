// `livod eval EST GT`: ATE/RPE of an estimated trajectory against ground truth, as evo computes
// them (tools/eval), printed as a text table; optionally a PNG plot.

#include <fmt/core.h>
#include <CLI/CLI.hpp>

#include <cmath>

#include <memory>
#include <optional>
#include <string>

#include "daemon/commands/command.hpp"
#include "tools/eval/evaluate.hpp"
#include "tools/eval/plot.hpp"

namespace livod::daemon {
namespace {

struct EvalArgs {
  std::string est;
  std::string gt;
  std::string format = "tum";
  std::string align = "se3";
  std::string rpe_unit = "frames";
  std::string times;
  std::string plot;
  eval::EvalOptions options;
};

}  // namespace

void add_eval_command(CLI::App& app, CommandContext& ctx) {
  auto args = std::make_shared<EvalArgs>();
  auto* cmd = app.add_subcommand(
      "eval", "Evaluate an estimated trajectory against ground truth (ATE and RPE, as evo)");
  cmd->add_option("EST", args->est, "estimated trajectory")->required()->check(CLI::ExistingFile);
  cmd->add_option("GT", args->gt, "ground-truth trajectory")->required()->check(CLI::ExistingFile);
  cmd->add_option("--format", args->format,
                  "tum | kitti (3x4 matrices, index association) | euroc (GT: EuRoC csv, EST: TUM)")
      ->check(CLI::IsMember({"tum", "kitti", "euroc"}))
      ->capture_default_str();
  cmd->add_option("--align", args->align, "Umeyama alignment of EST onto GT: se3 | sim3 | none")
      ->check(CLI::IsMember({"se3", "sim3", "none"}))
      ->capture_default_str();
  // NaN passes CLI11's range checks (every comparison with it is false): refuse it explicitly.
  const CLI::Validator finite(
      [](const std::string& text) {
        double v = 0.0;
        return CLI::detail::lexical_cast(text, v) && std::isfinite(v)
                   ? std::string()
                   : "'" + text + "' is not a finite number";
      },
      "FINITE");
  cmd->add_option("--t-max-diff", args->options.max_time_diff_s,
                  "max. stamp difference for time association (s)")
      ->check(finite)
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--t-offset", args->options.time_offset_s,
                  "offset added to EST stamps before association (s)")
      ->check(finite)
      ->capture_default_str();
  cmd->add_option("--rpe-delta", args->options.rpe_delta, "RPE sub-sequence length")
      ->check(finite)
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--rpe-unit", args->rpe_unit, "unit of --rpe-delta: m | s | frames")
      ->check(CLI::IsMember({"m", "s", "frames"}))
      ->capture_default_str();
  cmd->add_option("--times", args->times, "KITTI times file (one time in s per pose)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--plot", args->plot, "write a PNG: trajectories from above and ATE over time");

  cmd->callback([args, &ctx] {
    eval::EvalOptions& o = args->options;
    // The CLI checks restrict the strings to known names, so these parses always succeed.
    o.format = eval::parse_trajectory_format(args->format).value();
    o.alignment = eval::parse_alignment(args->align).value();
    o.rpe_unit = eval::parse_delta_unit(args->rpe_unit).value();
    if (!args->times.empty()) o.kitti_times = args->times;
    const eval::EvalResult result = eval::evaluate_files(args->est, args->gt, o);
    fmt::print("estimate     {}\nground truth {}\n", args->est, args->gt);
    fmt::print("{}", eval::format_report(result, o));
    if (!args->plot.empty()) {
      eval::write_plot(args->plot, result, fmt::format("{}  vs  {}", args->est, args->gt));
      fmt::print("plot         {}\n", args->plot);
    }
    ctx.exit_code = 0;
  });
}

}  // namespace livod::daemon
