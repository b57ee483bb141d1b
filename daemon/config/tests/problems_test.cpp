// Every kind of problem is detected, with its YAML path and position, and all problems of a file
// are reported in one pass.

#include <gtest/gtest.h>

#include <set>
#include <tuple>

#include "daemon/config/load_config.hpp"
#include "daemon/config/tests/config_test_support.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon {
namespace {

using test::dump;
using test::find_problem;
using test::load;
using test::minimal_config;

// The minimal config with `old_text` replaced by `new_text` (which must occur exactly once).
std::string edited(const std::string& old_text, const std::string& new_text) {
  std::string yaml = minimal_config();
  const auto at = yaml.find(old_text);
  EXPECT_NE(at, std::string::npos) << old_text;
  EXPECT_EQ(yaml.find(old_text, at + 1), std::string::npos) << old_text;
  return yaml.replace(at, old_text.size(), new_text);
}

// Asserts exactly one problem, of this kind and path, and returns it.
ConfigProblem only_problem(const ConfigResult& result, ProblemKind kind, const std::string& path) {
  EXPECT_EQ(result.problems.size(), 1u) << dump(result);
  const ConfigProblem* p = find_problem(result, kind, path);
  EXPECT_NE(p, nullptr) << "expected " << to_string(kind) << " at " << path << "\n" << dump(result);
  return p != nullptr ? *p : ConfigProblem{};
}

TEST(ConfigProblems, YamlSyntaxErrorHasLineAndColumn) {
  const auto result = load("body_frame: imu\nsensors: [1, 2\nfoo: 3\n");
  const auto p = only_problem(result, ProblemKind::syntax, "");
  EXPECT_EQ(p.severity, Severity::error);
  EXPECT_EQ(p.line, 3);
  EXPECT_GT(p.column, 0);
  EXPECT_NE(p.message.find("YAML syntax"), std::string::npos);
  EXPECT_FALSE(result.ok());
}

TEST(ConfigProblems, EmptyFileNamesTheRequiredKeys) {
  const auto result = load("");
  ASSERT_EQ(result.problems.size(), 2u) << dump(result);
  EXPECT_NE(find_problem(result, ProblemKind::missing_key, "body_frame"), nullptr);
  EXPECT_NE(find_problem(result, ProblemKind::missing_key, "sensors"), nullptr);
}

TEST(ConfigProblems, RootMustBeAMapping) {
  only_problem(load("- a\n- b\n"), ProblemKind::wrong_type, "");
}

TEST(ConfigProblems, OnlyOneDocument) {
  const auto p = only_problem(load(minimal_config() + "---\nfoo: 1\n"), ProblemKind::syntax, "");
  EXPECT_EQ(p.line, 14);  // the "---" separator
}

// yaml-cpp 0.7's LoadAll loops forever on these (jbeder/yaml-cpp#1040); found by config_fuzz.
TEST(ConfigProblems, StrayFlowIndicatorAtDocumentStart) {
  for (const std::string input : {",", ",'", "# comment\n  , x\n", "body_frame: imu\n,\n"}) {
    const auto result = load(input);
    EXPECT_FALSE(result.ok()) << input;
    EXPECT_NE(find_problem(result, ProblemKind::syntax, ""), nullptr) << input << dump(result);
  }
}

TEST(ConfigProblems, OversizedInputIsRefused) {
  const std::string huge(kMaxConfigBytes + 1, '#');
  only_problem(load(huge), ProblemKind::syntax, "");
}

TEST(ConfigProblems, UnknownKeysGetDidYouMean) {
  const auto result = load(edited("    extrinsic:\n", "    extrnsic:\n") +
                           "estimator: {lio: {voxel_sise: 0.4}}\nestimater: {}\nfoo_bar: 1\n");
  ASSERT_EQ(result.problems.size(), 5u) << dump(result);
  const auto* sensor_key = find_problem(result, ProblemKind::unknown_key, "sensors[0].extrnsic");
  ASSERT_NE(sensor_key, nullptr) << dump(result);
  EXPECT_EQ(sensor_key->message, "unknown key 'extrnsic' (did you mean 'extrinsic'?)");
  EXPECT_EQ(sensor_key->line, 7);
  EXPECT_EQ(sensor_key->column, 5);
  const auto* nested = find_problem(result, ProblemKind::unknown_key, "estimator.lio.voxel_sise");
  ASSERT_NE(nested, nullptr) << dump(result);
  EXPECT_NE(nested->message.find("did you mean 'voxel_size'?"), std::string::npos);
  const auto* top = find_problem(result, ProblemKind::unknown_key, "estimater");
  ASSERT_NE(top, nullptr) << dump(result);
  EXPECT_NE(top->message.find("did you mean 'estimator'?"), std::string::npos);
  const auto* far = find_problem(result, ProblemKind::unknown_key, "foo_bar");
  ASSERT_NE(far, nullptr) << dump(result);
  EXPECT_EQ(far->message, "unknown key 'foo_bar'");
  // The sensor lost its extrinsic to the typo, which is reported too.
  EXPECT_NE(find_problem(result, ProblemKind::missing_extrinsic, "sensors[0].extrinsic"), nullptr);
}

TEST(ConfigProblems, DuplicateKeyKeepsTheFirst) {
  const auto result =
      load(edited("    model: VLP-16\n", "    model: VLP-16\n    model: HDL-32E\n"));
  const auto p = only_problem(result, ProblemKind::duplicate_key, "sensors[0].model");
  EXPECT_EQ(p.line, 6);
  EXPECT_EQ(result.config.sensors[0].model, "VLP-16");
}

TEST(ConfigProblems, WrongTypes) {
  {
    const auto p = only_problem(load(edited("{udp: {}}", "{udp: {ports: {lidar: abc}}}")),
                                ProblemKind::wrong_type, "sensors[0].source.udp.ports.lidar");
    EXPECT_EQ(p.message, "expected an integer, got 'abc'");
    EXPECT_EQ(p.line, 6);
    EXPECT_EQ(p.column, 35);
  }
  only_problem(load(edited("    model: VLP-16\n", "    model: VLP-16\n    enabled: maybe\n")),
               ProblemKind::wrong_type, "sensors[0].enabled");
  only_problem(load(edited("[0.1, 0.0, 0.2]", "{x: 0.1}")), ProblemKind::wrong_type,
               "sensors[0].extrinsic.translation");
  only_problem(load(minimal_config() + "health: {period_s: fast}\n"), ProblemKind::wrong_type,
               "health.period_s");
  only_problem(load(minimal_config() + "estimator: {lio: {max_iterations: 4.5}}\n"),
               ProblemKind::wrong_type, "estimator.lio.max_iterations");
  only_problem(load(minimal_config() + "estimator: [1]\n"), ProblemKind::wrong_type, "estimator");
}

TEST(ConfigProblems, OutOfRange) {
  {
    const auto p = only_problem(load(edited("{udp: {}}", "{udp: {ports: {lidar: 70000}}}")),
                                ProblemKind::out_of_range, "sensors[0].source.udp.ports.lidar");
    EXPECT_EQ(p.message, "must be in [1, 65535], got 70000");
  }
  {
    const auto p = only_problem(load(minimal_config() + "estimator: {imu: {acc_cov: 0}}\n"),
                                ProblemKind::out_of_range, "estimator.imu.acc_cov");
    EXPECT_EQ(p.message, "must be in (0, 100], got 0");
  }
  only_problem(load(edited("    model: VLP-16\n", "    model: VLP-16\n    time_offset_s: 2\n")),
               ProblemKind::out_of_range, "sensors[0].time_offset_s");
  only_problem(load(minimal_config() + "estimator: {lio: {blind: nan}}\n"),
               ProblemKind::out_of_range, "estimator.lio.blind");
  only_problem(load(minimal_config() + "realtime: {capture_priority: 120}\n"),
               ProblemKind::out_of_range, "realtime.capture_priority");
  only_problem(load(minimal_config() + "realtime: {cpu_dma_latency_us: -2}\n"),
               ProblemKind::out_of_range, "realtime.cpu_dma_latency_us");
  // A warning, not an error: privileged ports work with CAP_NET_BIND_SERVICE.
  const auto low = load(edited("{udp: {}}", "{udp: {ports: {lidar: 999}}}"));
  const auto p = only_problem(low, ProblemKind::out_of_range, "sensors[0].source.udp.ports.lidar");
  EXPECT_EQ(p.severity, Severity::warning);
  EXPECT_TRUE(low.ok());
}

TEST(ConfigProblems, InvalidValues) {
  {
    const auto p = only_problem(load(edited("driver: velodyne", "driver: velodine")),
                                ProblemKind::invalid_value, "sensors[0].driver");
    EXPECT_NE(p.message.find("(did you mean 'velodyne'?)"), std::string::npos) << p.message;
  }
  {
    const auto p = only_problem(load(edited("model: VLP-16", "model: VLP-61")),
                                ProblemKind::invalid_value, "sensors[0].model");
    EXPECT_NE(p.message.find("(did you mean 'VLP-16'?)"), std::string::npos) << p.message;
    // Case, '-', '_' and spaces do not matter (the families' one normalisation, as for
    // `livod decode`); the canonical spelling is kept.
    const auto loose = load(edited("model: VLP-16", "model: vlp_16"));
    EXPECT_TRUE(loose.ok()) << dump(loose);
    EXPECT_EQ(loose.config.sensors[0].model, "VLP-16");
  }
  only_problem(load(edited("name: lidar", "name: Front-Lidar")), ProblemKind::invalid_value,
               "sensors[0].name");
  only_problem(load(edited("{udp: {}}", "{udp: {bind_address: 300.1.2.3}}")),
               ProblemKind::invalid_value, "sensors[0].source.udp.bind_address");
  only_problem(load(edited("{udp: {}}", "{udp: {multicast_group: 192.168.1.10}}")),
               ProblemKind::invalid_value, "sensors[0].source.udp.multicast_group");
  only_problem(load(minimal_config() + "outputs: {lcm: {url: \"udpm://10.0.0.1:7667\"}}\n"),
               ProblemKind::invalid_value, "outputs.lcm.url");
  only_problem(load(minimal_config() + "logging: {level: verbose}\n"), ProblemKind::invalid_value,
               "logging.level");
}

TEST(ConfigProblems, LcmChannels) {
  only_problem(load(minimal_config() + "outputs: {lcm: {channels: {pose: livod_pose}}}\n"),
               ProblemKind::invalid_value, "outputs.lcm.channels.pose");
  only_problem(load(minimal_config() + "outputs: {lcm: {channels: {health: \"\"}}}\n"),
               ProblemKind::invalid_value, "outputs.lcm.channels.health");
  only_problem(load(minimal_config() + "outputs: {lcm: {channels: {pose: [A]}}}\n"),
               ProblemKind::wrong_type, "outputs.lcm.channels.pose");
  {
    const auto p = only_problem(load(minimal_config() + "outputs: {lcm: {channels: {posee: X}}}\n"),
                                ProblemKind::unknown_key, "outputs.lcm.channels.posee");
    EXPECT_NE(p.message.find("did you mean 'pose'"), std::string::npos) << p.message;
  }
  only_problem(load(minimal_config() + "outputs: {lcm: {publish_bot_core_pose: maybe}}\n"),
               ProblemKind::wrong_type, "outputs.lcm.publish_bot_core_pose");
  {
    // Two enabled outputs on one channel.
    const auto p = only_problem(
        load(minimal_config() + "outputs: {lcm: {channels: {bot_core_pose: LIVOD_POSE}}}\n"),
        ProblemKind::inconsistent, "outputs.lcm.channels.bot_core_pose");
    EXPECT_NE(p.message.find("pose channel"), std::string::npos) << p.message;
  }
  // ... unless one of them is switched off.
  EXPECT_TRUE(load(minimal_config() +
                   "outputs: {lcm: {channels: {cloud: LIVOD_POSE}, publish_cloud: false}}\n")
                  .problems.empty());
  // LCM's 63-byte limit, on the channel when it was given, else once on the suffix.
  only_problem(
      load(minimal_config() + "outputs: {lcm: {channels: {pose: " + std::string(64, 'P') + "}}}\n"),
      ProblemKind::out_of_range, "outputs.lcm.channels.pose");
  {
    const auto p = only_problem(
        load(minimal_config() + "outputs: {lcm: {channel_suffix: " + std::string(50, 'S') + "}}\n"),
        ProblemKind::out_of_range, "outputs.lcm.channel_suffix");
    EXPECT_NE(p.message.find("LIVOD_POSE_IMU"), std::string::npos) << p.message;
  }
  // Every bad value at once.
  const auto all = load(minimal_config() +
                        "outputs: {lcm: {channels: {pose: x, health: LIVOD_CLOUD, cloud: y}, "
                        "publish_cloud: true, cloud_max_points: 5}}\n");
  EXPECT_EQ(all.problems.size(), 3u) << dump(all);  // pose, cloud, cloud_max_points
}

TEST(ConfigProblems, DuplicateSensorNames) {
  const auto result = load(minimal_config() + R"(  - name: lidar
    driver: ouster
    source: {udp: {sensor_address: 192.168.1.5}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)");
  const auto p = only_problem(result, ProblemKind::duplicate_name, "sensors[2].name");
  EXPECT_EQ(p.line, 14);
  EXPECT_NE(p.message.find("already used by sensors[0] (line 3)"), std::string::npos) << p.message;
}

// Two Velodynes with the given udp sections; the second one starts on line 14.
ConfigResult two_velodynes(const std::string& first_udp, const std::string& second_udp,
                           const std::string& second_extra = "") {
  return load(edited("{udp: {}}", first_udp) + "  - name: lidar2\n    driver: velodyne\n" +
              "    model: VLP-16\n    source: " + second_udp + "\n" + second_extra +
              "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n");
}

TEST(ConfigProblems, DuplicatePortsOnTheSameAddress) {
  {
    // Both default to 2368 and 8308 on 0.0.0.0: two conflicts, both on the second sensor.
    const auto result = two_velodynes("{udp: {}}", "{udp: {}}");
    ASSERT_EQ(result.problems.size(), 2u) << dump(result);
    const auto* p =
        find_problem(result, ProblemKind::duplicate_port, "sensors[2].source.udp.ports.lidar");
    ASSERT_NE(p, nullptr) << dump(result);
    EXPECT_NE(p->message.find("port 2368 (default) on 0.0.0.0 is already used by sensors[0] "
                              "'lidar' for its lidar stream (line 6)"),
              std::string::npos)
        << p->message;
    EXPECT_NE(
        find_problem(result, ProblemKind::duplicate_port, "sensors[2].source.udp.ports.position"),
        nullptr);
  }
  {
    // A specific address conflicts with the wildcard on the same port.
    const auto result =
        two_velodynes("{udp: {}}", "{udp: {bind_address: 192.168.1.5, ports: {position: 8309}}}");
    only_problem(result, ProblemKind::duplicate_port, "sensors[2].source.udp.ports.lidar");
  }
  {
    // Two NICs: the same port on two different addresses is fine.
    const auto result =
        two_velodynes("{udp: {bind_address: 192.168.1.5}}", "{udp: {bind_address: 192.168.2.5}}");
    EXPECT_TRUE(result.problems.empty()) << dump(result);
  }
  {
    // A disabled sensor binds nothing.
    const auto result = two_velodynes("{udp: {}}", "{udp: {}}", "    enabled: false\n");
    EXPECT_TRUE(result.problems.empty()) << dump(result);
  }
}

TEST(ConfigProblems, PortsWithinOneSensor) {
  // Ouster points and IMU may share a port (the packet type tells them apart).
  const std::string ouster = R"(  - name: os
    driver: ouster
    source: {udp: {sensor_address: 192.168.1.5, ports: {lidar: 7502, imu: 7502}}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  EXPECT_TRUE(load(minimal_config() + ouster).problems.empty());
  // A Livox command port equal to its data port is a conflict.
  const std::string livox = R"(  - name: avia
    driver: livox_sdk1
    model: AVIA
    source: {udp: {ports: {lidar: 56001, imu: 56001, command: 56001}}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  const auto result = load(minimal_config() + livox);
  const auto p =
      only_problem(result, ProblemKind::duplicate_port, "sensors[2].source.udp.ports.command");
  EXPECT_NE(p.message.find("also this sensor's lidar port"), std::string::npos) << p.message;
  // A disabled internal IMU does not bind its port: no conflict with another sensor's 7503.
  const std::string ouster2 = R"(  - name: os_b
    driver: ouster
    imu: {enabled: false}
    source: {udp: {sensor_address: 192.168.1.6, ports: {lidar: 7504, imu: 7503}}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
  - name: os_c
    driver: ouster
    source: {udp: {sensor_address: 192.168.1.7, ports: {lidar: 7505, imu: 7503}}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  EXPECT_TRUE(load(minimal_config() + ouster2).problems.empty())
      << dump(load(minimal_config() + ouster2));
}

TEST(ConfigProblems, MissingExtrinsic) {
  {
    const auto result =
        load(edited("    extrinsic:\n      translation: [0.1, 0.0, 0.2]\n      rotation: {rpy_deg: "
                    "[0, 0, 0]}\n",
                    ""));
    const auto p = only_problem(result, ProblemKind::missing_extrinsic, "sensors[0].extrinsic");
    EXPECT_EQ(p.line, 3);
    EXPECT_EQ(p.column, 5);
    EXPECT_NE(p.message.find("only the body IMU 'imu' may leave it out"), std::string::npos);
  }
  {
    // A disabled sensor may leave it out.
    const auto result = load(edited("    extrinsic:\n      translation: [0.1, 0.0, 0.2]\n      "
                                    "rotation: {rpy_deg: [0, 0, 0]}\n",
                                    "    enabled: false\n") +
                             "  - {name: vlp2, driver: velodyne, model: VLP-16, "
                             "source: {udp: {}}, extrinsic: {translation: [0, 0, 0], "
                             "rotation: {rpy_deg: [0, 0, 0]}}}\n");
    EXPECT_TRUE(result.problems.empty()) << dump(result);
  }
  {
    // The body IMU must not move the body frame.
    const auto result =
        load(minimal_config() +
             "    extrinsic: {translation: [0, 0, 1], rotation: {rpy_deg: [0, 0, 0]}}\n");
    only_problem(result, ProblemKind::inconsistent, "sensors[1].extrinsic");
  }
}

TEST(ConfigProblems, MissingReplayFileIsAWarning) {
  const auto result = load(R"(body_frame: os1.imu
sensors:
  - name: os1
    driver: ouster
    source: {replay: {file: /nonexistent/capture.pcap}}
    metadata: )" + livod::test::data_path("ouster/pcaps/OS-1-128_v2.3.0_1024x10.json").string() +
                           R"(
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)");
  const auto p = only_problem(result, ProblemKind::missing_file, "sensors[0].source.replay.file");
  EXPECT_EQ(p.severity, Severity::warning);
  EXPECT_TRUE(result.ok());
}

TEST(ConfigProblems, MissingMetadataOrCalibrationIsAnError) {
  const auto result = load(edited("    source: {udp: {}}\n",
                                  "    source: {udp: {}}\n    calibration: no/such/VLP-16.xml\n"));
  const auto p = only_problem(result, ProblemKind::missing_file, "sensors[0].calibration");
  EXPECT_EQ(p.severity, Severity::error);
  // Replaying an Ouster pcap needs the metadata.
  const auto replay =
      load(R"(body_frame: os1.imu
sensors:
  - name: os1
    driver: ouster
    source: {replay: {file: )" +
           livod::test::data_path("ouster/pcaps/OS-1-64_1024x10_fw20.pcap").string() +
           R"(}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)");
  only_problem(replay, ProblemKind::missing_key, "sensors[0].metadata");
}

TEST(ConfigProblems, InconsistentSources) {
  only_problem(load(edited("{device: {path: /dev/ttyUSB0}}", "{udp: {}}")),
               ProblemKind::inconsistent, "sensors[1].source.udp");
  only_problem(load(edited("{udp: {}}", "{udp: {}, replay: {file: a.pcap}}")),
               ProblemKind::inconsistent, "sensors[0].source");
  only_problem(load(edited("{udp: {}}", "{}")), ProblemKind::missing_key, "sensors[0].source");
  only_problem(
      load(edited("{udp: {}}", "{replay: {file: " +
                                   livod::test::data_path("rosbag1/test2.bag").string() + "}}")),
      ProblemKind::missing_key, "sensors[0].source.replay.topic");
  // Serial IMUs are live only; a velodyne capture is not a candump log.
  only_problem(load(edited("{device: {path: /dev/ttyUSB0}}", "{replay: {file: imu.log}}")),
               ProblemKind::inconsistent, "sensors[1].source.replay.format");
  only_problem(load(edited("{udp: {}}", "{replay: {file: a.pcap, format: candump}}")),
               ProblemKind::inconsistent, "sensors[0].source.replay.format");
}

TEST(ConfigProblems, LiveAndReplayDoNotMix) {
  const auto result = load(edited("{udp: {}}", "{replay: {file: /nonexistent/a.pcap}}"));
  ASSERT_EQ(result.error_count(), 1u) << dump(result);
  const auto* p = find_problem(result, ProblemKind::inconsistent, "sensors[1].source");
  ASSERT_NE(p, nullptr) << dump(result);
  EXPECT_NE(p->message.find("is live while sensors[0] 'lidar' is replayed"), std::string::npos)
      << p->message;
}

TEST(ConfigProblems, BodyFrameMustBeAnEnabledImu) {
  {
    const auto p = only_problem(load(edited("body_frame: imu", "body_frame: lidar")),
                                ProblemKind::inconsistent, "body_frame");
    EXPECT_NE(p.message.find("is a lidar, not an IMU"), std::string::npos) << p.message;
  }
  {
    const auto p = only_problem(load(edited("body_frame: imu", "body_frame: imu0")),
                                ProblemKind::invalid_value, "body_frame");
    EXPECT_NE(p.message.find("(did you mean 'imu'?)"), std::string::npos) << p.message;
  }
  only_problem(load(edited("body_frame: imu", "body_frame: lidar.imu")), ProblemKind::inconsistent,
               "body_frame");
  const std::string os = R"(body_frame: os.imu
sensors:
  - name: os
    driver: ouster
    imu: {enabled: false}
    source: {udp: {sensor_address: 192.168.1.5}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  const auto p = only_problem(load(os), ProblemKind::inconsistent, "body_frame");
  EXPECT_NE(p.message.find("disabled"), std::string::npos) << p.message;
}

TEST(ConfigProblems, RelativeToMustNameAnotherSensorWithoutLoops) {
  {
    const auto p =
        only_problem(load(edited("    extrinsic:\n", "    extrinsic:\n      relative_to: imuu\n")),
                     ProblemKind::invalid_value, "sensors[0].extrinsic.relative_to");
    EXPECT_NE(p.message.find("(did you mean 'imu'?)"), std::string::npos) << p.message;
  }
  only_problem(load(edited("    extrinsic:\n", "    extrinsic:\n      relative_to: lidar\n")),
               ProblemKind::inconsistent, "sensors[0].extrinsic.relative_to");
  const auto loop = load(edited("    extrinsic:\n", "    extrinsic:\n      relative_to: cam\n") +
                         R"(  - name: cam
    driver: v4l2
    source: {device: {path: /dev/video0}}
    camera: {width: 640, height: 480, intrinsics: [500, 500, 320, 240]}
    extrinsic: {relative_to: lidar, translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)");
  ASSERT_EQ(loop.problems.size(), 1u) << dump(loop);
  EXPECT_EQ(loop.problems[0].kind, ProblemKind::inconsistent);
  EXPECT_NE(loop.problems[0].message.find("loop"), std::string::npos);
}

TEST(ConfigProblems, InconsistentSensorSettings) {
  only_problem(load(edited("    source: {udp: {}}\n",
                           "    source: {udp: {}}\n    frame_cut: {mode: frame_id}\n")),
               ProblemKind::inconsistent, "sensors[0].frame_cut.mode");
  only_problem(
      load(edited("    source: {udp: {}}\n", "    source: {udp: {}}\n    metadata: os.json\n")),
      ProblemKind::inconsistent, "sensors[0].metadata");
  only_problem(load(edited("{udp: {}}", "{udp: {ports: {imu: 7503}}}")), ProblemKind::inconsistent,
               "sensors[0].source.udp.ports.imu");
  const auto ignored = load(edited("    source: {udp: {}}\n",
                                   "    source: {udp: {}}\n    frame_cut: {period_s: 0.05}\n"));
  const auto p = only_problem(ignored, ProblemKind::inconsistent, "sensors[0].frame_cut.period_s");
  EXPECT_EQ(p.severity, Severity::warning);
  const std::string mid40 = R"(  - name: m40
    driver: livox_sdk1
    model: MID-40
    imu: {enabled: true}
    source: {udp: {ports: {lidar: 56002, command: 55502}}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  only_problem(load(minimal_config() + mid40), ProblemKind::inconsistent, "sensors[2].imu.enabled");
  const std::string ouster_live = R"(  - name: os
    driver: ouster
    source: {udp: {ports: {lidar: 7502}}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  only_problem(load(minimal_config() + ouster_live), ProblemKind::inconsistent,
               "sensors[2].metadata");
}

TEST(ConfigProblems, InconsistentEstimatorSettings) {
  only_problem(load(minimal_config() + "estimator: {imu: {init_samples: 50, init_time_s: 1}}\n"),
               ProblemKind::inconsistent, "estimator.imu.init_time_s");
  only_problem(load(minimal_config() + "estimator: {map: {half_extent_m: 6}}\n"),
               ProblemKind::inconsistent, "estimator.map.slide_threshold_m");
  only_problem(
      load(minimal_config() + "estimator: {lio: {max_layer: 3, layer_init_num: [5, 5]}}\n"),
      ProblemKind::inconsistent, "estimator.lio.layer_init_num");
  const std::string camera = R"(  - name: cam
    driver: v4l2
    source: {device: {path: /dev/video0}}
    camera: {width: 320, height: 240, intrinsics: [300, 300, 160, 120], scale: 0.1}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  // 32x24 px after scaling, and a 3-level pyramid of 8x8 patches needs a 20 px border.
  only_problem(load(minimal_config() + camera), ProblemKind::inconsistent, "sensors[2].camera");
  EXPECT_TRUE(load(minimal_config() + camera + "estimator: {vio: {enabled: false}}\n").ok());
}

TEST(ConfigProblems, NoLidarIsAnError) {
  const auto result = load(R"(body_frame: imu
sensors:
  - {name: imu, driver: serial_imu, source: {device: {path: /dev/ttyUSB0}}, serial: {protocol: xsens_mtdata2}}
)");
  only_problem(result, ProblemKind::inconsistent, "sensors");
}

TEST(ConfigProblems, CustomCanDecoderIsChecked) {
  const auto result = load(R"(body_frame: can
sensors:
  - {name: vlp, driver: velodyne, model: VLP-16, source: {udp: {}},
     extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}}
  - name: can
    driver: can_imu
    source: {device: {interface: can0}}
    can:
      decoder: custom
      sample_id: 0x300
      signals:
        - {quantity: gyro_z,  id: 0x174, start_bit: 0,  length: 16, factor: 0.005, unit: deg_s}
        - {quantity: accel_y, id: 0x174, start_bit: 56, length: 16, factor: 0.001, unit: g}
        - {quantity: gyro_x,  id: 0x178, start_bit: 0,  length: 16, factor: 0.005, unit: m_s2}
        - {quantity: gyro_x,  id: 0x178, start_bit: 16, length: 16, factor: 0.005, unit: deg_s}
)");
  ASSERT_EQ(result.problems.size(), 3u) << dump(result);
  EXPECT_NE(find_problem(result, ProblemKind::out_of_range, "sensors[1].can.signals[1].length"),
            nullptr);
  EXPECT_NE(find_problem(result, ProblemKind::inconsistent, "sensors[1].can.signals[2].unit"),
            nullptr);
  EXPECT_NE(find_problem(result, ProblemKind::inconsistent, "sensors[1].can.sample_id"), nullptr);
}

// Six distinct mistakes in one file: each reported once, nothing else, all in one pass.
TEST(ConfigProblems, ManyProblemsAreAllReportedInOnePass) {
  const std::string yaml = R"(body_frame: imu
sensors:
  - name: lidar
    driver: velodyne
    model: VLP-16
    source: {udp: {ports: {lidar: 70000}}}
    extrinsic:
      translation: [0.1, 0.0]
      rotation: {rpy_deg: [0, 0, 0]}
  - name: lidar
    driver: ouster
    source: {udp: {sensor_address: 192.168.1.9, ports: {lidar: 8308}}}
    extrinsic: {translation: [0, 0, 0], rotation: {quaternion_wxyz: [1, 0, 0, 0]}}
  - name: cam
    driver: v4l2
    source: {device: {path: /dev/video0}}
    camera: {width: 640, height: 480, intrinsics: [500, 500, 320, 240]}
  - name: imu
    driver: serial_imu
    source: {device: {path: /dev/ttyUSB0}}
    serial: {protocol: xsens_mtdata2, baudrate: 115200}
)";
  const auto result = load(yaml);
  using Expected = std::tuple<ProblemKind, std::string, int>;
  const std::set<Expected> expected = {
      {ProblemKind::out_of_range, "sensors[0].source.udp.ports.lidar", 6},
      {ProblemKind::invalid_value, "sensors[0].extrinsic.translation", 8},
      {ProblemKind::duplicate_name, "sensors[1].name", 10},
      {ProblemKind::duplicate_port, "sensors[1].source.udp.ports.lidar", 12},
      {ProblemKind::missing_extrinsic, "sensors[2].extrinsic", 14},
      {ProblemKind::unknown_key, "sensors[3].serial.baudrate", 21},
  };
  std::set<Expected> got;
  for (const auto& p : result.problems) got.emplace(p.kind, p.path, p.line);
  EXPECT_EQ(got, expected) << dump(result);
  EXPECT_EQ(result.problems.size(), expected.size()) << dump(result);
  EXPECT_EQ(result.error_count(), expected.size());
  // Sorted by position in the file, as a compiler would list them.
  for (std::size_t i = 1; i < result.problems.size(); ++i) {
    EXPECT_LE(std::tie(result.problems[i - 1].line, result.problems[i - 1].column),
              std::tie(result.problems[i].line, result.problems[i].column));
  }
}

TEST(ConfigProblems, FormatIsFileLineColumnSeverityPathMessage) {
  const auto result = load(edited("{udp: {}}", "{udp: {ports: {lidar: 70000}}}"));
  ASSERT_EQ(result.problems.size(), 1u) << dump(result);
  EXPECT_EQ(format_problem("robot.yaml", result.problems[0]),
            "robot.yaml:6:35: error: sensors[0].source.udp.ports.lidar: must be in [1, 65535], "
            "got 70000");
  ConfigProblem whole_file{Severity::error, ProblemKind::missing_file, "", 0, 0, "cannot read"};
  EXPECT_EQ(format_problem("x.yaml", whole_file), "x.yaml: error: cannot read");
  ConfigProblem warning{Severity::warning, ProblemKind::missing_file, "a.b", 2, 3, "m"};
  EXPECT_EQ(format_problem("x.yaml", warning), "x.yaml:2:3: warning: a.b: m");
}

TEST(ConfigProblems, UnreadableFileIsAProblemNotAnException) {
  const auto result = load_config("/nonexistent/livod.yaml");
  const auto p = only_problem(result, ProblemKind::missing_file, "");
  EXPECT_EQ(p.line, 0);
  EXPECT_FALSE(result.ok());
}

// Inputs that have broken YAML loaders: none may throw or crash.
TEST(ConfigProblems, HostileYamlIsReportedNotThrown) {
  const std::vector<std::string> inputs = {
      "&a [*a]",
      "a: &x {b: *x}",
      "sensors: &s [*s, *s]\nbody_frame: *s\n",
      std::string(5000, '['),
      "body_frame: imu\nsensors:\n  - &x {name: a, driver: velodyne, model: VLP-16, "
      "source: {udp: {}}}\n  - *x\n  - *x\n",
      "? [a, b]\n: 1\n",
      "sensors:\n\t- name: x\n",
      std::string("body_frame: \0imu\n", 17),
      "!!binary aGVsbG8=",
      "sensors: !!map {a: 1}",
      "{",
      "%YAML 1.2\n---\n",
      ",",
      "}",
      "]",
  };
  for (const auto& input : inputs) {
    ConfigResult result;
    EXPECT_NO_THROW(result = load(input)) << input.substr(0, 60);
    EXPECT_FALSE(result.ok()) << input.substr(0, 60);
  }
}

}  // namespace
}  // namespace livod::daemon

namespace livod::daemon {
namespace {

std::vector<std::string> not_implemented(const std::string& yaml) {
  const ConfigResult r = load_config_from_string(yaml, "test.yaml");
  std::vector<std::string> paths;
  for (const auto& p : r.problems) {
    if (p.kind == ProblemKind::not_implemented) {
      EXPECT_EQ(p.severity, Severity::error) << p.message;
      paths.push_back(p.path);
    }
  }
  return paths;
}

const char* kLidar = R"(body_frame: os1.imu
sensors:
  - name: os1
    driver: ouster
    model: OS1-64
    source: {udp: {sensor_address: 192.168.1.10}}
    imu: {enabled: true}
    extrinsic: {translation: [0, 0, 0.03], rotation: {rpy_deg: [0, 0, 0]}}
)";

// What livod cannot run is an error at check-config time, never a silent no-op at run time.
TEST(ConfigImplemented, WhatCannotRunIsAnError) {
  EXPECT_TRUE(not_implemented(kLidar).empty());

  const std::string camera = std::string(kLidar) + R"(  - name: cam
    driver: aravis
    source: {device: {camera_id: ""}}
    camera: {width: 640, height: 512, intrinsics: [500, 500, 320, 256]}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  // A live camera feeds the visual update (`livod run` starts it).
  EXPECT_TRUE(not_implemented(camera).empty());
  // Disabled, the camera keeps its calibration in the file and is no problem.
  std::string disabled = camera;
  disabled.replace(disabled.find("    driver: aravis"), 0, "    enabled: false\n");
  EXPECT_TRUE(not_implemented(disabled).empty());
  // Replayed frames feed the visual update.
  const std::string live_source = "{device: {camera_id: \"\"}}";
  std::string replayed = camera;
  replayed.replace(replayed.find(live_source), live_source.size(), "{replay: {file: mav0/cam0}}");
  EXPECT_TRUE(not_implemented(replayed).empty());
  // The visual update takes one camera: a second enabled one is refused.
  std::string two_cameras = replayed;
  two_cameras += replayed.substr(replayed.find("  - name: cam\n"));
  two_cameras.replace(two_cameras.rfind("name: cam"), 9, "name: cam2");
  EXPECT_EQ(not_implemented(two_cameras), std::vector<std::string>{"sensors[2].enabled"});
  // estimator.vio.enabled false: the camera is left out, with a warning that says so.
  const ConfigResult no_vio =
      load_config_from_string(replayed + "estimator: {vio: {enabled: false}}\n", "test.yaml");
  bool warned = false;
  for (const auto& p : no_vio.problems) {
    EXPECT_NE(p.kind, ProblemKind::not_implemented) << p.message;
    if (p.severity == Severity::warning && p.path == "sensors[1].enabled" &&
        p.message.find("estimator.vio.enabled is false") != std::string::npos) {
      warned = true;
    }
  }
  EXPECT_TRUE(warned);

  const std::string two_lidars = std::string(kLidar) + R"(  - name: vlp
    driver: velodyne
    model: VLP-16
    source: {udp: {}}
    extrinsic: {translation: [0, 0, 0.3], rotation: {rpy_deg: [0, 0, 0]}}
)";
  // Every enabled LiDAR feeds the estimator.
  EXPECT_TRUE(not_implemented(two_lidars).empty());
  // ... LiDAR-inertially: with the visual update (a camera and VIO on) the second is refused, with
  // a message that says how to fuse both.
  const std::string cam_replayed = replayed.substr(replayed.find("  - name: cam\n"));
  const ConfigResult lidars_vio = load_config_from_string(two_lidars + cam_replayed, "test.yaml");
  ASSERT_EQ(not_implemented(two_lidars + cam_replayed),
            std::vector<std::string>{"sensors[1].enabled"});
  bool explained = false;
  for (const auto& p : lidars_vio.problems) {
    if (p.kind == ProblemKind::not_implemented &&
        p.message.find("estimator.vio.enabled: false") != std::string::npos) {
      explained = true;
    }
  }
  EXPECT_TRUE(explained) << test::dump(lidars_vio);
  EXPECT_TRUE(
      not_implemented(two_lidars + cam_replayed + "estimator: {vio: {enabled: false}}\n").empty());
  // At most 8 LiDARs: the ninth is refused.
  std::string nine_lidars = kLidar;
  for (int i = 1; i < 9; ++i) {
    nine_lidars += "  - name: vlp" + std::to_string(i) + R"(
    driver: velodyne
    model: VLP-16
    source: {udp: {ports: {lidar: )" +
                   std::to_string(3000 + 10 * i) + ", position: " + std::to_string(3001 + 10 * i) +
                   R"(}}}
    extrinsic: {translation: [0, 0, 0.3], rotation: {rpy_deg: [0, 0, 0]}}
)";
  }
  EXPECT_EQ(not_implemented(nine_lidars), std::vector<std::string>{"sensors[8].enabled"});

  const std::string extra_imu = std::string(kLidar) + R"(  - name: can
    driver: can_imu
    source: {replay: {file: imu.log}}
    can: {decoder: sbg}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  EXPECT_EQ(not_implemented(extra_imu), std::vector<std::string>{"sensors[1].enabled"});

  const std::string live_can = R"(body_frame: can
sensors:
  - name: vlp
    driver: velodyne
    model: VLP-16
    source: {udp: {}}
    extrinsic: {translation: [0, 0, 0.3], rotation: {rpy_deg: [0, 0, 0]}}
  - name: can
    driver: can_imu
    source: {device: {interface: can0}}
    can: {decoder: sbg}
)";
  // A live CAN IMU as the body IMU runs in `livod run`.
  EXPECT_TRUE(not_implemented(live_can).empty());

  // So does a live serial IMU.
  std::string live_serial = live_can;
  live_serial.replace(live_serial.find("    driver: can_imu"), std::string::npos,
                      "    driver: serial_imu\n    source: {device: {path: /dev/ttyUSB0}}\n"
                      "    serial: {protocol: xsens_mtdata2}\n");
  EXPECT_TRUE(not_implemented(live_serial).empty());
}

}  // namespace
}  // namespace livod::daemon
