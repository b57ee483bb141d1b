// A rig whose body IMU is on a serial line: the simulator writes the IMU's byte stream as a livod
// serial capture (reads of random sizes, so messages are torn across reads, with corrupted
// messages and line noise), `livod replay` feeds it through the same stream decoder as the live
// serial source and the IMU's own clock domain (its sensor clock offset and skewed against the
// host), and the trajectory is evaluated against ground truth. Xsens MTi (MTData2) and VectorNav
// VN-100 (binary output). The LiDAR is a Livox Mid-360 with its internal IMU switched off.

#include <gtest/gtest.h>

#include "tests/replay/sim_replay.hpp"

namespace livod {
namespace {

constexpr double kDurationS = 10.0;
constexpr double kHandheldAteM = 0.03;  // the handheld target (docs/replay.md)

sim::Scenario serial_body_rig(sim::SerialImuProtocol protocol) {
  sim::Scenario s = sim::make_scenario("room_handheld_mid360");
  s.name = protocol == sim::SerialImuProtocol::kXsensMtData2 ? "room_mid360_xsens"
                                                             : "room_mid360_vectornav";
  s.lidars.at(0).imu = false;
  sim::SerialImuMount imu;
  imu.name = "serial_imu";
  imu.protocol = protocol;
  imu.noise.rate_hz = 400.0;
  imu.noise.gyro_bias0 = Eigen::Vector3d(0.002, -0.001, 0.0015);
  imu.noise.accel_bias0 = Eigen::Vector3d(0.03, -0.02, 0.04);
  // A free-running clock started 3.25 s before the sequence, 30 ppm slow.
  imu.clock =
      sim::ClockFaults{.offset_s = 3.25, .skew_ppm = -30.0, .jitter_s = 0.0, .reset_at_s = -1};
  imu.corrupt_probability = 0.005;
  imu.noise_probability = 0.005;
  s.serial_imu = imu;
  s.body_imu = imu.name;
  return s;
}

class SerialBodyImu : public ::testing::TestWithParam<sim::SerialImuProtocol> {};

TEST_P(SerialBodyImu, ReplaysToAnAccurateTrajectory) {
  const sim::Scenario scenario = serial_body_rig(GetParam());
  if (!test::scenario_runnable(scenario)) GTEST_SKIP() << "Mid-360 not simulated";
  const auto run = test::simulate_replay_evaluate(scenario, kDurationS, "");
  const auto& s = run.result.summary;
  ASSERT_GT(s.frames, 0U);
  EXPECT_GE(static_cast<double>(s.frames), (kDurationS - 1.0) / 0.1);
  EXPECT_EQ(s.counters.scans_out_of_order, 0U);
  EXPECT_LE(run.eval.ape.rmse, kHandheldAteM);

  // The serial IMU is the body IMU; its samples, less the corrupted messages, reached the
  // estimator, and its clock domain found the 3.25 s offset.
  const auto it = std::find_if(s.sensors.begin(), s.sensors.end(),
                               [](const auto& x) { return x.name == "serial_imu"; });
  ASSERT_NE(it, s.sensors.end());
  EXPECT_NE(it->role.find("body imu"), std::string::npos) << it->role;
  EXPECT_GT(it->imu_samples, static_cast<std::uint64_t>(0.97 * kDurationS * 400.0));
  EXPECT_LT(it->imu_samples, static_cast<std::uint64_t>(kDurationS * 400.0) + 1);
  EXPECT_NE(it->counters.find("serial capture: reads"), std::string::npos) << it->counters;
  EXPECT_EQ(it->counters.find("checksum errors 0,"), std::string::npos) << it->counters;
}

INSTANTIATE_TEST_SUITE_P(Protocols, SerialBodyImu,
                         ::testing::Values(sim::SerialImuProtocol::kXsensMtData2,
                                           sim::SerialImuProtocol::kVectorNavBinary),
                         [](const ::testing::TestParamInfo<sim::SerialImuProtocol>& param_info) {
                           return param_info.param == sim::SerialImuProtocol::kXsensMtData2
                                      ? std::string("Xsens")
                                      : std::string("VectorNav");
                         });

}  // namespace
}  // namespace livod
