// Decoding the simulator's Livox captures with livod's decoders gives back exactly the simulated
// points (after the wire format's millimetre quantisation, which the simulator applies) and IMU
// samples (within float32 precision).

#include <gtest/gtest.h>

#include "drivers/livox/livox_decoder.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::sim {
namespace {

void round_trip(const std::string& scenario_name, const std::string& model) {
  const Scenario scenario = make_scenario(scenario_name);
  const World world = make_room_world(1);
  const Trajectory trajectory(scenario.trajectory);
  const LidarMount& mount = scenario.lidars.at(0);
  SimLidarOptions options;
  options.clock = mount.clock;
  options.range = mount.range;
  options.imu_noise = mount.imu_noise;
  options.seed = 99;
  auto lidar = make_sim_lidar(model, options);
  SceneContext scene{&world, &trajectory, mount.T_body_sensor};

  std::vector<SimDatagram> datagrams;
  std::vector<SimPointTruth> truths;
  std::vector<SimImuTruth> imu_truths;
  SimOutputs out;
  out.on_datagram = [&](SimDatagram&& d) { datagrams.push_back(std::move(d)); };
  out.on_point = [&](const SimPointTruth& p) { truths.push_back(p); };
  out.on_imu = [&](const SimImuTruth& m) { imu_truths.push_back(m); };
  lidar->run(4.0, 4.35, scene, out);  // while moving
  ASSERT_FALSE(datagrams.empty());

  livox::LivoxDecoder decoder(*livox::livox_model(model), livox::LivoxDecoderOptions{});
  std::vector<Eigen::Vector3f> decoded;
  std::vector<ImuSample> imu;
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) {
    for (std::size_t i = 0; i < s.size(); ++i) decoded.push_back(s.point(i));
  };
  sinks.on_imu = [&](const ImuSample& m) { imu.push_back(m); };
  for (const auto& d : datagrams) {
    decoder.on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
  }
  decoder.flush(sinks);
  EXPECT_EQ(decoder.counters().decode_errors, 0u);
  EXPECT_EQ(decoder.counters().sequence_gaps, 0u);

  std::vector<Eigen::Vector3f> expected;
  for (const auto& t : truths) {
    if (t.valid) expected.push_back(t.p_sensor.cast<float>());
  }
  ASSERT_GT(expected.size(), truths.size() / 2) << "too few returns in the room";
  ASSERT_EQ(decoded.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(decoded[i], expected[i]) << "point " << i;
  }
  ASSERT_EQ(imu.size(), imu_truths.size());
  for (std::size_t i = 0; i < imu.size(); ++i) {
    EXPECT_LT((imu[i].gyro_rad_s - imu_truths[i].gyro_rad_s).norm(), 1e-6);
    EXPECT_LT((imu[i].accel_m_s2 - imu_truths[i].accel_m_s2).norm(), 1e-5);
  }
}

TEST(LivoxSim, AviaCaptureDecodesToTheSimulatedPoints) {
  round_trip("room_handheld_avia", "AVIA");
}

TEST(LivoxSim, Mid360CaptureDecodesToTheSimulatedPoints) {
  round_trip("room_handheld_mid360", "MID-360");
}

}  // namespace
}  // namespace livod::sim
