// Omitted keys take their documented defaults; values that are given are read.

#include <gtest/gtest.h>

#include <fstream>

#include "daemon/config/estimator_defaults.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/config/summary.hpp"
#include "daemon/config/tests/config_test_support.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon {
namespace {

using test::dump;
using test::load;
using test::minimal_config;

TEST(ConfigDefaults, MinimalConfigLoadsWithoutProblems) {
  const auto result = load(minimal_config());
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  EXPECT_TRUE(result.ok());
}

TEST(ConfigDefaults, TopLevelSectionsTakeTheirDefaults) {
  const auto result = load(minimal_config());
  ASSERT_TRUE(result.ok()) << dump(result);
  const LivodConfig& c = result.config;
  EXPECT_EQ(c.logging.level, "info");
  EXPECT_EQ(c.body_frame, "imu");
  EXPECT_EQ(c.body_sensor_index, 1);
  EXPECT_FALSE(c.body_is_internal_imu);
  EXPECT_TRUE(c.outputs.lcm.enabled);
  EXPECT_EQ(c.outputs.lcm.url, "udpm://239.255.76.67:7667?ttl=0");
  EXPECT_EQ(c.outputs.lcm.channel_suffix, "");
  EXPECT_TRUE(c.outputs.lcm.publish_imu_rate);
  EXPECT_FALSE(c.outputs.lcm.publish_cloud);
  EXPECT_TRUE(c.outputs.lcm.publish_bot_core_pose);
  EXPECT_EQ(c.outputs.lcm.channels.pose, "LIVOD_POSE");
  EXPECT_EQ(c.outputs.lcm.channels.pose_imu, "LIVOD_POSE_IMU");
  EXPECT_EQ(c.outputs.lcm.channels.health, "LIVOD_HEALTH");
  EXPECT_EQ(c.outputs.lcm.channels.cloud, "LIVOD_CLOUD");
  EXPECT_EQ(c.outputs.lcm.channels.bot_core_pose, "POSE_BODY");
  EXPECT_TRUE(c.outputs.trajectory.empty());
  EXPECT_TRUE(c.outputs.map_pcd.empty());
  EXPECT_TRUE(c.outputs.timing_report.empty());
  EXPECT_DOUBLE_EQ(c.health.period_s, 1.0);
  EXPECT_DOUBLE_EQ(c.health.stale_after_s, 0.5);
  EXPECT_EQ(c.realtime.capture_priority, 0);
  EXPECT_FALSE(c.realtime.lock_memory);
  EXPECT_EQ(c.realtime.cpu_dma_latency_us, -1);  // no PM QoS request unless asked for
}

// The estimator defaults are FAST-LIVO2's avia.yaml (fast-livo2-notes.md section 1.5), except the
// point selection and noise model, which follow the LiDAR model (estimator_defaults_test.cpp; the
// minimal configuration's LiDAR is a VLP-16).
TEST(ConfigDefaults, EstimatorDefaultsAreTheAviaValues) {
  const auto result = load(minimal_config());
  ASSERT_TRUE(result.ok()) << dump(result);
  const auto& e = result.config.estimator;
  EXPECT_DOUBLE_EQ(e.imu.acc_cov, 0.5);
  EXPECT_DOUBLE_EQ(e.imu.gyr_cov, 0.3);
  EXPECT_DOUBLE_EQ(e.imu.b_acc_cov, 1e-4);
  EXPECT_DOUBLE_EQ(e.imu.b_gyr_cov, 1e-4);
  EXPECT_EQ(e.imu.init_samples, 30);
  EXPECT_DOUBLE_EQ(e.imu.init_time_s, 0.0);
  EXPECT_FALSE(e.imu.gravity_align);
  EXPECT_TRUE(e.imu.gravity_est);
  EXPECT_TRUE(e.imu.bias_est);
  EXPECT_EQ(e.lio.max_iterations, 5);
  EXPECT_DOUBLE_EQ(e.lio.dept_err, 0.015);           // VLP-16 datasheet
  EXPECT_DOUBLE_EQ(e.lio.beam_err_deg, 0.5 * 0.17);  // half its 3 mrad divergence
  EXPECT_DOUBLE_EQ(e.lio.min_eigen_value, 0.0025);
  EXPECT_DOUBLE_EQ(e.lio.sigma_num, 3.0);
  EXPECT_DOUBLE_EQ(e.lio.voxel_size, 0.5);
  EXPECT_EQ(e.lio.max_layer, 2);
  EXPECT_EQ(e.lio.max_points_num, kDefaultPlanePoints);  // FAST-LIVO2's 50 otherwise
  EXPECT_EQ(e.lio.max_cov_points, 50);
  EXPECT_EQ(e.lio.layer_init_num, (std::vector<int>{5, 5, 5, 5, 5}));
  EXPECT_EQ(e.lio.point_filter_num, 1);
  EXPECT_EQ(e.lio.point_budget, kDefaultPointBudget);
  EXPECT_DOUBLE_EQ(e.lio.blind, 0.8);
  EXPECT_DOUBLE_EQ(e.lio.filter_size_surf, 0.1);
  EXPECT_TRUE(e.map.sliding);
  EXPECT_DOUBLE_EQ(e.map.half_extent_m, 50.0);
  EXPECT_DOUBLE_EQ(e.map.slide_threshold_m, 8.0);
  EXPECT_TRUE(e.vio.enabled);
  EXPECT_EQ(e.vio.max_iterations, 5);
  EXPECT_DOUBLE_EQ(e.vio.outlier_threshold, 1000.0);
  EXPECT_DOUBLE_EQ(e.vio.img_point_cov, 100.0);
  EXPECT_EQ(e.vio.patch_size, 8);
  EXPECT_EQ(e.vio.pyramid_levels, 3);
  EXPECT_TRUE(e.vio.normal_en);
  EXPECT_TRUE(e.vio.exposure_estimate);
  EXPECT_DOUBLE_EQ(e.vio.inv_expo_cov, 0.1);
}

TEST(ConfigDefaults, SensorDefaultsDependOnDriver) {
  const auto result = load(minimal_config());
  ASSERT_TRUE(result.ok()) << dump(result);
  const SensorConfig& lidar = result.config.sensors.at(0);
  EXPECT_EQ(lidar.name, "lidar");
  EXPECT_EQ(lidar.driver, Driver::velodyne);
  EXPECT_EQ(lidar.model, "VLP-16");
  EXPECT_TRUE(lidar.enabled);
  const auto* udp = std::get_if<UdpSourceConfig>(&lidar.source);
  ASSERT_NE(udp, nullptr);
  EXPECT_EQ(udp->bind_address, "0.0.0.0");
  EXPECT_EQ(udp->ports.lidar, 2368);
  EXPECT_EQ(udp->ports.position, 8308);
  EXPECT_EQ(udp->ports.imu, 0);
  EXPECT_EQ(udp->socket_buffer_bytes, 8 * 1024 * 1024);
  EXPECT_TRUE(udp->multicast_group.empty());
  EXPECT_EQ(lidar.frame_cut.mode, FrameCutMode::azimuth);
  EXPECT_FALSE(lidar.imu.enabled);  // a VLP-16 has none
  EXPECT_EQ(lidar.ring_capacity, 1024);
  EXPECT_EQ(lidar.clock.mode, ClockMode::automatic);
  EXPECT_DOUBLE_EQ(lidar.clock.window_s, 60.0);
  EXPECT_DOUBLE_EQ(lidar.time_offset_s, 0.0);
  EXPECT_TRUE(lidar.T_body_sensor.translation().isApprox(Eigen::Vector3d(0.1, 0.0, 0.2)));

  const SensorConfig& imu = result.config.sensors.at(1);
  EXPECT_EQ(imu.driver, Driver::serial_imu);
  EXPECT_EQ(imu.serial.baud_rate, 115200);
  EXPECT_TRUE(imu.T_body_sensor.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_FALSE(imu.extrinsic.has_value());
}

TEST(ConfigDefaults, PerModelPortsAndInternalImu) {
  const auto result = load(R"(body_frame: mid.imu
sensors:
  - {name: mid, driver: livox_sdk2, model: mid-360, source: {udp: {}},
     extrinsic: {translation: [-0.011, -0.02329, 0.04412], rotation: {rpy_deg: [0, 0, 0]}}}
  - {name: hap, driver: livox_sdk2, model: HAP, source: {udp: {bind_address: 192.168.2.5}},
     extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}}
  - {name: m40, driver: livox_sdk1, model: MID-40, source: {udp: {ports: {lidar: 56002, imu: 56002, command: 55502}}},
     extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}}
)");
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  const auto& s = result.config.sensors;
  EXPECT_EQ(s[0].model, "MID-360");  // canonical spelling
  const auto& mid = std::get<UdpSourceConfig>(s[0].source).ports;
  EXPECT_EQ(mid.command, 56101);
  EXPECT_EQ(mid.push, 56201);
  EXPECT_EQ(mid.lidar, 56301);
  EXPECT_EQ(mid.imu, 56401);
  const auto& hap = std::get<UdpSourceConfig>(s[1].source).ports;
  EXPECT_EQ(hap.command, 56000);
  EXPECT_EQ(hap.lidar, 57000);
  EXPECT_EQ(hap.imu, 58000);
  EXPECT_TRUE(s[0].imu.enabled);
  EXPECT_FALSE(s[2].imu.enabled);  // Mid-40: no IMU
  EXPECT_EQ(s[0].frame_cut.mode, FrameCutMode::time);
  EXPECT_DOUBLE_EQ(s[0].frame_cut.period_s, 0.1);
  EXPECT_EQ(result.config.body_sensor_index, 0);
  EXPECT_TRUE(result.config.body_is_internal_imu);
}

