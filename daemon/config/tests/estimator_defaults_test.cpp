// The estimator settings that follow the LiDAR model (estimator_defaults.hpp): chosen from the
// model's facts when the file does not set them, never over a value the file sets, and printed
// with their reasons by check-config.

#include "daemon/config/estimator_defaults.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <sstream>

#include "daemon/config/summary.hpp"
#include "daemon/config/tests/config_test_support.hpp"

namespace livod::daemon {
namespace {

using test::dump;
using test::load;

// An Ouster as the body (its internal IMU), like the configurations `livod sim` writes.
std::string ouster_config(const std::string& model, const std::string& estimator = "") {
  std::string yaml = R"(body_frame: os1.imu
sensors:
  - name: os1
    driver: ouster
    model: )" + model +
                     R"(
    source: {udp: {sensor_address: 192.168.1.10}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  if (!estimator.empty()) yaml += "estimator: " + estimator + "\n";
  return yaml;
}

const EstimatorChoice* choice(const LivodConfig& c, const std::string& key) {
  for (const auto& ch : c.estimator_choices) {
    if (ch.key == key) return &ch;
  }
  return nullptr;
}

// estimator_settings_for(model) without a file's keys, on parameters that `prime` set to values
// the choices must overwrite: the parameters it leaves and the value it reports for `key` ("" if
// it reports none).
struct ModelChoice {
  estimator::EstimatorParams params;
  std::string value;
};
ModelChoice choose_for(const char* model, const std::string& key,
                       const std::function<void(estimator::EstimatorParams&)>& prime) {
  ModelChoice r;
  prime(r.params);
  const auto facts = lidar_model_facts(model);
  for (const auto& c : estimator_settings_for(facts, model, {}, r.params)) {
    if (c.key == key) r.value = c.value;
  }
  return r;
}

// The value estimator_settings_for(model) chooses for a number of LioParams, set to 7 first (a
// value every choice overwrites), checked against the value it reports for `key`.
double chosen(const char* model, const std::string& key, double estimator::LioParams::*field) {
  const auto r = choose_for(model, key, [field](auto& p) { p.lio.*field = 7.0; });
  std::ostringstream value;
  value << r.params.lio.*field;
  EXPECT_EQ(r.value, value.str()) << model << " " << key;
  return r.params.lio.*field;
}

// Every model of every family table with a point rate has facts (Hesai, the other Velodynes and
// Livox models included); Ouster's generic "OS" names no beam count, so it has none.
TEST(EstimatorDefaults, EveryModelOfTheFamilyTablesHasItsFacts) {
  for (const char* model : {"OS1-64", "OS1-128", "VLP-16", "HDL-32E", "AVIA", "MID-360",
                            "PANDARXT32", "XT32", "PANDAR40P", "VLS-128", "OS0-32", "HAP"}) {
    const auto facts = lidar_model_facts(model);
    ASSERT_TRUE(facts) << model;
    EXPECT_GT(facts->beams, 0);
    EXPECT_GT(facts->points_per_scan, 1000.0);
    EXPECT_GT(facts->range_sigma_m, 0.0);
    EXPECT_GT(facts->divergence_deg, 0.0);
    EXPECT_FALSE(facts->source.empty());
  }
  EXPECT_FALSE(lidar_model_facts("NO-SUCH-LIDAR"));
  EXPECT_FALSE(lidar_model_facts("OS"));
}

// The Hesai PandarXT-32 (640 k points/s): one point in 2, its datasheet's 1 cm, and
// a divergence its sources do not give, said so.
TEST(EstimatorDefaults, HesaiGetsItsDefaultsFromItsFamilyTable) {
  const auto facts = lidar_model_facts("PandarXT-32");
  ASSERT_TRUE(facts);
  EXPECT_EQ(facts->model, "PANDARXT32");
  EXPECT_EQ(facts->beams, 32);
  EXPECT_DOUBLE_EQ(facts->points_per_scan, 64000.0);
  EXPECT_DOUBLE_EQ(facts->range_sigma_m, 0.01);
  EXPECT_TRUE(facts->divergence_assumed);
  estimator::EstimatorParams params;
  const auto choices = estimator_settings_for(facts, "PANDARXT32", {}, params);
  EXPECT_EQ(params.lio.point_filter_num, 2);
  EXPECT_EQ(params.lio.point_budget, kDefaultPointBudget);
  EXPECT_DOUBLE_EQ(params.lio.dept_err, 0.01);
  EXPECT_DOUBLE_EQ(params.lio.beam_err_deg, 0.5 * kAssumedDivergenceDeg);
  bool assumed = false;
  for (const auto& c : choices) {
    assumed = assumed || (c.key == "lio.beam_err_deg" &&
                          c.reason.find("not in livod's sources") != std::string::npos);
  }
  EXPECT_TRUE(assumed);
}

// A 128-beam Ouster brings 131 k points per scan: one point in 4 and the point
// budget keep a frame real-time; a 16-beam Velodyne keeps every point.
TEST(EstimatorDefaults, PointSelectionFollowsThePointsPerScan) {
  const auto os128 = load(ouster_config("OS1-128"));
  ASSERT_TRUE(os128.ok()) << dump(os128);
  EXPECT_EQ(os128.config.estimator.lio.point_filter_num, 4);
  EXPECT_EQ(os128.config.estimator.lio.point_budget, kDefaultPointBudget);
  const auto os64 = load(ouster_config("OS1-64"));
  ASSERT_TRUE(os64.ok()) << dump(os64);
  EXPECT_EQ(os64.config.estimator.lio.point_filter_num, 2);
  const auto vlp = load(test::minimal_config());
  ASSERT_TRUE(vlp.ok()) << dump(vlp);
  EXPECT_EQ(vlp.config.estimator.lio.point_filter_num, 1);
  EXPECT_EQ(vlp.config.estimator.lio.point_budget, kDefaultPointBudget);
  // The noise model: the datasheet's range noise, half the beam divergence.
  EXPECT_DOUBLE_EQ(os128.config.estimator.lio.dept_err, 0.015);
  EXPECT_DOUBLE_EQ(os128.config.estimator.lio.beam_err_deg, 0.09);
}

TEST(EstimatorDefaults, ExplicitSettingsWin) {
  const auto r = load(ouster_config(
      "OS1-128",
      "{lio: {point_filter_num: 1, point_budget: 0, dept_err: 0.03, beam_err_deg: 0.2, "
      "filter_size_surf: 0.3, map_pose_covariance: true, max_points_num: 50, map_min_move_m: "
      "0.25, min_plane_spread_ratio: 0}}"));
  ASSERT_TRUE(r.ok()) << dump(r);
  const auto& lio = r.config.estimator.lio;
  EXPECT_EQ(lio.point_filter_num, 1);
  EXPECT_EQ(lio.point_budget, 0);
  EXPECT_DOUBLE_EQ(lio.dept_err, 0.03);
  EXPECT_DOUBLE_EQ(lio.beam_err_deg, 0.2);
  EXPECT_DOUBLE_EQ(lio.filter_size_surf, 0.3);
  EXPECT_TRUE(lio.map_pose_covariance);
  EXPECT_EQ(lio.max_points_num, 50);
  EXPECT_DOUBLE_EQ(lio.map_min_move_m, 0.25);
  EXPECT_DOUBLE_EQ(lio.min_plane_spread_ratio, 0.0);
  for (const auto& c : r.config.estimator_choices) {
    EXPECT_EQ(c.reason, "set in the configuration") << c.key;
  }
  // Setting one key leaves the others to the model.
  const auto one = load(ouster_config("OS1-128", "{lio: {dept_err: 0.03}}"));
  ASSERT_TRUE(one.ok()) << dump(one);
  EXPECT_DOUBLE_EQ(one.config.estimator.lio.dept_err, 0.03);
  EXPECT_EQ(one.config.estimator.lio.point_filter_num, 4);
  EXPECT_EQ(one.config.estimator.lio.max_points_num, kDefaultPlanePoints);
}

// The pose uncertainty goes into the map points of spinning LiDARs with fewer than 32 rings only
// (docs/estimator.md "Long drives": the VLP-16 street loses track without it, the 64-ring drive
// tilts with it, Livox rooms are as good or better without it; the 32-ring streets lost track
// without it until the plane spread test, "Lines are not planes").
TEST(EstimatorDefaults, MapPoseCovarianceFollowsTheRings) {
  const auto pose_term = [](const char* model) {
    EXPECT_TRUE(lidar_model_facts(model).has_value()) << model;
    const auto r = choose_for(model, "lio.map_pose_covariance", [](auto& p) {
      p.lio.map_pose_covariance = !p.lio.map_pose_covariance;  // must be overwritten
    });
    EXPECT_EQ(r.value, r.params.lio.map_pose_covariance ? "true" : "false") << model;
    return r.params.lio.map_pose_covariance;
  };
  EXPECT_TRUE(pose_term("VLP-16"));
  EXPECT_FALSE(pose_term("HDL-32E"));
  EXPECT_FALSE(pose_term("PANDARXT32"));
  EXPECT_FALSE(pose_term("OS0-32"));
  EXPECT_FALSE(pose_term("OS1-64"));
  EXPECT_FALSE(pose_term("OS1-128"));
  EXPECT_FALSE(pose_term("AVIA"));
  EXPECT_FALSE(pose_term("MID-360"));
  // The file's value wins.
  const auto set = load(ouster_config("OS1-64", "{lio: {map_pose_covariance: true}}"));
  ASSERT_TRUE(set.ok()) << dump(set);
  EXPECT_TRUE(set.config.estimator.lio.map_pose_covariance);
}

// Lines are not planes (estimator/map/plane.hpp): spinning LiDARs with 32 rings or more, whose
// map points carry their sensor noise only; off for the VLP-16 (too few planes left: its street
// loses track), for Livox (no rings, no gain measured) and without facts (FAST-LIVO2).
TEST(EstimatorDefaults, PlaneSpreadTestFollowsTheRings) {
  const auto spread = [](const char* model) {
    return chosen(model, "lio.min_plane_spread_ratio",
                  &estimator::LioParams::min_plane_spread_ratio);
  };
  for (const char* model : {"HDL-32E", "PANDARXT32", "OS0-32", "OS1-64", "OS1-128"}) {
    EXPECT_DOUBLE_EQ(spread(model), kPlaneSpreadRatio) << model;
  }
  for (const char* model : {"VLP-16", "AVIA", "MID-360"}) {
    EXPECT_DOUBLE_EQ(spread(model), 0.0) << model;
  }
  estimator::EstimatorParams unknown;
  estimator_settings_for(std::nullopt, "XYZ-99", {}, unknown);
  EXPECT_DOUBLE_EQ(unknown.lio.min_plane_spread_ratio, 0.0);
  EXPECT_TRUE(unknown.lio.map_pose_covariance);

  // The pose term set in the file turns the test off, and says why.
  const auto pose = load(ouster_config("OS1-64", "{lio: {map_pose_covariance: true}}"));
  ASSERT_TRUE(pose.ok()) << dump(pose);
  EXPECT_DOUBLE_EQ(pose.config.estimator.lio.min_plane_spread_ratio, 0.0);
  ASSERT_NE(choice(pose.config, "lio.min_plane_spread_ratio"), nullptr);
  EXPECT_NE(choice(pose.config, "lio.min_plane_spread_ratio")->reason.find("map_pose_covariance"),
            std::string::npos);
  // The test set in the file takes the pose term out of the map points, on any model.
  for (const char* model : {"VLP-16", "XYZ-99"}) {
    estimator::EstimatorParams params;
    params.lio.min_plane_spread_ratio = 2.0;
    const auto choices = estimator_settings_for(lidar_model_facts(model), model,
                                                {"lio.min_plane_spread_ratio"}, params);
    EXPECT_FALSE(params.lio.map_pose_covariance) << model;
    EXPECT_DOUBLE_EQ(params.lio.min_plane_spread_ratio, 2.0) << model;
    const auto c = std::find_if(choices.begin(), choices.end(),
                                [](const auto& e) { return e.key == "lio.map_pose_covariance"; });
    ASSERT_NE(c, choices.end()) << model;
    EXPECT_NE(c->reason.find("min_plane_spread_ratio is set"), std::string::npos) << c->reason;
  }
  // Both set against each other: rejected, with the reason.
  const auto both = load(
      ouster_config("OS1-64", "{lio: {map_pose_covariance: true, min_plane_spread_ratio: 4}}"));
  EXPECT_FALSE(both.ok());
  EXPECT_NE(dump(both).find("needs map_pose_covariance: false"), std::string::npos) << dump(both);
}

// Inserting scans from new viewpoints only: the spinning LiDARs with fewer than 32 rings (the
// VLP-16 lost track on the realistic street without it); every scan for the rest and for a model
// without facts (FAST-LIVO2).
TEST(EstimatorDefaults, ViewpointGateFollowsTheRings) {
  const auto min_move = [](const char* model) {
    return chosen(model, "lio.map_min_move_m", &estimator::LioParams::map_min_move_m);
  };
  EXPECT_DOUBLE_EQ(min_move("VLP-16"), kViewpointMoveM);
  for (const char* model :
       {"HDL-32E", "PANDARXT32", "OS0-32", "OS1-64", "OS1-128", "AVIA", "MID-360"}) {
    EXPECT_DOUBLE_EQ(min_move(model), 0.0) << model;
  }
  // No facts: the estimator's own (FAST-LIVO2's), explained.
  estimator::EstimatorParams unknown;
  const auto choices = estimator_settings_for(std::nullopt, "XYZ-99", {}, unknown);
  EXPECT_DOUBLE_EQ(unknown.lio.map_min_move_m, 0.0);
  EXPECT_TRUE(std::any_of(choices.begin(), choices.end(),
                          [](const auto& e) { return e.key == "lio.map_min_move_m"; }));
  // Through the configuration: the VLP-16 alone gets it, the file's value wins.
  const std::string alone = test::minimal_config();  // a VLP-16 and a serial IMU
  const auto gated = load(alone);
  ASSERT_TRUE(gated.problems.empty()) << dump(gated);
  EXPECT_DOUBLE_EQ(gated.config.estimator.lio.map_min_move_m, kViewpointMoveM);
  const auto set = load(alone + "estimator: {lio: {map_min_move_m: 0}}\n");
  ASSERT_TRUE(set.problems.empty()) << dump(set);
  EXPECT_DOUBLE_EQ(set.config.estimator.lio.map_min_move_m, 0.0);
  EXPECT_EQ(choice(set.config, "lio.map_min_move_m")->reason, "set in the configuration");
}

TEST(EstimatorDefaults, UnknownModelGetsTheBudgetAndSaysWhy) {
  std::set<std::string> given;
  estimator::EstimatorParams params;
  const auto choices = estimator_settings_for(std::nullopt, "XYZ-99", given, params);
  EXPECT_EQ(params.lio.point_budget, kDefaultPointBudget);
  EXPECT_EQ(params.lio.point_filter_num, 1);
  EXPECT_EQ(params.lio.max_points_num, kDefaultPlanePoints);  // whatever the model
  EXPECT_DOUBLE_EQ(params.lio.dept_err, estimator::LioParams{}.dept_err);
  bool explained = false;
  for (const auto& c : choices) {
    explained = explained || c.reason.find("XYZ-99 has no model facts") != std::string::npos;
  }
  EXPECT_TRUE(explained);
}

// check-config prints every model-dependent value and why.
TEST(EstimatorDefaults, CheckConfigPrintsTheEffectiveValuesAndWhy) {
  const auto r = load(ouster_config("OS1-128", "{lio: {dept_err: 0.03}}"));
  ASSERT_TRUE(r.ok()) << dump(r);
  const std::string summary = summarize_config(r.config);
  EXPECT_NE(summary.find("estimator on os1 (OS1-128), effective values:"), std::string::npos)
      << summary;
  EXPECT_NE(summary.find("lio.point_filter_num 4"), std::string::npos) << summary;
  EXPECT_NE(summary.find("131072 points per 10 Hz scan"), std::string::npos) << summary;
  EXPECT_NE(summary.find("lio.dept_err 0.03"), std::string::npos) << summary;
  EXPECT_NE(summary.find("set in the configuration"), std::string::npos) << summary;
  EXPECT_NE(summary.find("lio.point_budget 8000"), std::string::npos) << summary;
  EXPECT_NE(summary.find("lio.max_points_num 500"), std::string::npos) << summary;
  ASSERT_NE(choice(r.config, "lio.beam_err_deg"), nullptr);
  EXPECT_NE(choice(r.config, "lio.beam_err_deg")->reason.find("divergence"), std::string::npos);
}

}  // namespace
}  // namespace livod::daemon
