// A LiDAR's own point model (`lio:` on a LiDAR; docs/configuration.md): read with estimator.lio's
// ranges, defaulting to estimator.lio's values, refused on other sensors, at least one LiDAR
// building the map, and shown by check-config's summary.

#include <gtest/gtest.h>

#include <string>

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
  EXPECT_NE(summary.find("point noise: range 0.03 m, bearing 0.1 deg (estimator.lio), matched "
                         "only (does not build the map)"),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find("point noise: range 0.015 m (estimator.lio), bearing 0.1 deg "
                         "(estimator.lio), builds the map"),
            std::string::npos)
      << summary;
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

}  // namespace
}  // namespace livod::daemon