TEST(ConfigDefaults, GivenValuesOverrideDefaults) {
  const auto result = load(minimal_config() + R"(logging: {level: debug}
estimator:
  imu: {acc_cov: 2.0, init_time_s: 0.5, static_check: {enabled: false}}
  lio: {max_layer: 3, layer_init_num: [6, 6, 5, 5], voxel_size: 2.0, convergence: {rotation_deg: 0.02}}
  map: {sliding: false, half_extent_m: 100, slide_threshold_m: 20}
  vio: {enabled: false, pyramid_levels: 4, patch_size: 8}
outputs:
  lcm: {url: "memq://", channel_suffix: _REPLAY, publish_cloud: true, cloud_max_points: 5000}
  trajectory: /tmp/livod-test-traj.tum
health: {period_s: 0.5, stale_after_s: 0.2}
realtime: {capture_priority: 60, scheduler_priority: 50, lock_memory: true, cpu_dma_latency_us: 0}
)");
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  const LivodConfig& c = result.config;
  EXPECT_EQ(c.logging.level, "debug");
  EXPECT_DOUBLE_EQ(c.estimator.imu.acc_cov, 2.0);
  EXPECT_DOUBLE_EQ(c.estimator.imu.init_time_s, 0.5);
  EXPECT_FALSE(c.estimator.imu.static_check.enabled);
  EXPECT_EQ(c.estimator.lio.max_layer, 3);
  EXPECT_EQ(c.estimator.lio.layer_init_num, (std::vector<int>{6, 6, 5, 5}));
  EXPECT_DOUBLE_EQ(c.estimator.lio.convergence.rotation_deg, 0.02);
  EXPECT_DOUBLE_EQ(c.estimator.lio.convergence.translation_m, 0.00015);
  EXPECT_FALSE(c.estimator.map.sliding);
  EXPECT_FALSE(c.estimator.vio.enabled);
  EXPECT_EQ(c.estimator.vio.pyramid_levels, 4);
  EXPECT_EQ(c.outputs.lcm.url, "memq://");
  EXPECT_EQ(c.outputs.lcm.channel_suffix, "_REPLAY");
  EXPECT_TRUE(c.outputs.lcm.publish_cloud);
  EXPECT_EQ(c.outputs.lcm.cloud_max_points, 5000);
  EXPECT_EQ(c.outputs.trajectory, "/tmp/livod-test-traj.tum");
  EXPECT_DOUBLE_EQ(c.health.period_s, 0.5);
  EXPECT_EQ(c.realtime.capture_priority, 60);
  EXPECT_TRUE(c.realtime.lock_memory);
  EXPECT_EQ(c.realtime.cpu_dma_latency_us, 0);
}

