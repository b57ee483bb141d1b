// Several LiDARs feeding one estimator (docs/estimator.md "Several LiDARs"), end to end: the
// simulator's two-LiDAR scenarios (unsynchronised scans, each LiDAR on its own clock) through
// their pcaps, the decoders, the clock domains and the scheduler, evaluated against ground truth
// as `livod eval` does; the same recording is replayed with one LiDAR disabled for comparison.
// Each run prints one "[multi-lidar]" line with ATE and per-frame CPU time.

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "tests/replay/sim_replay.hpp"

namespace livod {
namespace {

struct LidarRun {
  double ate_m = 0.0;
  std::size_t frames = 0;
  std::uint64_t degenerate = 0;
  daemon::replay::ReplaySummary summary;
};

// The folder's config.yaml with `disabled` sensors switched off (enabled: false) and `settings`
// added to the named sensors (e.g. {"vlp16", "lio: {build_map: false}"}), replayed and evaluated
// against the folder's ground truth.
LidarRun replay_with(const std::filesystem::path& folder, const std::string& label,
                     const std::vector<std::string>& disabled = {},
                     const std::vector<std::pair<std::string, std::string>>& settings = {}) {
  std::string config = test::read_file(folder / "config.yaml");
  const auto add_to = [&](const std::string& name, const std::string& line) {
    const std::string entry = "  - name: " + name + "\n";
    const auto at = config.find(entry);
    EXPECT_NE(at, std::string::npos) << name;
    if (at != std::string::npos) config.insert(at + entry.size(), "    " + line + "\n");
  };
  for (const auto& name : disabled) add_to(name, "enabled: false");
  for (const auto& [name, line] : settings) add_to(name, line);
  const auto path = folder / (label + ".yaml");
  std::ofstream(path) << config;
  const auto result = test::replay(path, test::temp_dir(label + "-replay"));
  LidarRun r;
  r.summary = result.summary;
  r.frames = result.summary.frames;
  r.degenerate = result.summary.degenerate_frames;
  if (r.frames == 0) {
    ADD_FAILURE() << label << ": no pose; " << result.summary.init_status;
    return r;
  }
  r.ate_m = test::evaluate(result.trajectory, folder / "groundtruth.txt").ape.rmse;
  const auto& s = result.summary;
  std::printf(
      "[multi-lidar] %s: %zu poses, ATE RMSE %.4f m, degenerate frames %llu (%.0f %%), frame "
      "CPU p50 %.2f ms p99 %.2f ms, %.0f points/frame, scans in %llu, late scans %llu, late "
      "points %llu\n",
      label.c_str(), s.frames, r.ate_m, static_cast<unsigned long long>(r.degenerate),
      100.0 * static_cast<double>(r.degenerate) / static_cast<double>(s.frames), s.frame_cpu_ms.p50,
      s.frame_cpu_ms.p99, s.used_points.p50, static_cast<unsigned long long>(s.counters.scans_in),
      static_cast<unsigned long long>(s.counters.scans_late),
      static_cast<unsigned long long>(s.counters.points_late));
  return r;
}

// Two Mid-360s back to back, scans cut 30 ms apart; the body is the front one's IMU, so the rear
// one alone cannot be replayed (its IMU is off): the pair against the front one alone.
TEST(MultiLidarReplay, DualMid360RoomIsAtLeastAsAccurateAsTheFrontOneAlone) {
  const sim::Scenario scenario = sim::make_scenario("room_dual_mid360");
  if (!test::scenario_runnable(scenario)) GTEST_SKIP() << "Mid-360 not simulated";
  const auto folder = test::simulate(scenario, 14.0, "dual-mid360");
  const LidarRun both = replay_with(folder, "dual-mid360-both");
  const LidarRun front = replay_with(folder, "dual-mid360-front", {"rear"});
  // Every scan end of either LiDAR is an update: about twice the frames of one LiDAR.
  EXPECT_GT(both.frames, front.frames * 18 / 10);
  EXPECT_EQ(both.summary.counters.scans_out_of_order, 0u);
  EXPECT_EQ(both.summary.counters.scans_late, 0u);
  EXPECT_LE(both.ate_m, front.ate_m);
  EXPECT_LT(both.ate_m, 0.01);  // the single-LiDAR room target (replay_accuracy_test)
}

// A roof VLP-16 and a bumper Avia on different clocks, the CAN IMU as the body: the pair against
// each LiDAR alone on the same recording (12 s, ~80 m; docs/estimator.md "Several LiDARs"). With
// every LiDAR building the map (the default) the pair is far better than the VLP-16 alone but a
// little worse than the Avia alone (5.3 against 4.7 mm, and so on five seeds out of five): the
// VLP-16's rings, 2 deg apart, cut most voxels in single-ring lines, which pass the planarity test
// as planes whose tilt about the line nothing observes, and its points then match those planes
// (their residuals were 4x the Avia's in the sectors only the VLP-16 sees). With the VLP-16
// matched against the map but not building it (`lio: {build_map: false}`) the pair is better than
// either LiDAR alone.
TEST(MultiLidarReplay, Vlp16PlusAviaStreetBeatsBothLidarsAlone) {
  const sim::Scenario scenario = sim::make_scenario("street_vehicle_vlp16_avia");
  if (!test::scenario_runnable(scenario)) GTEST_SKIP() << "VLP-16 or Avia not simulated";
  const auto folder = test::simulate(scenario, 12.0, "vlp16-avia");
  const LidarRun both = replay_with(folder, "vlp16-avia-both");
  const LidarRun matched = replay_with(folder, "vlp16-avia-both-vlp16-matched", {},
                                       {{"vlp16", "lio: {build_map: false}"}});
  const LidarRun vlp16 = replay_with(folder, "vlp16-avia-vlp16", {"avia"});
  const LidarRun avia = replay_with(folder, "vlp16-avia-avia", {"vlp16"});
  EXPECT_GT(both.frames, vlp16.frames * 18 / 10);
  EXPECT_GT(matched.frames, vlp16.frames * 18 / 10);
  EXPECT_EQ(both.summary.counters.scans_late, 0u);
  EXPECT_EQ(matched.summary.counters.scans_late, 0u);
  // The default: better than the weaker LiDAR, within 1.5x of the better one.
  EXPECT_LE(both.ate_m, std::max(vlp16.ate_m, avia.ate_m));
  EXPECT_LE(both.ate_m, 1.5 * std::min(vlp16.ate_m, avia.ate_m));
  // The VLP-16 matched only: better than each LiDAR alone (issue 10).
  EXPECT_LE(matched.ate_m, std::min(vlp16.ate_m, avia.ate_m));
}

// The corridor with side rooms: the forward Avia sees uniform walls, floor and ceiling, and faces
// along x only as slivers through the doorways; the Avia looking left sees into the rooms. With
// it, half as many frames are degenerate (measured, 16 s: 11 % against 23 %). The trajectory is
// not more accurate on this seed (ATE 6.6 mm against 6.2 mm) and over seeds it goes either way
// (seeds 1-5: pair 6.6, 4.7, 10.3, 6.4, 7.8 mm; forward alone 6.2, 7.4, 5.9, 7.9, 12.6 mm): the
// slivers keep the forward LiDAR alone from drifting much, so the check on accuracy is that the
// pair stays comparable.
TEST(MultiLidarReplay, SidewaysLidarConstrainsTheCorridor) {
  const sim::Scenario scenario = sim::make_scenario("corridor_side_rooms_dual_avia");
  if (!test::scenario_runnable(scenario)) GTEST_SKIP() << "Avia not simulated";
  const auto folder = test::simulate(scenario, 16.0, "corridor-dual-avia");
  const LidarRun both = replay_with(folder, "corridor-dual-avia-both");
  const LidarRun forward = replay_with(folder, "corridor-dual-avia-forward", {"side"});
  const double both_share = static_cast<double>(both.degenerate) / static_cast<double>(both.frames);
  const double forward_share =
      static_cast<double>(forward.degenerate) / static_cast<double>(forward.frames);
  EXPECT_GT(forward_share, 0.15);  // the forward LiDAR alone: degenerate in the plain stretches
  EXPECT_LT(both_share, 0.6 * forward_share);
  EXPECT_LE(both.ate_m, 1.25 * forward.ate_m);
}

}  // namespace
}  // namespace livod
