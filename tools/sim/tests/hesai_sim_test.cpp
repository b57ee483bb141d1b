// Decoding the simulator's PandarXT-32 captures with livod's Hesai decoder (and the angle
// correction file the simulator writes) gives back every simulated point (4 mm quantisation is
// applied by the simulator; float rounding remains) at its firing time on the sensor clock, in
// whole turns, with no loss.

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <tuple>

#include "drivers/hesai/hesai_decoder.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::sim {
namespace {

TEST(HesaiSim, Xt32CaptureDecodesToTheSimulatedPoints) {
  // The VLP-16 street scenario's vehicle with an XT32 on its roof instead; a UTC sensor clock.
  const Scenario scenario = make_scenario("street_vehicle_vlp16");
  const World world = make_street_world(1, scenario.street_length_m);
  const Trajectory trajectory(scenario.trajectory);
  SimLidarOptions options;
  options.clock =
      ClockFaults{.offset_s = 1.7e9, .skew_ppm = 0.0, .jitter_s = 0.0, .reset_at_s = -1};
  options.range.sigma_m = 0.01;
  options.range.min_range_m = 0.5;
  options.range.max_range_m = 100.0;
  options.seed = 11;
  auto lidar = make_sim_lidar("PANDARXT32", options);
  EXPECT_EQ(lidar->model(), "PANDARXT32");
  EXPECT_FALSE(simulated_lidar_has_imu("PANDARXT32"));
  const SceneContext scene{&world, &trajectory, scenario.lidars.at(0).T_body_sensor};

  std::vector<SimDatagram> datagrams;
  std::vector<SimPointTruth> truths;
  SimOutputs out;
  out.on_datagram = [&](SimDatagram&& d) { datagrams.push_back(std::move(d)); };
  out.on_point = [&](const SimPointTruth& p) { truths.push_back(p); };
  lidar->run(8.03, 8.35, scene, out);  // driving at 10 m/s
  ASSERT_FALSE(datagrams.empty());
  const auto side = lidar->write_side_files(test::temp_dir("hesai-sim"), "xt32");
  ASSERT_EQ(side.size(), 1U);

  drivers::hesai::HesaiOptions ho;
  ho.model = drivers::hesai::Model::kPandarXT32;
  ho.calibration_file = side[0];
  drivers::hesai::HesaiDecoder decoder(ho);
  std::vector<LidarScan> scans;
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) { scans.push_back(s); };
  for (const auto& d : datagrams) decoder.on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
  decoder.flush(sinks);
  EXPECT_EQ(decoder.counters().decode_errors, 0U);
  EXPECT_EQ(decoder.counters().sequence_gaps, 0U);
  EXPECT_EQ(decoder.hesai_counters().late_packets, 0U);
  // From 8.03 s to 8.35 s: a partial turn, two whole turns from 0 degrees, a partial turn.
  ASSERT_EQ(scans.size(), 4U);
  EXPECT_EQ(decoder.counters().incomplete_scans, 2U);

  // Truth by (ring, firing time on the sensor clock, to the microsecond); the clock is the one
  // the simulator stamped with (no jitter: deterministic).
  SensorClock sensor_clock(options.clock, 0);
  std::map<std::tuple<int, std::int64_t>, const SimPointTruth*> by_key;
  std::size_t valid = 0;
  for (const auto& t : truths) {
    if (!t.valid) continue;
    ++valid;
    by_key[{t.ring, sensor_clock.stamp_ns(t.t) / 1000}] = &t;
  }
  ASSERT_GT(valid, truths.size() / 3);
  std::size_t decoded = 0;
  double worst_m = 0.0;
  std::int64_t worst_ns = 0;
  for (const auto& s : scans) {
    for (std::size_t i = 0; i < s.size(); ++i) {
      ++decoded;
      // Packet stamps are whole microseconds (truncated), so the decoded time is up to 1 us
      // early, plus the simulated clock's double rounding at 1.7e9 s (0.24 us).
      const std::int64_t ns = s.start.sensor.ns + s.t_offset_ns[i];
      const SimPointTruth* t = nullptr;
      for (const std::int64_t us : {ns / 1000 - 1, ns / 1000, ns / 1000 + 1, ns / 1000 + 2}) {
        const auto it = by_key.find({s.ring[i], us});
        if (it != by_key.end() &&
            (s.point(i).cast<double>() - it->second->p_sensor).norm() < 1e-3) {
          t = it->second;
        }
      }
      ASSERT_NE(t, nullptr) << "decoded point " << i << " matches no simulated return";
      worst_m = std::max(worst_m, (s.point(i).cast<double>() - t->p_sensor).norm());
      worst_ns = std::max(worst_ns, std::abs(ns - sensor_clock.stamp_ns(t->t)));
    }
  }
  EXPECT_EQ(decoded, valid);
  EXPECT_LT(worst_m, 1e-4);
  EXPECT_LE(worst_ns, 1'300);
}

}  // namespace
}  // namespace livod::sim