TEST(ConfigDefaults, VisualUpdateKeys) {
  const auto result = load(minimal_config() + R"(estimator:
  vio:
    huber_k: 2.0
    min_patches: 20
    max_view_angle_deg: 70
    min_corner_score: 9
    max_observations: 12
    observation_distance_m: 0.3
    observation_angle_deg: 10
    observation_pixels: 25
    image_timeout_s: 0.08
    convergence: {rotation_deg: 0.002, translation_m: 0.00002}
)");
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  const auto& v = result.config.estimator.vio;
  EXPECT_DOUBLE_EQ(v.huber_k, 2.0);
  EXPECT_EQ(v.min_patches, 20);
  EXPECT_DOUBLE_EQ(v.max_view_angle_deg, 70.0);
  EXPECT_DOUBLE_EQ(v.min_corner_score, 9.0);
  EXPECT_EQ(v.max_observations, 12);
  EXPECT_DOUBLE_EQ(v.observation_distance_m, 0.3);
  EXPECT_DOUBLE_EQ(v.observation_angle_deg, 10.0);
  EXPECT_DOUBLE_EQ(v.observation_pixels, 25.0);
  EXPECT_DOUBLE_EQ(v.image_timeout_s, 0.08);
  EXPECT_DOUBLE_EQ(v.convergence.rotation_deg, 0.002);
  EXPECT_DOUBLE_EQ(v.convergence.translation_m, 0.00002);
  // Defaults of the keys FAST-LIVO2 does not have.
  const auto d = load(minimal_config());
  EXPECT_DOUBLE_EQ(d.config.estimator.vio.huber_k, 1.345);
  EXPECT_EQ(d.config.estimator.vio.max_observations, 8);
  // Out of range: an error naming the key.
  const auto bad = load(minimal_config() + "estimator: {vio: {max_view_angle_deg: 120}}\n");
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(dump(bad).find("max_view_angle_deg"), std::string::npos) << dump(bad);
}

