// The configuration asks the LiDAR families' tables (drivers/lidar_family.hpp): models and
// aliases, ports, cuts, internal IMUs, the files they need and their own sections (hesai:,
// velodyne:), and builds what their decoder factories take.

#include <gtest/gtest.h>

#include "daemon/config/sensor_models.hpp"
#include "daemon/config/tests/config_test_support.hpp"
#include "drivers/hesai/settings.hpp"
#include "drivers/velodyne/settings.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon::test {
namespace {

// A LiDAR entry `lidar` plus the Xsens body IMU of minimal_config().
std::string with_lidar(const std::string& lidar_keys) {
  return R"(body_frame: imu
sensors:
  - name: lidar
)" + lidar_keys +
         R"(    extrinsic:
      translation: [0.1, 0.0, 0.2]
      rotation: {rpy_deg: [0, 0, 0]}
  - name: imu
    driver: serial_imu
    source: {device: {path: /dev/ttyUSB0}}
    serial: {protocol: xsens_mtdata2}
)";
}

std::string hesai_calibration() {
  return livod::test::data_path("hesai/PandarXT32.csv").string();
}

TEST(LidarFamiliesConfig, HesaiSensorWithItsSectionLoads) {
  const auto result = load(with_lidar(R"(    driver: hesai
    model: xt32
    calibration: )" + hesai_calibration() +
                                      R"(
    source: {udp: {}}
    hesai: {fov_deg: [30, 200], min_range_m: 0.5, max_range_m: 100}
)"));
  ASSERT_TRUE(result.ok()) << dump(result);
  const SensorConfig& s = result.config.sensors[0];
  EXPECT_EQ(s.driver, Driver::hesai);
  EXPECT_EQ(s.model, "PANDARXT32");  // the alias, canonical
  const auto& udp = std::get<UdpSourceConfig>(s.source);
  EXPECT_EQ(udp.ports.lidar, 2368);
  EXPECT_EQ(udp.ports.position, 10110);
  EXPECT_EQ(s.frame_cut.mode, FrameCutMode::azimuth);
  EXPECT_FALSE(s.imu.enabled);
  const auto* settings = std::get_if<drivers::hesai::HesaiSettings>(&s.lidar_settings);
  ASSERT_NE(settings, nullptr);
  ASSERT_TRUE(settings->fov);
  EXPECT_DOUBLE_EQ(settings->fov->start_deg, 30.0);
  EXPECT_DOUBLE_EQ(settings->fov->end_deg, 200.0);
  EXPECT_DOUBLE_EQ(*settings->max_range_m, 100.0);

  // What the family's factory gets, and the decoder it builds.
  const drivers::LidarDecoderConfig dc = decoder_config(s);
  EXPECT_EQ(dc.model, "PANDARXT32");
  EXPECT_EQ(dc.calibration, s.calibration);
  ASSERT_TRUE(dc.cut);
  EXPECT_EQ(dc.cut->mode, drivers::CutMode::kAzimuth);
  const auto decoder = lidar_family(s.driver)->make_decoder(dc);
  EXPECT_EQ(decoder->model_name(), "PANDARXT32");
}

TEST(LidarFamiliesConfig, HesaiNeedsItsAngleFileAndValidSection) {
  {
    const auto result = load(with_lidar(R"(    driver: hesai
    model: PANDAR40P
    source: {udp: {}}
)"));
    EXPECT_NE(find_problem(result, ProblemKind::missing_key, "sensors[0].calibration"), nullptr)
        << dump(result);
  }
  {
    const auto result = load(with_lidar(R"(    driver: hesai
    model: PANDAR40P
    calibration: )" + hesai_calibration() +
                                        R"(
    source: {udp: {}}
    hesai: {fov_deg: [30], min_range_m: 5, max_range_m: 2, start_angle: 3}
    imu: {enabled: true}
    frame_cut: {mode: frame_id}
)"));
    EXPECT_NE(find_problem(result, ProblemKind::invalid_value, "sensors[0].hesai.fov_deg"), nullptr)
        << dump(result);
    EXPECT_NE(find_problem(result, ProblemKind::invalid_value, "sensors[0].hesai.max_range_m"),
              nullptr)
        << dump(result);
    EXPECT_NE(find_problem(result, ProblemKind::unknown_key, "sensors[0].hesai.start_angle"),
              nullptr)
        << dump(result);
    EXPECT_NE(find_problem(result, ProblemKind::inconsistent, "sensors[0].imu"), nullptr)
        << dump(result);  // neither Hesai model has an IMU
    EXPECT_NE(find_problem(result, ProblemKind::inconsistent, "sensors[0].frame_cut.mode"), nullptr)
        << dump(result);
  }
}

TEST(LidarFamiliesConfig, FamilySectionsBelongToTheirFamily) {
  const auto misplaced = load(with_lidar(R"(    driver: velodyne
    model: puck
    source: {udp: {}}
    hesai: {fov_deg: [0, 90]}
)"));
  EXPECT_NE(find_problem(misplaced, ProblemKind::inconsistent, "sensors[0].hesai"), nullptr)
      << dump(misplaced);
  EXPECT_EQ(misplaced.config.sensors[0].model, "VLP-16");  // PUCK is the VLP-16's alias

  const auto velodyne = load(with_lidar(R"(    driver: velodyne
    model: VLP-32C
    source: {udp: {}}
    velodyne: {fov_deg: [270, 90]}
)"));
  ASSERT_TRUE(velodyne.ok()) << dump(velodyne);
  const auto* s =
      std::get_if<drivers::velodyne::VelodyneSettings>(&velodyne.config.sensors[0].lidar_settings);
  ASSERT_NE(s, nullptr);
  ASSERT_TRUE(s->fov);
  EXPECT_DOUBLE_EQ(s->fov->start_deg, 270.0);
}

TEST(LidarFamiliesConfig, OusterFramesAreTheSensorsOwn) {
  const auto result = load(with_lidar(R"(    driver: ouster
    model: OS-1-64
    metadata: )" + livod::test::data_path("ouster/pcaps/OS-1-128_v2.3.0_1024x10.json").string() +
                                      R"(
    source: {udp: {}}
    frame_cut: {mode: time}
)"));
  EXPECT_NE(find_problem(result, ProblemKind::inconsistent, "sensors[0].frame_cut.mode"), nullptr)
      << dump(result);
  EXPECT_EQ(result.config.sensors[0].model, "OS1-64");
}

TEST(LidarFamiliesConfig, DriverFactsComeFromTheTables) {
  EXPECT_EQ(lidar_family(Driver::hesai)->driver, "hesai");
  EXPECT_EQ(lidar_family(Driver::v4l2), nullptr);
  EXPECT_TRUE(is_packet_lidar(Driver::hesai));
  EXPECT_TRUE(model_has_internal_imu(Driver::velodyne, "HDL-32E"));
  EXPECT_FALSE(model_has_internal_imu(Driver::livox_sdk1, "MID-70"));
  EXPECT_EQ(port_names(Driver::hesai), (std::vector<std::string>{"lidar", "position"}));
  EXPECT_EQ(default_ports(Driver::livox_sdk2, "HAP").lidar, 57000);
  EXPECT_EQ(canonical_model(Driver::velodyne, "ultra puck"), "VLP-32C");
  EXPECT_FALSE(canonical_model(Driver::velodyne, "PANDARXT32"));
  EXPECT_EQ(allowed_frame_cuts(Driver::ouster),
            (std::vector<FrameCutMode>{FrameCutMode::frame_id}));
}

}  // namespace
}  // namespace livod::daemon::test
