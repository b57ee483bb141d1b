// Decoding the simulator's VLP-16 capture with livod's Velodyne decoder gives back the simulated
// points (2 mm quantisation is applied by the simulator; float rounding remains).

#include <gtest/gtest.h>

#include "drivers/velodyne/velodyne_decoder.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::sim {
namespace {

TEST(VelodyneSim, Vlp16CaptureDecodesToTheSimulatedPoints) {
  const Scenario scenario = make_scenario("street_vehicle_vlp16");
  const World world = make_street_world(1, scenario.street_length_m);
  const Trajectory trajectory(scenario.trajectory);
  const LidarMount& mount = scenario.lidars.at(0);
  SimLidarOptions options;
  options.clock = mount.clock;
  options.range = mount.range;
  options.seed = 5;
  auto lidar = make_sim_lidar("VLP-16", options);
  SceneContext scene{&world, &trajectory, mount.T_body_sensor};
  std::vector<SimDatagram> datagrams;
  std::vector<SimPointTruth> truths;
  SimOutputs out;
  out.on_datagram = [&](SimDatagram&& d) { datagrams.push_back(std::move(d)); };
  out.on_point = [&](const SimPointTruth& p) { truths.push_back(p); };
  lidar->run(8.0, 8.25, scene, out);  // driving at 10 m/s
  ASSERT_FALSE(datagrams.empty());

  drivers::velodyne::VelodyneOptions vo;
  vo.model = drivers::velodyne::Model::kVlp16;
  drivers::velodyne::VelodyneDecoder decoder(vo);
  std::vector<Eigen::Vector3f> decoded;
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) {
    for (std::size_t i = 0; i < s.size(); ++i) decoded.push_back(s.point(i));
  };
  for (const auto& d : datagrams) decoder.on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
  decoder.flush(sinks);
  EXPECT_EQ(decoder.counters().decode_errors, 0u);
  EXPECT_EQ(decoder.counters().sequence_gaps, 0u);
  EXPECT_GT(decoder.velodyne_counters().position_packets, 1u);
  EXPECT_GE(decoder.counters().scans, 2u);  // 0.25 s at 10 Hz crosses at least two cuts

  std::vector<Eigen::Vector3f> expected;
  for (const auto& t : truths) {
    if (t.valid) expected.push_back(t.p_sensor.cast<float>());
  }
  ASSERT_GT(expected.size(), truths.size() / 3);
  ASSERT_EQ(decoded.size(), expected.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    worst = std::max(worst, static_cast<double>((decoded[i] - expected[i]).norm()));
  }
  EXPECT_LT(worst, 1e-4);
}

}  // namespace
}  // namespace livod::sim