TEST(ConfigDefaults, LcmChannelsAndBotCorePose) {
  const auto result = load(minimal_config() + R"(outputs:
  lcm:
    channel_suffix: _BENCH
    publish_bot_core_pose: false
    channels: {pose: ROBOT_POSE, pose_imu: ROBOT_POSE_FAST, health: ROBOT_HEALTH,
               cloud: ROBOT_SCAN, bot_core_pose: POSE_LIVOD}
)");
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  const LcmOutputConfig& lcm = result.config.outputs.lcm;
  EXPECT_FALSE(lcm.publish_bot_core_pose);
  EXPECT_EQ(lcm.channels.pose, "ROBOT_POSE");
  EXPECT_EQ(lcm.channels.pose_imu, "ROBOT_POSE_FAST");
  EXPECT_EQ(lcm.channels.health, "ROBOT_HEALTH");
  EXPECT_EQ(lcm.channels.cloud, "ROBOT_SCAN");
  EXPECT_EQ(lcm.channels.bot_core_pose, "POSE_LIVOD");
  EXPECT_EQ(lcm.channel(lcm.channels.pose), "ROBOT_POSE_BENCH");
  // Given channels keep the defaults of the others; null keeps a default too.
  const auto partial =
      load(minimal_config() + "outputs: {lcm: {channels: {pose: MY_POSE, health: null}}}\n");
  ASSERT_TRUE(partial.problems.empty()) << dump(partial);
  EXPECT_EQ(partial.config.outputs.lcm.channels.pose, "MY_POSE");
  EXPECT_EQ(partial.config.outputs.lcm.channels.health, "LIVOD_HEALTH");
  EXPECT_EQ(partial.config.outputs.lcm.channels.bot_core_pose, "POSE_BODY");
}

TEST(ConfigDefaults, NullSectionsAndLcmNull) {
  const auto result = load(minimal_config() + "estimator:\noutputs:\n  lcm: null\nhealth: ~\n");
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  EXPECT_FALSE(result.config.outputs.lcm.enabled);
  EXPECT_DOUBLE_EQ(result.config.estimator.lio.voxel_size, 0.5);
}

TEST(ConfigDefaults, CameraAndCanSectionsAreRead) {
  const auto result = load(R"(body_frame: bosch
sensors:
  - {name: vlp, driver: velodyne, model: VLP-32C, source: {udp: {}},
     extrinsic: {translation: [0, 0, 0.3], rotation: {rpy_deg: [0, 0, 0]}}}
  - name: cam
    driver: v4l2
    source: {device: {path: /dev/video0}}
    camera: {model: equidistant, width: 720, height: 540,
             intrinsics: [351.31, 351.49, 367.85, 253.84],
             distortion: [-0.0370, -0.0089, 0.0089, -0.0038], frame_rate_hz: 40, decimation: 4}
    extrinsic: {relative_to: vlp, translation: [0.05, 0, -0.1], rotation: {rpy_deg: [-90, 0, -90]}}
  - {name: bosch, driver: can_imu, source: {device: {interface: can1}}, can: {decoder: bosch_mm7}}
  - {name: sbg, driver: can_imu, enabled: false, source: {device: {interface: can0}},
     can: {decoder: sbg, ids: {accel: 0x221, gyro: 0x222}}}
)");
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  const auto& cam = result.config.sensors.at(1);
  EXPECT_EQ(cam.camera.model, CameraModel::equidistant);
  EXPECT_EQ(cam.camera.width, 720);
  EXPECT_DOUBLE_EQ(cam.camera.intrinsics[3], 253.84);
  EXPECT_EQ(cam.camera.distortion.size(), 4u);
  EXPECT_EQ(cam.camera.decimation, 4);
  ASSERT_TRUE(cam.camera.frame_rate_hz.has_value());
  EXPECT_DOUBLE_EQ(*cam.camera.frame_rate_hz, 40.0);
  EXPECT_FALSE(cam.camera.exposure_s.has_value());
  EXPECT_EQ(cam.ring_capacity, 8);  // frames, not packets
  const auto& sbg = result.config.sensors.at(3);
  EXPECT_EQ(sbg.can.decoder, CanDecoder::sbg);
  EXPECT_EQ(sbg.can.sbg_ids.info, 0x120u);
  EXPECT_EQ(sbg.can.sbg_ids.accel, 0x221u);
  EXPECT_EQ(sbg.can.sbg_ids.gyro, 0x222u);
  EXPECT_FALSE(sbg.enabled);
  EXPECT_EQ(std::get<DeviceSourceConfig>(result.config.sensors.at(2).source).interface, "can1");
}

