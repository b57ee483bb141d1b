// The HDL-32E is the one Velodyne with an internal IMU (gyro and accelerometer words in its
// position packets, on the position port): its `imu` section, `body_frame: <lidar>.imu`, its
// ports and the summary; the other Velodynes still have none.

#include <gtest/gtest.h>

#include "daemon/config/load_config.hpp"
#include "daemon/config/summary.hpp"
#include "daemon/config/tests/config_test_support.hpp"

namespace livod::daemon {
namespace {

using test::dump;
using test::load;

// One Velodyne as the only sensor, its internal IMU as the body.
std::string velodyne_body(const std::string& model, const std::string& extra = "",
                          const std::string& udp = "{}") {
  return "body_frame: hdl.imu\nsensors:\n  - name: hdl\n    driver: velodyne\n    model: " + model +
         "\n    source: {udp: " + udp + "}\n" + extra +
         "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n";
}

const ConfigProblem& only_problem(const ConfigResult& result, ProblemKind kind,
                                  const std::string& path) {
  EXPECT_EQ(result.problems.size(), 1u) << dump(result);
  const ConfigProblem* p = test::find_problem(result, kind, path);
  if (p == nullptr) {
    ADD_FAILURE() << "no " << to_string(kind) << " problem at " << path << "\n" << dump(result);
    static const ConfigProblem none{};
    return none;
  }
  return *p;
}

TEST(VelodyneImuConfig, Hdl32eInternalImuIsTheBodyByDefault) {
  const auto result = load(velodyne_body("HDL-32E"));
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  const SensorConfig& hdl = result.config.sensors.at(0);
  EXPECT_TRUE(hdl.imu.enabled);
  EXPECT_EQ(result.config.body_sensor_index, 0);
  EXPECT_TRUE(result.config.body_is_internal_imu);
  // No port of its own: the IMU words come in the position packets.
  const auto& ports = std::get<UdpSourceConfig>(hdl.source).ports;
  EXPECT_EQ(ports.lidar, 2368);
  EXPECT_EQ(ports.position, 8308);
  EXPECT_EQ(ports.imu, 0);
  const std::string summary = summarize_config(result.config);
  EXPECT_NE(summary.find("hdl: velodyne HDL-32E, udp 0.0.0.0 lidar:2368 position:8308, internal "
                         "IMU (in the position packets)"),
            std::string::npos)
      << summary;
}

TEST(VelodyneImuConfig, Hdl32eImuSectionIsReadAndItsPositionPortChecked) {
  // Disabled: it cannot be the body.
  const auto disabled = load(velodyne_body("HDL-32E", "    imu: {enabled: false}\n"));
  const auto& p = only_problem(disabled, ProblemKind::inconsistent, "body_frame");
  EXPECT_NE(p.message.find("disabled (imu.enabled: false)"), std::string::npos) << p.message;
  EXPECT_FALSE(disabled.config.sensors.at(0).imu.enabled);

  // Moved ports are read; the position port carries the IMU.
  const auto moved = load(velodyne_body("hdl-32e", "    imu: {enabled: true}\n",
                                        "{ports: {lidar: 2370, position: 8310}}"));
  ASSERT_TRUE(moved.problems.empty()) << dump(moved);
  const auto& ports = std::get<UdpSourceConfig>(moved.config.sensors.at(0).source).ports;
  EXPECT_EQ(ports.lidar, 2370);
  EXPECT_EQ(ports.position, 8310);
  EXPECT_EQ(moved.config.sensors.at(0).model, "HDL-32E");

  // An 'imu' port does not exist; the message says where the IMU is.
  const auto imu_port = load(velodyne_body("HDL-32E", "", "{ports: {imu: 8308}}"));
  const auto& q =
      only_problem(imu_port, ProblemKind::inconsistent, "sensors[0].source.udp.ports.imu");
  EXPECT_NE(q.message.find("position packets, on the 'position' port"), std::string::npos)
      << q.message;

  // The position port shared with the data port is a conflict (one socket per stream).
  only_problem(load(velodyne_body("HDL-32E", "", "{ports: {position: 2368}}")),
               ProblemKind::duplicate_port, "sensors[0].source.udp.ports.position");
}

TEST(VelodyneImuConfig, OtherVelodynesHaveNoInternalImu) {
  for (const char* model : {"VLP-16", "VLP-32C", "VLS-128"}) {
    SCOPED_TRACE(model);
    const auto body = load(velodyne_body(model));
    const auto& p = only_problem(body, ProblemKind::inconsistent, "body_frame");
    EXPECT_NE(p.message.find("has no internal IMU"), std::string::npos) << p.message;
    EXPECT_FALSE(body.config.sensors.at(0).imu.enabled);

    const auto enabled = load(velodyne_body(model, "    imu: {enabled: true}\n"));
    ASSERT_GE(enabled.problems.size(), 1u) << dump(enabled);
    const ConfigProblem* e =
        test::find_problem(enabled, ProblemKind::inconsistent, "sensors[0].imu.enabled");
    ASSERT_NE(e, nullptr) << dump(enabled);
    EXPECT_NE(e->message.find("only the HDL-32E has one"), std::string::npos) << e->message;
  }
  // `imu: {enabled: false}` is accepted on any Velodyne (a VLP-16 with a CAN IMU as the body).
  const auto vlp = load(R"(body_frame: can
sensors:
  - {name: vlp, driver: velodyne, model: VLP-16, source: {udp: {}}, imu: {enabled: false},
     extrinsic: {translation: [0, 0, 0.3], rotation: {rpy_deg: [0, 0, 0]}}}
  - {name: can, driver: can_imu, source: {device: {interface: can0}}, can: {decoder: sbg}}
)");
  EXPECT_TRUE(vlp.problems.empty()) << dump(vlp);
}

// An HDL-32E beside another body IMU keeps its IMU (it feeds the LiDAR's clock model) unless
// disabled; either way its position port stays bound, so a second HDL-32E needs other ports.
TEST(VelodyneImuConfig, TwoHdl32eNeedTheirOwnPositionPorts) {
  const std::string base = R"(body_frame: can
sensors:
  - {name: can, driver: can_imu, source: {device: {interface: can0}}, can: {decoder: sbg}}
  - {name: front, driver: velodyne, model: HDL-32E, source: {udp: {}},
     extrinsic: {translation: [0.5, 0, 1], rotation: {rpy_deg: [0, 0, 0]}}}
  - {name: rear, driver: velodyne, model: HDL-32E, imu: {enabled: false},
     source: {udp: {ports: {lidar: 2369, position: POSITION}}},
     extrinsic: {translation: [-0.5, 0, 1], rotation: {rpy_deg: [0, 0, 180]}}}
)";
  const auto with_port = [&](const std::string& port) {
    std::string yaml = base;
    yaml.replace(yaml.find("POSITION"), 8, port);
    return load(yaml);
  };
  const auto ok = with_port("8309");
  ASSERT_TRUE(ok.problems.empty()) << dump(ok);
  EXPECT_TRUE(ok.config.sensors.at(1).imu.enabled);
  EXPECT_FALSE(ok.config.sensors.at(2).imu.enabled);
  only_problem(with_port("8308"), ProblemKind::duplicate_port,
               "sensors[2].source.udp.ports.position");
}

}  // namespace
}  // namespace livod::daemon
