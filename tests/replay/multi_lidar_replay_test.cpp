// Several LiDARs feeding one estimator (docs/estimator.md "Several LiDARs"), end to end: the
// simulator's two-LiDAR scenarios (unsynchronised scans, each LiDAR on its own clock) through
// their pcaps, the decoders, the clock domains and the scheduler, evaluated against ground truth
// as `livod eval` does; the same recording is replayed with one LiDAR disabled for comparison.
// Each run prints one "[multi-lidar]" line with ATE and per-frame CPU time.

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
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
// each LiDAR alone on the same recordings (12 s, ~80 m; docs/estimator.md "Several LiDARs"). Both
// building the map, the VLP-16's single-ring lines pass the planarity test as planes whose tilt
// about the line nothing observes, and its points then match those planes: a sparse spinning
// LiDAR beside a denser one is matched only by default (issue 15). Since then three things set
// the pair against the Avia alone on seeds 1-5: the scan downsampler's noise-blind point (stop 30:
// the pair no longer beat the Avia on any seed), the map settings of the LiDAR that builds the
// map (the VLP-16, the estimator LiDAR, had chosen the pose term for the Avia's map: 12.2 -> 7.5
// mm mean against the Avia's 7.2), and the VLP-16's clock fed by scans whose receive times carried
// up to a packet of accumulation (its points 0.1-0.3 ms late against the Avia's: 7.5 -> 6.7 mm),
// and then the matched-only VLP-16's rows gated at 2 sigma instead of 3 (6.7 -> 5.2 mm; seed 2
// was 1.3 % over the Avia before). Issue 10: the pair at least as accurate as the better LiDAR,
// on every seed.
TEST(MultiLidarReplay, Vlp16PlusAviaStreetIsAtLeastAsAccurateAsTheAvia) {
  const sim::Scenario scenario = sim::make_scenario("street_vehicle_vlp16_avia");
  if (!test::scenario_runnable(scenario)) GTEST_SKIP() << "VLP-16 or Avia not simulated";
  double pair_sum = 0.0;
  double avia_sum = 0.0;
  constexpr std::uint64_t kSeeds = 5;
  for (std::uint64_t seed = 1; seed <= kSeeds; ++seed) {
    const std::string tag = "vlp16-avia-" + std::to_string(seed);
    const auto folder = test::simulate(scenario, 12.0, tag, seed);
    // The configuration `livod sim` wrote, as is: the VLP-16 matched only by default.
    const LidarRun pair = replay_with(folder, tag + "-both");
    const LidarRun avia = replay_with(folder, tag + "-avia", {"vlp16"});
    EXPECT_EQ(pair.summary.counters.scans_late, 0u) << seed;
    EXPECT_LE(pair.ate_m, avia.ate_m) << seed;
    pair_sum += pair.ate_m;
    avia_sum += avia.ate_m;
    if (seed != 1) continue;
    // Seed 1: against the VLP-16 alone, and with both building the map.
    const LidarRun both_build =
        replay_with(folder, tag + "-both-build-map", {}, {{"vlp16", "lio: {build_map: true}"}});
    const LidarRun vlp16 = replay_with(folder, tag + "-vlp16", {"avia"});
    EXPECT_GT(pair.frames, vlp16.frames * 18 / 10);
    EXPECT_GT(both_build.frames, vlp16.frames * 18 / 10);
    EXPECT_EQ(both_build.summary.counters.scans_late, 0u);
    EXPECT_LT(pair.ate_m, 0.5 * vlp16.ate_m);
    // Both building the map: better than the weaker LiDAR and within the street target
    // (replay_accuracy_test: 0.05 % of ~80 m); on the realistic street its self-built line
    // planes cost the pair twice the Avia's error.
    EXPECT_LE(both_build.ate_m, std::max(vlp16.ate_m, avia.ate_m));
    EXPECT_LT(both_build.ate_m, 0.04);
  }
  std::printf(
      "[multi-lidar] VLP-16 + Avia street, seeds 1-%llu: mean ATE %.4f m (pair) against "
      "%.4f m (Avia alone)\n",
      static_cast<unsigned long long>(kSeeds), pair_sum / kSeeds, avia_sum / kSeeds);
  EXPECT_LE(pair_sum, avia_sum);
}

