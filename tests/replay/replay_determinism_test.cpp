// `livod replay` is deterministic: the same recordings give byte-identical trajectory and map
// files, also when the capture is given on the command line (NAME=PATH) under another name, and
// whatever the number of estimator threads (residuals and map refits run on a worker pool).

#include <gtest/gtest.h>

#include "tests/replay/sim_replay.hpp"

namespace livod {
namespace {

TEST(ReplayDeterminism, SameInputSameBytes) {
  const sim::Scenario scenario = sim::make_scenario("room_handheld_mid360");
  const auto folder = test::simulate(scenario, 12.0, "determinism");
  const auto a = test::replay(folder / "config.yaml", test::temp_dir("determinism-a"));
  const auto renamed = folder / "renamed_capture.pcap";
  std::filesystem::copy_file(folder / (scenario.lidars.front().name + ".pcap"), renamed);
  const auto b = test::replay(folder / "config.yaml", test::temp_dir("determinism-b"),
                              {scenario.lidars.front().name + "=" + renamed.string()});

  ASSERT_GT(a.summary.frames, 80U);
  const std::string traj_a = test::read_file(a.trajectory);
  const std::string traj_b = test::read_file(b.trajectory);
  EXPECT_EQ(a.summary.frames, b.summary.frames);
  EXPECT_TRUE(traj_a == traj_b) << "trajectories differ";
  EXPECT_EQ(std::count(traj_a.begin(), traj_a.end(), '\n'), static_cast<long>(a.summary.frames));
  const std::string map_a = test::read_file(a.map);
  EXPECT_GT(a.summary.exported_points, 1000U);
  EXPECT_TRUE(map_a == test::read_file(b.map)) << "maps differ";
  EXPECT_EQ(b.summary.sensors.front().file, renamed.string());

  for (const int threads : {1, 3}) {
    daemon::replay::ReplayOptions options;
    options.out_dir = test::temp_dir("determinism-threads-" + std::to_string(threads));
    options.threads = threads;
    const auto c =
        daemon::replay::run_replay(test::load_clean_config(folder / "config.yaml"), options);
    EXPECT_TRUE(test::read_file(c.trajectory) == traj_a) << threads << " thread(s)";
    EXPECT_TRUE(test::read_file(c.map) == map_a) << threads << " thread(s)";
  }
}

}  // namespace
}  // namespace livod
