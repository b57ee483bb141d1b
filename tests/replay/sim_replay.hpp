#pragma once
// Helpers of the end-to-end replay tests: simulate a scenario into a folder exactly as
// `livod sim` does, replay the folder's config.yaml as `livod replay` does, evaluate the
// trajectory against the folder's ground truth as `livod eval` does.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "daemon/config/load_config.hpp"
#include "daemon/replay/replay_engine.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/eval/evaluate.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/runner.hpp"
#include "tools/sim/scenario.hpp"

namespace livod::test {

// True when every LiDAR model the scenario mounts is simulated (what `livod sim --list` shows).
inline bool scenario_runnable(const sim::Scenario& scenario) {
  std::set<std::string> models;
  for (const auto& [model, description] : sim::simulated_lidar_models()) models.insert(model);
  for (const auto& lidar : scenario.lidars) {
    if (!models.contains(lidar.model)) return false;
  }
  return true;
}

// `livod sim --scenario NAME --duration D --no-images -o DIR`.
inline std::filesystem::path simulate(const sim::Scenario& scenario, double duration_s,
                                      const std::string& tag, std::uint64_t seed = 1) {
  const auto dir = temp_dir(tag + "-sim");
  sim::SimRunOptions options;
  options.out_dir = dir;
  options.seed = seed;
  options.duration_s = duration_s;
  options.write_images = false;
  sim::run_scenario(scenario, options);
  return dir;
}

// Loads a configuration; every problem fails the test (a replayable config has none).
inline daemon::LivodConfig load_clean_config(const std::filesystem::path& path) {
  const daemon::ConfigResult loaded = daemon::load_config(path);
  for (const auto& p : loaded.problems) {
    if (p.severity == daemon::Severity::error) {
      ADD_FAILURE() << daemon::format_problem(loaded.source, p);
    }
  }
  return loaded.config;
}

// `livod replay --config CONFIG -o OUT [inputs]`.
inline daemon::replay::ReplayResult replay(const std::filesystem::path& config,
                                           const std::filesystem::path& out,
                                           const std::vector<std::string>& inputs = {}) {
  daemon::replay::ReplayOptions options;
  options.out_dir = out;
  options.inputs = inputs;
  return daemon::replay::run_replay(load_clean_config(config), options);
}

// `livod eval EST GT` (SE(3) Umeyama alignment, evo's association).
inline eval::EvalResult evaluate(const std::filesystem::path& trajectory,
                                 const std::filesystem::path& groundtruth) {
  return eval::evaluate_files(trajectory, groundtruth, eval::EvalOptions{});
}

// A scenario simulated to a folder, replayed with `estimator` settings appended to its config
// (with_estimator) and evaluated against its ground truth; prints one "[accuracy]" line.
struct ScenarioReplay {
  std::filesystem::path folder;
  daemon::replay::ReplayResult result;
  eval::EvalResult eval;
  double path_m = 0.0;  // ground-truth distance travelled
};

inline ScenarioReplay simulate_replay_evaluate(const sim::Scenario& scenario, double duration_s,
                                               const std::string& estimator);

inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// folder/config.yaml with `estimator: <settings>` appended, as folder/replay.yaml (the settings of
// the rig, like FAST-LIVO2's per-dataset files), unless the generated file already has an
// estimator section. Empty settings: a plain copy.
inline std::filesystem::path with_estimator(const std::filesystem::path& folder,
                                            const std::string& settings) {
  const std::string generated = read_file(folder / "config.yaml");
  const auto out = folder / "replay.yaml";
  std::ofstream f(out);
  f << generated;
  const bool has_estimator =
      generated.rfind("estimator:", 0) == 0 || generated.find("\nestimator:") != std::string::npos;
  if (!settings.empty() && !has_estimator) f << "estimator: " << settings << "\n";
  return out;
}

inline ScenarioReplay simulate_replay_evaluate(const sim::Scenario& scenario, double duration_s,
                                               const std::string& estimator) {
  ScenarioReplay r;
  r.folder = simulate(scenario, duration_s, scenario.name);
  r.result = replay(with_estimator(r.folder, estimator), temp_dir(scenario.name + "-replay"));
  const auto& s = r.result.summary;
  if (s.frames == 0) {
    ADD_FAILURE() << scenario.name << ": no pose; IMU init: " << s.init_status;
    return r;
  }
  r.eval = evaluate(r.result.trajectory, r.folder / "groundtruth.txt");
  r.path_m = r.eval.gt.path_length();
  std::printf(
      "[accuracy] %s: %.0f s, %zu poses, path %.1f m, ATE RMSE %.4f m (%.4f %% of path), max "
      "%.4f m; degenerate frames %llu; frame p50 %.2f ms p99 %.2f ms; %.0f points/scan; IMU "
      "init: %s\n",
      scenario.name.c_str(), duration_s, s.frames, r.path_m, r.eval.ape.rmse,
      100.0 * r.eval.ape.rmse / r.path_m, r.eval.ape.max,
      static_cast<unsigned long long>(s.degenerate_frames), s.frame_ms.p50, s.frame_ms.p99,
      s.used_points.p50, s.init_status.c_str());
  return r;
}

}  // namespace livod::test
