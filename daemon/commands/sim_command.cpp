// `livod sim`: writes a simulated sequence (wire-format captures, ground truth, configuration).

#include <fmt/core.h>
#include <CLI/CLI.hpp>

#include <cmath>
#include <optional>
#include <set>

#include "daemon/commands/command.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/plain_scenario.hpp"
#include "tools/sim/runner.hpp"
#include "tools/sim/scenario.hpp"

namespace livod::daemon {
namespace {

// A scenario can run when every LiDAR model it mounts is simulated.
bool runnable(const sim::Scenario& s, const std::set<std::string>& models) {
  for (const auto& l : s.lidars) {
    if (!models.contains(l.model)) return false;
  }
  return true;
}

}  // namespace

void add_sim_command(CLI::App& app, CommandContext& ctx) {
  auto* cmd = app.add_subcommand("sim", "Simulate a sensor sequence in the real wire formats");
  struct Options {
    bool list = false;
    std::string scenario;
    std::string scenario_file;
    std::uint64_t seed = 1;
    std::optional<double> duration;
    std::string out;
    bool no_images = false;
    bool bag = false;
    double scan_rate_hz = 0.0;
    bool plain = false;
  };
  auto opts = std::make_shared<Options>();
  cmd->add_flag("--list", opts->list, "List the named scenarios (name first, one per line)");
  cmd->add_option("--scenario", opts->scenario, "Named scenario to simulate");
  cmd->add_option("--scenario-file", opts->scenario_file, "Custom scenario (YAML)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--seed", opts->seed, "Random seed (same seed, same bytes)")
      ->capture_default_str();
  cmd->add_option("--duration", opts->duration,
                  "Seconds to simulate, in (0, 3600] (default: the scenario's); a street world "
                  "grows to hold the trajectory");
  cmd->add_option("-o,--output", opts->out, "Output folder");
  cmd->add_flag("--no-images", opts->no_images, "Write camera csv/yaml but no PNG files");
  cmd->add_flag("--bag", opts->bag,
                "Also write sequence.bag: the same sequence as a ROS1 bag (FAST-LIO/FAST-LIVO2 "
                "topics, synchronised stamps)");
  cmd->add_option("--scan-rate", opts->scan_rate_hz,
                  "Scans per second of every LiDAR: 10 or 20 (Ouster 1024x10 / 1024x20, Velodyne "
                  "600 / 1200 RPM, Livox 100 / 50 ms frames; default: the scenario's)")
      ->check(CLI::IsMember({10.0, 20.0}));
  cmd->add_flag(
      "--plain", opts->plain,
      "Ideal sensors and an empty world: no beam divergence, detection limit, range walk, "
      "moving objects or foliage (Gaussian range noise and dropouts only)");
  cmd->callback([opts, &ctx] {
    std::set<std::string> models;
    for (const auto& [m, _] : sim::simulated_lidar_models()) models.insert(m);
    if (opts->list) {
      for (const auto& [name, description] : sim::list_scenarios()) {
        if (runnable(sim::make_scenario(name), models)) fmt::print("{}  {}\n", name, description);
      }
      ctx.exit_code = 0;
      return;
    }
    if (opts->scenario.empty() == opts->scenario_file.empty()) {
      fmt::print(stderr,
                 "livod sim: give exactly one of --scenario NAME or --scenario-file FILE "
                 "(see --list)\n");
      ctx.exit_code = 2;
      return;
    }
    if (opts->out.empty()) {
      fmt::print(stderr, "livod sim: -o OUTPUT_DIR is required\n");
      ctx.exit_code = 2;
      return;
    }
    sim::Scenario scenario = opts->scenario.empty() ? sim::load_scenario_yaml(opts->scenario_file)
                                                    : sim::make_scenario(opts->scenario);
    for (auto& lidar : scenario.lidars) {
      if (opts->scan_rate_hz > 0.0) lidar.scan_rate_hz = opts->scan_rate_hz;
    }
    if (opts->plain) sim::make_plain(scenario);
    sim::SimRunOptions run;
    run.out_dir = opts->out;
    run.seed = opts->seed;
    if (opts->duration) {
      const double d = *opts->duration;
      if (!(std::isfinite(d) && d > 0.0 && d <= sim::kMaxSimDurationS)) {
        fmt::print(stderr, "livod sim: --duration {}: must be a number of seconds in (0, {}]\n", d,
                   sim::kMaxSimDurationS);
        ctx.exit_code = 2;
        return;
      }
      run.duration_s = d;
    }
    run.write_images = !opts->no_images;
    run.write_bag = opts->bag;
    if (opts->bag && opts->no_images && !scenario.cameras.empty()) {
      fmt::print(stderr, "livod sim: --no-images: the bag will have no camera images\n");
    }
    const auto report = sim::run_scenario(scenario, run);
    fmt::print("scenario {}: {:.1f} s simulated in {:.1f} s ({:.2f}x real time)\n", scenario.name,
               report.simulated_s, report.wall_s, report.simulated_s / report.wall_s);
    for (const auto& s : report.sensors) {
      fmt::print("  {:<10} {:<8} {:>9} messages  {:>6} lost  {}\n", s.name, s.kind, s.messages,
                 s.dropped, s.file.string());
    }
    fmt::print("  ground truth: {} poses in {}\n", report.groundtruth_poses,
               (run.out_dir / "groundtruth.txt").string());
    ctx.exit_code = 0;
  });
}

}  // namespace livod::daemon
