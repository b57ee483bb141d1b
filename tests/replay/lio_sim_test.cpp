// LIO on simulated Livox captures: simulator -> wire format -> livod's decoder -> estimator,
// compared with the simulator's ground truth. Sensor clocks are ideal here (mapped = sensor time
// + a known epoch); clock mapping has its own tests and the replay command's tests cover it.

#include <gtest/gtest.h>

#include "core/so3.hpp"
#include "drivers/livox/livox_decoder.hpp"
#include "estimator/pipeline.hpp"
#include "tests/replay/ideal_clock_sinks.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace livod {
namespace {

struct RunResult {
  double rmse_m = 0.0;
  double max_m = 0.0;
  double max_rot_deg = 0.0;
  int frames = 0;
  double path_m = 0.0;
};

RunResult run_livox(const std::string& scenario_name, const std::string& model, double duration) {
  sim::Scenario scenario = sim::make_scenario(scenario_name);
  const sim::World world = sim::make_room_world(1);
  const sim::Trajectory trajectory(scenario.trajectory);
  const sim::LidarMount& mount = scenario.lidars.at(0);
  sim::SimLidarOptions options;
  options.range = mount.range;
  options.imu_noise = mount.imu_noise;
  options.seed = 7;
  auto lidar = sim::make_sim_lidar(model, options);
  sim::SceneContext scene{&world, &trajectory, mount.T_body_sensor};

  estimator::PipelineOptions po;
  po.T_imu_lidar = mount.T_body_sensor;  // body = the LiDAR's internal IMU
  po.params.lio.blind = 0.3;
  estimator::LioPipeline pipeline(po);
  livox::LivoxDecoder decoder(*livox::livox_model(model), livox::LivoxDecoderOptions{});

  std::vector<estimator::PipelineOutput> outputs;
  const drivers::DecoderSinks sinks = test::ideal_clock_sinks(pipeline);
  sim::SimOutputs out;
  out.on_datagram = [&](sim::SimDatagram&& d) {
    decoder.on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
  };
  for (double t = 0.0; t < duration; t += 0.1) {
    lidar->run(t, t + 0.1, scene, out);
    pipeline.process([&](const estimator::PipelineOutput& o) { outputs.push_back(o); });
  }
  EXPECT_TRUE(pipeline.initialised()) << pipeline.init_status();

  RunResult r;
  r.frames = static_cast<int>(outputs.size());
  if (outputs.empty()) return r;
  // The estimator's world is the IMU frame at initialisation (no gravity alignment): compare
  // poses relative to the ground truth at that time.
  const double t_init = outputs.front().t.seconds();
  const Eigen::Isometry3d T_gt0_inv = trajectory.at(0.0).T_world_body().inverse();
  double sum = 0.0;
  Eigen::Vector3d last = trajectory.at(0.0).p_world;
  for (const auto& o : outputs) {
    const double t = o.t.seconds();
    const Eigen::Isometry3d gt = T_gt0_inv * trajectory.at(t).T_world_body();
    const double e = (gt.translation() - o.x.p_world_imu).norm();
    const double rot = so3::log(gt.linear().transpose() * o.x.R_world_imu).norm() * 180.0 / M_PI;
    sum += e * e;
    if (std::getenv("LIVOD_TEST_VERBOSE") != nullptr) {
      std::printf("t %.2f err %.4f rot %.3f matched %d/%d iters %d degen %d ratio %.4f\n", t, e,
                  rot, o.report.matched, o.report.used_points, o.report.iterations,
                  o.report.degeneracy.degenerate ? 1 : 0, o.report.degeneracy.translation_ratio);
    }
    r.max_m = std::max(r.max_m, e);
    r.max_rot_deg = std::max(r.max_rot_deg, rot);
    r.path_m += (trajectory.at(t).p_world - last).norm();
    last = trajectory.at(t).p_world;
  }
  (void)t_init;
  r.rmse_m = std::sqrt(sum / static_cast<double>(outputs.size()));
  return r;
}

TEST(LioSim, AviaHandheldRoom) {
  const RunResult r = run_livox("room_handheld_avia", "AVIA", 20.0);
  RecordProperty("rmse_m", std::to_string(r.rmse_m));
  std::printf("Avia room: %d frames, path %.1f m, ATE RMSE %.4f m, max %.4f m, max rot %.3f deg\n",
              r.frames, r.path_m, r.rmse_m, r.max_m, r.max_rot_deg);
  EXPECT_GT(r.frames, 150);
  // The estimator's own defaults (FAST-LIVO2's, not the daemon's per-model ones) and no alignment:
  // 29.9 mm with the downsampler's nearest-to-centroid choice, 31.2 mm with its noise-blind one
  // (stop 30; docs/estimator.md "Long drives"). The daemon's Avia defaults: ReplayAccuracy.
  EXPECT_LT(r.rmse_m, 0.035);
}

TEST(LioSim, Mid360HandheldRoom) {
  const RunResult r = run_livox("room_handheld_mid360", "MID-360", 20.0);
  std::printf(
      "Mid-360 room: %d frames, path %.1f m, ATE RMSE %.4f m, max %.4f m, max rot %.3f deg\n",
      r.frames, r.path_m, r.rmse_m, r.max_m, r.max_rot_deg);
  EXPECT_GT(r.frames, 150);
  EXPECT_LT(r.rmse_m, 0.03);
}

}  // namespace
}  // namespace livod
