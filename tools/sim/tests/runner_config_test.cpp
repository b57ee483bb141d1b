// The config.yaml the runner writes is a valid livod configuration: livod's own loader reads it
// without a single problem, and the sensors, extrinsics and replay files it names are the ones the
// scenario simulated.

#include <gtest/gtest.h>

#include <set>

#include "daemon/config/load_config.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/runner.hpp"

namespace livod::sim {
namespace {

std::set<std::string> simulated_models() {
  std::set<std::string> models;
  for (const auto& [m, _] : simulated_lidar_models()) models.insert(m);
  return models;
}

void expect_pose_near(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                      const std::string& what) {
  EXPECT_LT((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), 1e-9) << what;
}

void check_config(const Scenario& scenario) {
  SCOPED_TRACE(scenario.name);
  SimRunOptions o;
  o.out_dir = test::temp_dir("config_" + scenario.name);
  o.duration_s = 0.2;
  o.write_images = false;
  run_scenario(scenario, o);

  const daemon::ConfigResult result = daemon::load_config(o.out_dir / "config.yaml");
  for (const auto& p : result.problems) ADD_FAILURE() << daemon::format_problem(result.source, p);
  ASSERT_TRUE(result.ok());
  const daemon::LivodConfig& config = result.config;

  std::size_t expected =
      scenario.lidars.size() + scenario.cameras.size() + (scenario.can_imu ? 1u : 0u);
  ASSERT_EQ(config.sensors.size(), expected);
  ASSERT_GE(config.body_sensor_index, 0);
  const auto& body = config.sensors[static_cast<std::size_t>(config.body_sensor_index)];
  EXPECT_EQ(body.name, scenario.body_imu);
  for (const auto& mount : scenario.lidars) {
    const auto* s = config.find_sensor(mount.name);
    ASSERT_NE(s, nullptr) << mount.name;
    EXPECT_EQ(s->model, mount.model);
    EXPECT_EQ(s->imu.enabled, mount.imu);
    const auto* replay = std::get_if<daemon::ReplaySourceConfig>(&s->source);
    ASSERT_NE(replay, nullptr);
    EXPECT_EQ(replay->format, daemon::ReplayFormat::pcap);
    EXPECT_TRUE(std::filesystem::exists(replay->file)) << replay->file;
    // The body is the internal IMU when the scenario says so; the LiDAR frame sits at
    // T_body_sensor either way.
    EXPECT_EQ(config.body_is_internal_imu && body.name == mount.name,
              scenario.body_imu == mount.name);
    expect_pose_near(s->T_body_sensor, mount.T_body_sensor, mount.name);
  }
  if (scenario.can_imu) {
    const auto* s = config.find_sensor(scenario.can_imu->name);
    ASSERT_NE(s, nullptr);
    EXPECT_EQ(s->driver, daemon::Driver::can_imu);
    const bool sbg = scenario.can_imu->format == CanImuFormat::kSbg;
    EXPECT_EQ(s->can.decoder, sbg ? daemon::CanDecoder::sbg : daemon::CanDecoder::bosch_mm7);
    // The MM7 has no clock: mapped from the receive time minus the bus latency.
    EXPECT_EQ(s->clock.mode, sbg ? daemon::ClockMode::automatic : daemon::ClockMode::receive_time);
    const auto* replay = std::get_if<daemon::ReplaySourceConfig>(&s->source);
    ASSERT_NE(replay, nullptr);
    EXPECT_EQ(replay->format, daemon::ReplayFormat::candump);
    EXPECT_TRUE(std::filesystem::exists(replay->file)) << replay->file;
    expect_pose_near(s->T_body_sensor, scenario.can_imu->T_body_imu, s->name);
  }
  for (const auto& cam : scenario.cameras) {
    const auto* s = config.find_sensor(cam.name);
    ASSERT_NE(s, nullptr) << cam.name;
    const auto& k = cam.params.intrinsics;
    // Written without images: the camera is there, disabled, so the folder replays as LIO.
    EXPECT_FALSE(s->enabled);
    EXPECT_EQ(s->camera.width, k.width);
    EXPECT_EQ(s->camera.height, k.height);
    EXPECT_DOUBLE_EQ(s->camera.intrinsics[0], k.fx);
    EXPECT_DOUBLE_EQ(s->camera.intrinsics[2], k.cx);
    const auto* replay = std::get_if<daemon::ReplaySourceConfig>(&s->source);
    ASSERT_NE(replay, nullptr);
    EXPECT_EQ(replay->format, daemon::ReplayFormat::euroc);
    EXPECT_TRUE(std::filesystem::is_directory(replay->file)) << replay->file;
    expect_pose_near(s->T_body_sensor, cam.T_body_cam, cam.name);
  }
}

// Every named scenario whose LiDARs are all simulated.
TEST(RunnerConfig, EveryRunnableScenarioWritesAConfigTheLoaderAccepts) {
  const auto models = simulated_models();
  int checked = 0;
  for (const auto& [name, _] : list_scenarios()) {
    const Scenario s = make_scenario(name);
    if (!std::all_of(s.lidars.begin(), s.lidars.end(),
                     [&](const LidarMount& l) { return models.contains(l.model); })) {
      continue;
    }
    check_config(s);
    ++checked;
  }
  EXPECT_GE(checked, 2);
}

// A CAN IMU as the body. Until the VLP-16 is simulated, an Avia (without its IMU) stands in for
// it: the loader rightly wants a LiDAR.
TEST(RunnerConfig, CanImuBodyConfigIsAccepted) {
  Scenario s = make_scenario("street_vehicle_vlp16");
  ASSERT_EQ(s.lidars.size(), 1u);
  if (!simulated_models().contains(s.lidars[0].model)) {
    s.lidars[0].model = "AVIA";
    s.lidars[0].name = "avia";
  }
  ASSERT_FALSE(s.lidars[0].imu);
  check_config(s);
  // The same with a Bosch MM7 on the bus, and an Xsens on a serial line beside it (its capture is
  // written, not configured: livod replay does not read serial captures yet).
  s.can_imu->format = CanImuFormat::kBoschMm7;
  s.serial_imu = SerialImuMount{};
  check_config(s);
}

}  // namespace
}  // namespace livod::sim
