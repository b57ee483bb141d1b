// Accuracy of `livod replay` on the simulator's scenarios, through the real files: the scenario
// is written to a folder (captures, config.yaml, groundtruth.txt) exactly as `livod sim` writes
// it, replayed from its config.yaml, and trajectory.txt is evaluated against groundtruth.txt as
// `livod eval` does (SE(3) Umeyama alignment). Thresholds (docs/replay.md): ATE RMSE <= 3 cm on
// the handheld room scenarios, <= 0.05 % of the distance travelled on the street (>= 300 m), and
// the corridor must raise the degeneracy flag. A scenario whose LiDAR model the simulator does not
// have yet is skipped (it runs as soon as simulated_lidar_models() lists the model).
//
// Estimator settings: none. The generated config.yaml has no `estimator:` section, so the daemon
// chooses the point selection and noise model from the LiDAR model (daemon/config/
// estimator_defaults.hpp) - what a user's first run does. Until issue 15 each rig had tuned
// settings here, like FAST-LIVO2's per-dataset files; the defaults now meet the same targets
// (docs/estimator.md, "Defaults per sensor").

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "tests/replay/sim_replay.hpp"

namespace livod {
namespace {

enum class Expectation { kHandheld, kStreet, kDegenerate };

struct AccuracyCase {
  const char* scenario;
  double duration_s;
  Expectation expectation;
  // The daemon's defaults insert a scan into the map only from a new viewpoint
  // (lio.map_min_move_m; the VLP-16 only): without that the realistic VLP-16 street stayed near its
  // start (ATE ~100 m, docs/estimator.md "Map insertion from new viewpoints").
  bool viewpoint_gated = false;
};

constexpr double kHandheldAteM = 0.03;
constexpr double kStreetAteFraction = 0.0005;  // of the distance travelled
constexpr double kStreetMinPathM = 300.0;

void PrintTo(const AccuracyCase& c, std::ostream* os) {
  *os << c.scenario;
}

class ReplayAccuracy : public ::testing::TestWithParam<AccuracyCase> {};

TEST_P(ReplayAccuracy, MeetsTheIssueTargets) {
  const AccuracyCase& c = GetParam();
  sim::Scenario scenario = sim::make_scenario(c.scenario);
  if (!test::scenario_runnable(scenario)) {
    GTEST_SKIP() << c.scenario << ": LiDAR model " << scenario.lidars.front().model
                 << " is not simulated yet";
  }
  const auto run = test::simulate_replay_evaluate(scenario, c.duration_s, "");
  const auto& s = run.result.summary;
  ASSERT_GT(s.frames, 0U);
  const auto& ev = run.eval;
  const double path = run.path_m;
  RecordProperty("ate_rmse_m", std::to_string(ev.ape.rmse));
  RecordProperty("path_m", std::to_string(path));

  // Every scan after initialisation became a pose: none out of order (a packet the simulated
  // link delays past the next scan is dropped by the decoder, not emitted as a scan of its own),
  // none dropped from a full queue.
  EXPECT_EQ(s.counters.scans_out_of_order, 0U);
  EXPECT_EQ(s.counters.scans_queue_overflow, 0U);
  EXPECT_GE(static_cast<double>(s.frames), (c.duration_s - 1.0) / 0.1);
  // The standing start's scans after the first stay out of the map where the gate is on; every
  // scan goes in elsewhere.
  if (c.viewpoint_gated) {
    EXPECT_GT(s.counters.scans_not_mapped, 5U);
  } else {
    EXPECT_EQ(s.counters.scans_not_mapped, 0U);
  }
  switch (c.expectation) {
    case Expectation::kHandheld:
      EXPECT_LE(ev.ape.rmse, kHandheldAteM);
      break;
    case Expectation::kStreet:
      EXPECT_GE(path, kStreetMinPathM);
      EXPECT_LE(ev.ape.rmse, kStreetAteFraction * path);
      break;
    case Expectation::kDegenerate:
      EXPECT_GT(s.degenerate_frames, 0U);
      break;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Scenarios, ReplayAccuracy,
    ::testing::Values(AccuracyCase{"room_handheld_avia", 20.0, Expectation::kHandheld},
                      AccuracyCase{"room_handheld_mid360", 20.0, Expectation::kHandheld},
                      AccuracyCase{"room_handheld_os1_64", 20.0, Expectation::kHandheld},
                      AccuracyCase{"room_aggressive_os1_64", 20.0, Expectation::kHandheld},
                      AccuracyCase{"street_vehicle_vlp16", 36.0, Expectation::kStreet, true},
                      AccuracyCase{"street_vehicle_os1_128", 36.0, Expectation::kStreet},
                      AccuracyCase{"corridor_handheld_os1_64", 15.0, Expectation::kDegenerate}),
    [](const ::testing::TestParamInfo<AccuracyCase>& param_info) {
      return std::string(param_info.param.scenario);
    });

}  // namespace
}  // namespace livod