// A replay of the real Ouster capture in the shared data, with paths relative to the config.
TEST(ConfigDefaults, RelativePathsResolveAgainstTheConfigFolder) {
  const auto pcaps = livod::test::data_path("ouster/pcaps");
  const auto result = load_config_from_string(R"(body_frame: os1.imu
sensors:
  - name: os1
    driver: ouster
    source: {replay: {file: OS-1-128_v2.3.0_1024x10_lb_n3.pcap}}
    metadata: ./OS-1-128_v2.3.0_1024x10.json
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)",
                                              "replay.yaml", pcaps);
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  const auto& os1 = result.config.sensors.at(0);
  const auto& replay = std::get<ReplaySourceConfig>(os1.source);
  EXPECT_EQ(replay.file, (pcaps / "OS-1-128_v2.3.0_1024x10_lb_n3.pcap").lexically_normal());
  EXPECT_EQ(replay.format, ReplayFormat::pcap);  // from the extension
  EXPECT_EQ(os1.metadata, (pcaps / "OS-1-128_v2.3.0_1024x10.json").lexically_normal());
  EXPECT_TRUE(std::filesystem::exists(os1.metadata));
  EXPECT_EQ(os1.frame_cut.mode, FrameCutMode::frame_id);
  EXPECT_TRUE(os1.imu.enabled);
}

TEST(ConfigDefaults, LoadConfigReadsAFileAndResolvesAgainstItsFolder) {
  const auto dir = livod::test::temp_dir("config_defaults_file");
  const auto calibration = livod::test::data_path("velodyne/veloview/VLP-16.xml");
  const auto config_path = dir / "livod.yaml";
  {
    std::ofstream out(config_path);
    out << minimal_config() << "    calibration_placeholder: 0\n";
  }
  // The line above makes the file wrong on purpose: the problem names the file and its line.
  auto result = test::without_not_implemented(load_config(config_path));
  ASSERT_EQ(result.problems.size(), 1u) << dump(result);
  EXPECT_EQ(result.source, config_path.string());
  EXPECT_EQ(result.problems[0].kind, ProblemKind::unknown_key);
  EXPECT_EQ(result.problems[0].line, 14);

  {
    std::ofstream out(config_path);
    std::string yaml = minimal_config();
    yaml.insert(yaml.find("    source: {udp: {}}"),
                "    calibration: " + calibration.string() + "\n");
    out << yaml << "outputs: {trajectory: out/traj.tum}\n";
  }
  std::filesystem::create_directories(dir / "out");
  result = test::without_not_implemented(load_config(config_path));
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  EXPECT_EQ(result.config.sensors[0].calibration, calibration.lexically_normal());
  EXPECT_EQ(result.config.outputs.trajectory, dir / "out" / "traj.tum");
  EXPECT_EQ(result.config.source_file, config_path);
}

TEST(ConfigDefaults, SummaryNamesEverySensorAndOutput) {
  const auto result = load(minimal_config());
  ASSERT_TRUE(result.ok()) << dump(result);
  const std::string summary = summarize_config(result.config);
  EXPECT_NE(summary.find("body frame: imu"), std::string::npos) << summary;
  EXPECT_NE(summary.find("lidar: velodyne VLP-16, udp 0.0.0.0 lidar:2368 position:8308"),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find("T_body_sensor t [0.100, 0.000, 0.200] m"), std::string::npos) << summary;
  EXPECT_NE(summary.find("imu: serial_imu, device /dev/ttyUSB0, body frame"), std::string::npos)
      << summary;
  EXPECT_NE(summary.find("outputs: lcm udpm://239.255.76.67:7667?ttl=0, IMU-rate pose, bot_core "
                         "pose on POSE_BODY;"),
            std::string::npos)
      << summary;
}

}  // namespace
}  // namespace livod::daemon
