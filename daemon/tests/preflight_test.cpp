// check-config runs the run's file checks (issue 14, item 3): Ouster metadata is read and parsed,
// its model is cross-checked, the metadata an Ouster bag carries is used, an Ouster frame cut
// other than frame_id is refused by the configuration itself; and replay reports map drops.

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "daemon/config/load_config.hpp"
#include "daemon/preflight.hpp"
#include "daemon/replay/map_accumulator.hpp"
#include "daemon/replay/source_kinds.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon {
namespace {

std::string ouster_pcap_config(const std::string& model, const std::string& metadata) {
  return "body_frame: os1.imu\n"
         "sensors:\n"
         "  - name: os1\n"
         "    driver: ouster\n" +
         (model.empty() ? std::string() : "    model: " + model + "\n") +
         "    source:\n"
         "      replay:\n"
         "        file: " +
         test::data_path("ouster/pcaps/OS-1-128_v2.3.0_1024x10_lb_n3.pcap").string() +
         "\n"
         "    metadata: " +
         metadata +
         "\n"
         "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n";
}

std::string good_metadata() {
  return test::data_path("ouster/pcaps/OS-1-128_v2.3.0_1024x10.json").string();
}

std::vector<ConfigProblem> preflight(const std::string& yaml, bool open_recordings = true) {
  const ConfigResult r = load_config_from_string(yaml, "test.yaml");
  EXPECT_TRUE(r.ok()) << (r.problems.empty() ? "" : r.problems[0].message);
  return check_config_files(r.config, open_recordings);
}

TEST(Preflight, GoodOusterConfigurationPasses) {
  EXPECT_TRUE(preflight(ouster_pcap_config("OS1-128", good_metadata())).empty());
  EXPECT_TRUE(preflight(ouster_pcap_config("", good_metadata())).empty());
}

TEST(Preflight, MalformedMetadataIsAnErrorNamingTheFile) {
  const auto dir = test::temp_dir("preflight_metadata");
  const auto bad = dir / "truncated.json";
  std::ofstream(bad) << R"({"sensor_info": {"prod_line": "OS-1-128")";
  const auto problems = preflight(ouster_pcap_config("OS1-128", bad.string()), false);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].severity, Severity::error);
  EXPECT_EQ(problems[0].path, "sensors[0].metadata");
  EXPECT_EQ(problems[0].line, 3);
  EXPECT_NE(problems[0].message.find(bad.string()), std::string::npos) << problems[0].message;
  EXPECT_NE(problems[0].message.find("JSON"), std::string::npos) << problems[0].message;
}

TEST(Preflight, ModelContradictingTheMetadataIsAnError) {
  for (const std::string model : {"OS1-16", "OS0-128"}) {
    const auto problems = preflight(ouster_pcap_config(model, good_metadata()));
    ASSERT_EQ(problems.size(), 1u) << model;
    EXPECT_NE(problems[0].message.find("model " + model + " contradicts the metadata"),
              std::string::npos)
        << problems[0].message;
  }
}

TEST(Preflight, OusterFrameCutOtherThanFrameIdIsRefusedByTheConfiguration) {
  for (const std::string mode : {"azimuth", "time"}) {
    const ConfigResult r = load_config_from_string(
        ouster_pcap_config("OS1-128", good_metadata()) + "    frame_cut: {mode: " + mode + "}\n",
        "test.yaml");
    ASSERT_EQ(r.error_count(), 1u) << mode;
    EXPECT_EQ(r.problems[0].path, "sensors[0].frame_cut.mode");
    EXPECT_NE(r.problems[0].message.find("use: frame_id"), std::string::npos)
        << r.problems[0].message;
  }
}

std::string ouster_bag_config(const std::string& model) {
  return "body_frame: os.imu\n"
         "sensors:\n"
         "  - name: os\n"
         "    driver: ouster\n" +
         (model.empty() ? std::string() : "    model: " + model + "\n") +
         "    source:\n"
         "      replay: {file: " +
         test::data_path("rosbag1/ouster_packets_512x10.bag").string() +
         ", topic: /os_node0/lidar_packets}\n"
         "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n";
}

TEST(Preflight, OusterBagWithoutMetadataUsesTheMetadataTopic) {
  EXPECT_TRUE(preflight(ouster_bag_config("")).empty());
  const auto metadata = replay::bag_ouster_metadata(
      test::data_path("rosbag1/ouster_packets_512x10.bag"), "/os_node0/lidar_packets");
  EXPECT_EQ(metadata.beam_altitude_angles_deg.size(), 128u);
  EXPECT_EQ(metadata.lidar_mode, "512x10");
  // The bag's metadata is cross-checked like a file's.
  const auto problems = preflight(ouster_bag_config("OS1-16"));
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].message.find("ouster_packets_512x10.bag"), std::string::npos)
      << problems[0].message;
  EXPECT_NE(problems[0].message.find("128 beams"), std::string::npos) << problems[0].message;
}

TEST(Preflight, MissingBagTopicIsFoundByCheckConfig) {
  std::string yaml = ouster_bag_config("");
  yaml.replace(yaml.find("/os_node0/lidar_packets"), 23, "/os_node0/lidar_pockets");
  const auto problems = preflight(yaml);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].message.find("no topic '/os_node0/lidar_pockets'"), std::string::npos)
      << problems[0].message;
}

TEST(MapAccumulator, CountsPointsOutsideTheGrid) {
  replay::MapAccumulator tiny(1e-6, 100);  // the grid spans +-1.05 m
  EXPECT_NEAR(tiny.grid_half_extent_m(), 1.048575, 1e-6);
  EXPECT_TRUE(tiny.add({0.5, 0.5, 0.5}));
  EXPECT_FALSE(tiny.add({5.0, 0.0, 0.0}));
  EXPECT_FALSE(tiny.add({std::nan(""), 0.0, 0.0}));
  EXPECT_EQ(tiny.dropped_outside(), 2u);
  EXPECT_EQ(tiny.dropped_full(), 0u);
}

}  // namespace
}  // namespace livod::daemon