// Two VLP-16s on the roof corners, tilted 10 deg outward, on their own clocks, the CAN IMU as the
// body: the street vehicle of street_vehicle_vlp16 with a second VLP-16. The simulator spins both
// from the same phase, as two VLP-16s phase-locked to a PPS do, so their scans end together: a
// group of two whole scans, then one of a few points. Each builds the map with its model's
// viewpoint gate (a gate per LiDAR: the same view inserted scan after scan bends the map), and
// the point budget counts per scan period (without that the cell followed the few points down and
// the whole scans went in with 36 000 points). Issue 10: the pair at least as accurate as the
// better VLP-16 alone.
TEST(MultiLidarReplay, PhaseLockedVlp16PairIsMoreAccurateThanEitherAlone) {
  sim::Scenario scenario = sim::make_scenario("street_vehicle_vlp16");
  if (!test::scenario_runnable(scenario)) GTEST_SKIP() << "VLP-16 not simulated";
  ASSERT_EQ(scenario.lidars.size(), 1u);
  sim::LidarMount left = scenario.lidars[0];
  sim::LidarMount right = left;
  left.name = "left";
  right.name = "right";
  const Eigen::Matrix3d R_level = left.T_body_sensor.linear();
  left.T_body_sensor.linear() =
      Eigen::AngleAxisd(-10.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()) * R_level;
  right.T_body_sensor.linear() =
      Eigen::AngleAxisd(10.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()) * R_level;
  left.T_body_sensor.translation().y() = 0.6;
  right.T_body_sensor.translation().y() = -0.6;
  right.clock.offset_s += 500.04;
  right.clock.skew_ppm = -20.0;
  scenario.lidars = {left, right};
  scenario.name = "street_vehicle_dual_vlp16";
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    const std::string tag = "dual-vlp16-" + std::to_string(seed);
    const auto folder = test::simulate(scenario, 20.0, tag, seed);
    const LidarRun pair = replay_with(folder, tag + "-both");
    const LidarRun left_alone = replay_with(folder, tag + "-left", {"right"});
    const LidarRun right_alone = replay_with(folder, tag + "-right", {"left"});
    EXPECT_EQ(pair.summary.counters.scans_late, 0u) << seed;
    // Each LiDAR's gate holds back some of its scans, as the one VLP-16's does alone.
    EXPECT_GT(pair.summary.counters.scans_not_mapped, 0u) << seed;
    EXPECT_GT(left_alone.summary.counters.scans_not_mapped, 0u) << seed;
    // About two scans' worth in the groups of whole scans (budget 8 000 a scan), half the groups
    // hold a few points; 36 000 points went into the whole-scan groups before.
    EXPECT_LT(pair.summary.used_points.p95, 2.5 * 8000) << seed;
    EXPECT_LT(pair.summary.used_points.p50, 100) << seed;
    EXPECT_LE(pair.ate_m, std::min(left_alone.ate_m, right_alone.ate_m)) << seed;
  }
}

// The corridor with side rooms: the forward Avia sees uniform walls, floor and ceiling, and faces
// along x only as slivers through the doorways; the Avia looking left sees into the rooms. Pooled
// over seeds 1-3: under earlier defaults one seed alone showed the forward Avia degenerate on 3 %
// of its frames only. Measured with the current defaults: 10.6 % of the pair's frames (33-34 of
// ~315 per seed) against 24.5 % of the forward Avia's alone - the sideways LiDAR halves the
// share of degenerate frames, which is what issue 10 asks.
TEST(MultiLidarReplay, SidewaysLidarConstrainsTheCorridor) {
  const sim::Scenario scenario = sim::make_scenario("corridor_side_rooms_dual_avia");
  if (!test::scenario_runnable(scenario)) GTEST_SKIP() << "Avia not simulated";
  std::uint64_t both_degenerate = 0;
  std::uint64_t both_frames = 0;
  std::uint64_t forward_degenerate = 0;
  std::uint64_t forward_frames = 0;
  double both_ate = 0.0;
  double forward_ate = 0.0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const std::string tag = "corridor-dual-avia-" + std::to_string(seed);
    const auto folder = test::simulate(scenario, 16.0, tag, seed);
    const LidarRun both = replay_with(folder, tag + "-both");
    const LidarRun forward = replay_with(folder, tag + "-forward", {"side"});
    both_degenerate += both.degenerate;
    both_frames += both.frames;
    forward_degenerate += forward.degenerate;
    forward_frames += forward.frames;
    both_ate += both.ate_m / 3.0;
    forward_ate += forward.ate_m / 3.0;
  }
  ASSERT_GT(both_frames, 0u);
  ASSERT_GT(forward_frames, 0u);
  const double both_share = static_cast<double>(both_degenerate) / static_cast<double>(both_frames);
  const double forward_share =
      static_cast<double>(forward_degenerate) / static_cast<double>(forward_frames);
  std::printf(
      "[multi-lidar] corridor seeds 1-3: degenerate %.1f %% (pair) against %.1f %% "
      "(forward alone); mean ATE %.4f m against %.4f m\n",
      100.0 * both_share, 100.0 * forward_share, both_ate, forward_ate);
  EXPECT_GT(forward_share, 0.12);  // the forward LiDAR alone: degenerate in the plain stretches
  EXPECT_LT(both_share, 0.6 * forward_share);
  // With the Avia's map points carrying their sensor noise only (lio.map_pose_covariance false,
  // its model's default since issue 15) both improved, the single LiDAR more (pair 7.9 / 8.2 /
  // 7.0 mm, forward alone 5.1 / 5.1 / 5.8: 1.43x). The side Avia fills a near wall's voxels with
  // 50 points in one or two scans, and a plane froze on them; with planes refining on up to 500
  // points (lio.max_points_num, the daemon's default since) the pair is 6.1 / 6.1 / 6.0 mm against
  // 4.9 / 5.3 / 6.3 (1.11x; docs/estimator.md "Corridor"); with the noise-blind downsampling
  // (stop 30) 6.3 / 5.4 / 6.7 against 5.0 / 4.3 / 6.2 mm (1.17x). Issue 10 asks for <= 1x: not
  // met yet.
  EXPECT_LE(both_ate, 1.25 * forward_ate);
  EXPECT_LT(both_ate, 0.01);
}

}  // namespace
}  // namespace livod
