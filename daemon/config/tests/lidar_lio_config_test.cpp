// A LiDAR's own point model (`lio:` on a LiDAR; docs/configuration.md): read with estimator.lio's
// ranges, defaulting to estimator.lio's values, refused on other sensors, at least one LiDAR
// building the map, and shown by check-config's summary.

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>

#include "daemon/config/estimator_defaults.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/config/summary.hpp"
#include "daemon/config/tests/config_test_support.hpp"

namespace livod::daemon {
namespace {

using test::dump;
using test::load;

// A roof VLP-16 and a bumper Avia with an Xsens serial IMU as the body; `vlp16` and `avia` are
// extra lines of each LiDAR, `imu` of the IMU, `tail` is appended.
std::string two_lidars(const std::string& vlp16, const std::string& avia = "",
                       const std::string& imu = "", const std::string& tail = "") {
  return "body_frame: imu\nsensors:\n"
         "  - name: vlp16\n    driver: velodyne\n    model: VLP-16\n    source: {udp: {}}\n"
         "    extrinsic: {translation: [0.1, 0, 0.35], rotation: {rpy_deg: [0, 0, 0]}}\n" +
         vlp16 +
         "  - name: avia\n    driver: livox_sdk1\n    model: AVIA\n    source: {udp: {}}\n"
         "    imu: {enabled: false}\n"
         "    extrinsic: {translation: [1.8, 0, -0.9], rotation: {rpy_deg: [0, 0, 0]}}\n" +
         avia +
         "  - name: imu\n    driver: serial_imu\n    source: {device: {path: /dev/ttyUSB0}}\n"
         "    serial: {protocol: xsens_mtdata2}\n" +
         imu + tail;
}

TEST(LidarLioConfig, UnsetValuesAreTheEstimatorsAndSetOnesAreRead) {
  const auto result = load(two_lidars("    lio: {dept_err: 0.03, build_map: false}\n", "", "",
                                      "estimator: {lio: {dept_err: 0.015, beam_err_deg: 0.1}}\n"));
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  const SensorConfig& vlp16 = result.config.sensors.at(0);
  const SensorConfig& avia = result.config.sensors.at(1);
  ASSERT_TRUE(vlp16.lio.dept_err.has_value());
  EXPECT_DOUBLE_EQ(*vlp16.lio.dept_err, 0.03);
  EXPECT_FALSE(vlp16.lio.beam_err_deg.has_value());
  EXPECT_FALSE(vlp16.lio.build_map);
  EXPECT_FALSE(avia.lio.dept_err.has_value());
  EXPECT_TRUE(avia.lio.build_map);
  // The summary gives every LiDAR's effective values and where they come from.
  const std::string summary = summarize_config(result.config);
  EXPECT_NE(summary.find("point noise: range 0.03 m, bearing 0.1 deg (estimator.lio), one point "
                         "in 1 (estimator.lio), matched only (does not build the map)"),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find("point noise: range 0.015 m (estimator.lio), bearing 0.1 deg "
                         "(estimator.lio), one point in 1 (AVIA default), builds the map"),
            std::string::npos)
      << summary;
}

// Without an estimator section every LiDAR's point model follows its own model: the Avia beside
// the VLP-16 (the estimator's LiDAR) gets the Avia's noise, not the VLP-16's; a value in its own
// lio: or in estimator.lio still wins.
TEST(LidarLioConfig, EachLidarGetsItsOwnModelsDefaults) {
  const auto facts_vlp16 = lidar_model_facts("VLP-16");
  const auto facts_avia = lidar_model_facts("AVIA");
  ASSERT_TRUE(facts_vlp16 && facts_avia);
  estimator::EstimatorParams vlp16_params;
  estimator_settings_for(facts_vlp16, "VLP-16", {}, vlp16_params);
  estimator::EstimatorParams avia_params;
  estimator_settings_for(facts_avia, "AVIA", {}, avia_params);
  ASSERT_NE(vlp16_params.lio.beam_err_deg, avia_params.lio.beam_err_deg);  // else no test

  const auto plain = load(two_lidars(""));
  ASSERT_TRUE(plain.problems.empty()) << dump(plain);
  const SensorConfig& vlp16 = plain.config.sensors.at(0);
  const SensorConfig& avia = plain.config.sensors.at(1);
  EXPECT_DOUBLE_EQ(plain.config.estimator.lio.beam_err_deg, vlp16_params.lio.beam_err_deg);
  EXPECT_FALSE(vlp16.lio.beam_err_deg.has_value());  // the estimator's LiDAR: estimator.lio
  ASSERT_TRUE(avia.lio.beam_err_deg && avia.lio.dept_err && avia.lio.point_filter_num);
  EXPECT_DOUBLE_EQ(*avia.lio.beam_err_deg, avia_params.lio.beam_err_deg);
  EXPECT_DOUBLE_EQ(*avia.lio.dept_err, avia_params.lio.dept_err);
  EXPECT_EQ(*avia.lio.point_filter_num, avia_params.lio.point_filter_num);
  EXPECT_NE(summarize_config(plain.config).find("(AVIA default)"), std::string::npos)
      << summarize_config(plain.config);

  // Its own lio: wins for that key; estimator.lio wins over the model for every LiDAR.
  const auto set = load(
      two_lidars("", "    lio: {beam_err_deg: 0.3}\n", "", "estimator: {lio: {dept_err: 0.04}}\n"));
  ASSERT_TRUE(set.problems.empty()) << dump(set);
  const SensorConfig& avia2 = set.config.sensors.at(1);
  EXPECT_DOUBLE_EQ(*avia2.lio.beam_err_deg, 0.3);
  EXPECT_FALSE(avia2.lio.dept_err.has_value());  // estimator.lio's 0.04
  EXPECT_FALSE(avia2.lio_from_model.contains("beam_err_deg"));
  EXPECT_FALSE(avia2.lio_from_model.contains("dept_err"));
  EXPECT_TRUE(avia2.lio_from_model.contains("point_filter_num"));
}

TEST(LidarLioConfig, EveryProblemIsListed) {
  // Out of range, an unknown key and a wrong type: each one reported.
  const auto result = load(
      two_lidars("    lio: {dept_err: 0, beam_err_deg: 9, build_map: maybe, range_sigma: 0.1}\n"));
  EXPECT_NE(test::find_problem(result, ProblemKind::out_of_range, "sensors[0].lio.dept_err"),
            nullptr)
      << dump(result);
  EXPECT_NE(test::find_problem(result, ProblemKind::out_of_range, "sensors[0].lio.beam_err_deg"),
            nullptr)
      << dump(result);
  EXPECT_NE(test::find_problem(result, ProblemKind::wrong_type, "sensors[0].lio.build_map"),
            nullptr)
      << dump(result);
  EXPECT_NE(test::find_problem(result, ProblemKind::unknown_key, "sensors[0].lio.range_sigma"),
            nullptr)
      << dump(result);
  EXPECT_EQ(result.problems.size(), 4u) << dump(result);
}

TEST(LidarLioConfig, OnlyLidarsTakeIt) {
  const auto result = load(two_lidars("", "", "    lio: {dept_err: 0.02}\n"));
  EXPECT_EQ(result.problems.size(), 1u) << dump(result);
  const ConfigProblem* p = test::find_problem(result, ProblemKind::inconsistent, "sensors[2].lio");
  ASSERT_NE(p, nullptr) << dump(result);
  EXPECT_NE(p->message.find("LiDARs"), std::string::npos) << p->message;
}

TEST(LidarLioConfig, SomeEnabledLidarMustBuildTheMap) {
  // Both matched only: each is named.
  const auto none =
      load(two_lidars("    lio: {build_map: false}\n", "    lio: {build_map: false}\n"));
  EXPECT_EQ(none.problems.size(), 2u) << dump(none);
  EXPECT_NE(test::find_problem(none, ProblemKind::inconsistent, "sensors[0].lio.build_map"),
            nullptr)
      << dump(none);
  EXPECT_NE(test::find_problem(none, ProblemKind::inconsistent, "sensors[1].lio.build_map"),
            nullptr)
      << dump(none);
  // The one that builds it disabled: the same.
  const auto disabled = load(two_lidars("    lio: {build_map: false}\n", "    enabled: false\n"));
  EXPECT_NE(test::find_problem(disabled, ProblemKind::inconsistent, "sensors[0].lio.build_map"),
            nullptr)
      << dump(disabled);
  // One building it is enough.
  const auto one = load(two_lidars("    lio: {build_map: false}\n"));
  EXPECT_TRUE(one.problems.empty()) << dump(one);
}

// The VLP-16's 16 rings beside the Avia: matched only unless its lio: says otherwise
// (apply_estimator_defaults; measured in MultiLidarReplay.Vlp16PlusAviaStreetBeatsBothLidarsAlone).
TEST(LidarLioConfig, SparseLidarBesideADenserOneIsMatchedOnlyByDefault) {
  const auto pair = load(two_lidars(""));
  ASSERT_TRUE(pair.problems.empty()) << dump(pair);
  EXPECT_FALSE(pair.config.sensors.at(0).lio.build_map);
  EXPECT_TRUE(pair.config.sensors.at(0).lio_from_model.contains("build_map"));
  EXPECT_TRUE(pair.config.sensors.at(1).lio.build_map);
  EXPECT_FALSE(pair.config.sensors.at(1).lio_from_model.contains("build_map"));
  const std::string summary = summarize_config(pair.config);
  EXPECT_NE(summary.find("matched only (does not build the map) (VLP-16 default: sparse rings "
                         "beside a denser LiDAR)"),
            std::string::npos)
      << summary;

  // Its own lio: wins.
  const auto told = load(two_lidars("    lio: {build_map: true}\n"));
  ASSERT_TRUE(told.problems.empty()) << dump(told);
  EXPECT_TRUE(told.config.sensors.at(0).lio.build_map);
  EXPECT_FALSE(told.config.sensors.at(0).lio_from_model.contains("build_map"));

  // No denser LiDAR building the map (the Avia disabled, or matched only itself): the VLP-16
  // builds it.
  for (const char* avia : {"    enabled: false\n", "    lio: {build_map: false}\n"}) {
    const auto alone = load(two_lidars("", avia));
    ASSERT_TRUE(alone.problems.empty()) << dump(alone);
    EXPECT_TRUE(alone.config.sensors.at(0).lio.build_map) << avia;
    EXPECT_FALSE(alone.config.sensors.at(0).lio_from_model.contains("build_map")) << avia;
  }
}

// The VLP-16 is the estimator LiDAR (the first one) but matched only: how the map is built follows
// the Avia that builds it (the street pair: 7.5 mm mean over seeds 1-5 so, 12.2 mm with the
// VLP-16's pose term; docs/estimator.md "Several LiDARs").
TEST(LidarLioConfig, TheMapSettingsFollowTheLidarThatBuildsTheMap) {
  const auto choice = [](const LivodConfig& c, const std::string& key) {
    const auto it = std::find_if(c.estimator_choices.begin(), c.estimator_choices.end(),
                                 [&](const EstimatorChoice& e) { return e.key == key; });
    return it == c.estimator_choices.end() ? EstimatorChoice{} : *it;
  };
  const auto pair = load(two_lidars(""));
  ASSERT_TRUE(pair.problems.empty()) << dump(pair);
  EXPECT_FALSE(pair.config.estimator.lio.map_pose_covariance);
  EXPECT_DOUBLE_EQ(pair.config.estimator.lio.min_plane_spread_ratio, 0.0);
  const EstimatorChoice pose = choice(pair.config, "lio.map_pose_covariance");
  EXPECT_EQ(pose.value, "false");
  EXPECT_NE(pose.reason.find("AVIA scans a dense rosette"), std::string::npos) << pose.reason;
  EXPECT_NE(pose.reason.find("(avia builds the map; vlp16 is matched only)"), std::string::npos)
      << pose.reason;

  // The VLP-16 building the map itself (told so, or with the Avia disabled): its own choice.
  const std::pair<std::string, std::string> builds_own_map[] = {
      {"    lio: {build_map: true}\n", ""}, {"", "    enabled: false\n"}};
  for (const auto& [vlp16, avia] : builds_own_map) {
    const auto own = load(two_lidars(vlp16, avia));
    ASSERT_TRUE(own.problems.empty()) << dump(own);
    EXPECT_TRUE(own.config.estimator.lio.map_pose_covariance) << vlp16 << avia;
    EXPECT_NE(choice(own.config, "lio.map_pose_covariance").reason.find("VLP-16's 16 rings"),
              std::string::npos);
  }

  // A value of the file wins.
  const auto told = load(two_lidars("", "", "", "estimator: {lio: {map_pose_covariance: true}}\n"));
  ASSERT_TRUE(told.problems.empty()) << dump(told);
  EXPECT_TRUE(told.config.estimator.lio.map_pose_covariance);
  EXPECT_EQ(choice(told.config, "lio.map_pose_covariance").reason, "set in the configuration");
}

// A matched-only LiDAR's rows are gated at 2 sigma (the map's gate is 3): the VLP-16 beside the
// Avia by default, any LiDAR told build_map: false too; a sigma_num of the file wins (its own
// lio: or estimator.lio), and a LiDAR that builds the map keeps the map's gate.
TEST(LidarLioConfig, AMatchedOnlyLidarIsGatedTighter) {
  const auto pair = load(two_lidars(""));
  ASSERT_TRUE(pair.problems.empty()) << dump(pair);
  const SensorConfig& vlp16 = pair.config.sensors.at(0);
  ASSERT_TRUE(vlp16.lio.sigma_num.has_value());
  EXPECT_DOUBLE_EQ(*vlp16.lio.sigma_num, kMatchedOnlyGateSigmas);
  EXPECT_TRUE(vlp16.lio_from_model.contains("sigma_num"));
  EXPECT_FALSE(pair.config.sensors.at(1).lio.sigma_num.has_value());
  EXPECT_NE(summarize_config(pair.config).find("gate 2 sigma (matched-only default)"),
            std::string::npos);

  const auto avia_told = load(two_lidars("", "    lio: {build_map: false}\n"));
  ASSERT_TRUE(avia_told.problems.empty()) << dump(avia_told);
  // The VLP-16 builds the map then (no denser LiDAR does); the Avia is matched only.
  EXPECT_FALSE(avia_told.config.sensors.at(0).lio.sigma_num.has_value());
  ASSERT_TRUE(avia_told.config.sensors.at(1).lio.sigma_num.has_value());
  EXPECT_DOUBLE_EQ(*avia_told.config.sensors.at(1).lio.sigma_num, kMatchedOnlyGateSigmas);

  const auto own = load(two_lidars("    lio: {sigma_num: 2.5}\n"));
  ASSERT_TRUE(own.problems.empty()) << dump(own);
  EXPECT_DOUBLE_EQ(*own.config.sensors.at(0).lio.sigma_num, 2.5);
  EXPECT_FALSE(own.config.sensors.at(0).lio_from_model.contains("sigma_num"));

  const auto estimator = load(two_lidars("", "", "", "estimator: {lio: {sigma_num: 3}}\n"));
  ASSERT_TRUE(estimator.problems.empty()) << dump(estimator);
  EXPECT_FALSE(estimator.config.sensors.at(0).lio.sigma_num.has_value());

  const auto bad = load_config_from_string(two_lidars("    lio: {sigma_num: 0}\n"), "test.yaml");
  EXPECT_FALSE(bad.problems.empty());
}

// Inserting scans from new viewpoints only (lio.map_min_move_m) follows the LiDARs that build the
// map: beside the Avia the matched-only VLP-16's gate is dropped (the Avia's view builds the map,
// and an Avia inserts every scan), the VLP-16 building the map keeps its own, and a value of the
// file is taken with several LiDARs too (each LiDAR has its own gate in the estimator).
TEST(LidarLioConfig, TheViewpointGateFollowsTheLidarsThatBuildTheMap) {
  const auto choice = [](const LivodConfig& c) {
    const auto it = std::find_if(c.estimator_choices.begin(), c.estimator_choices.end(),
                                 [](const auto& e) { return e.key == "lio.map_min_move_m"; });
    return it == c.estimator_choices.end() ? EstimatorChoice{} : *it;
  };
  const auto pair = load(two_lidars(""));
  ASSERT_TRUE(pair.problems.empty()) << dump(pair);
  EXPECT_DOUBLE_EQ(pair.config.estimator.lio.map_min_move_m, 0.0);
  EXPECT_EQ(choice(pair.config).value, "0");
  EXPECT_NE(choice(pair.config).reason.find("(avia builds the map; vlp16 is matched only)"),
            std::string::npos)
      << choice(pair.config).reason;

  // The VLP-16 building the map, beside the Avia or alone: its 16 rings' gate.
  const std::pair<std::string, std::string> builds_own_map[] = {
      {"    lio: {build_map: true}\n", ""}, {"", "    enabled: false\n"}};
  for (const auto& [vlp16, avia] : builds_own_map) {
    const auto own = load(two_lidars(vlp16, avia));
    ASSERT_TRUE(own.problems.empty()) << dump(own);
    EXPECT_DOUBLE_EQ(own.config.estimator.lio.map_min_move_m, kViewpointMoveM) << vlp16 << avia;
    EXPECT_NE(choice(own.config).reason.find("VLP-16's 16 rings"), std::string::npos);
  }

  // Set in the file with two enabled LiDARs: taken, no problem.
  const auto set = load_config_from_string(
      two_lidars("", "", "", "estimator: {lio: {map_min_move_m: 0.25}}\n"), "test.yaml");
  EXPECT_TRUE(set.problems.empty()) << dump(set);
  EXPECT_DOUBLE_EQ(set.config.estimator.lio.map_min_move_m, 0.25);
  EXPECT_EQ(choice(set.config).reason, "set in the configuration");
}

}  // namespace
}  // namespace livod::daemon
