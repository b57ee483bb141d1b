// OPEN (issue 15): the VLP-16 street scenario with the simulator's realism fails the street
// accuracy target with the per-model defaults (ATE ~100 m over 324 m: most frames degenerate, the
// estimate stays near the start). Isolated to the range noise that grows towards the detection
// limit (sigma_at_limit_m): the same capture without it gives 22 mm; the estimator's point noise
// model does not grow with range and incidence as the sensor's does (docs/estimator.md, "Known
// limits"). Label "open": left out of the default test run until the estimator handles it; run it
// with `ctest --test-dir build/release -L open`.

#include <gtest/gtest.h>

#include "tests/replay/sim_replay.hpp"

namespace livod {
namespace {

TEST(OpenVlp16RealisticStreet, MeetsTheStreetTarget) {
  const sim::Scenario scenario = sim::make_scenario("street_vehicle_vlp16");
  const auto run = test::simulate_replay_evaluate(scenario, 36.0, "");
  ASSERT_GT(run.result.summary.frames, 0U);
  EXPECT_GE(run.path_m, 300.0);
  EXPECT_LE(run.eval.ape.rmse, 0.0005 * run.path_m);
}

}  // namespace
}  // namespace livod
