// LIVO against LIO on the simulated camera scenarios (tests/replay/livo_sim.hpp): the visual
// update must never make the odometry worse, must fix the corridor the LiDAR cannot see along,
// must follow the camera's exposure and must survive the camera stopping.

#include <gtest/gtest.h>

#include <cstdlib>

#include "tests/replay/livo_sim.hpp"

namespace livod {
namespace {

bool verbose() {
  return std::getenv("LIVOD_TEST_VERBOSE") != nullptr;
}

void print_frames(const test::LivoSimRun& run) {
  if (!verbose()) return;
  for (const auto& o : run.livo) {
    const auto& v = o.report.vio;
    std::printf(
        "t %.2f kind %d matched %d vio ran %d upd %d cand %d sel %d rej %d patches %d it %d new %d "
        "obs %d rms %.1f -> %.1f tau %.3f map %zu ms %.2f (pyr %.2f sel %.2f upd %.2f map %.2f)\n",
        o.t.seconds(), static_cast<int>(o.report.kind), o.report.matched, v.ran, v.updated,
        v.candidates, v.selected, v.rejected_outlier, v.patches, v.iterations, v.new_points,
        v.new_observations, v.rms_before, v.rms_after, v.inv_exposure, v.map.points,
        v.timings.total_ms, v.timings.pyramid_ms, v.timings.selection_ms, v.timings.update_ms,
        v.timings.map_ms);
  }
}

TEST(LivoSim, RoomHandheldOs1) {
  test::LivoSimOptions options;
  options.duration_s = 12.0;
  const auto run = test::run_livo_sim(sim::make_scenario("room_handheld_os1_64"), options);
  print_frames(run);
  EXPECT_LE(run.livo_ate, run.lio_ate);
}

TEST(LivoSim, CorridorWithCamera) {
  test::LivoSimOptions options;
  options.duration_s = 15.0;
  const auto run =
      test::run_livo_sim(sim::make_scenario("corridor_handheld_os1_64_camera"), options);
  print_frames(run);
  EXPECT_LE(run.livo_ate, 0.05);
}

TEST(LivoSim, OtherCameraScenarios) {
  for (const char* name : {"room_handheld_avia", "street_drone_os1_64"}) {
    test::LivoSimOptions options;
    options.duration_s = 15.0;
    const auto run = test::run_livo_sim(sim::make_scenario(name), options);
    print_frames(run);
    EXPECT_LE(run.livo_ate, run.lio_ate) << name;
  }
}

TEST(LivoSim, ExposureStepsAndCameraLoss) {
  test::LivoSimOptions options;
  options.duration_s = 30.0;
  const auto run =
      test::run_livo_sim(sim::make_scenario("room_handheld_os1_64_camera_faults"), options);
  print_frames(run);
  EXPECT_LE(run.livo_ate, run.lio_ate);
}

}  // namespace
}  // namespace livod
