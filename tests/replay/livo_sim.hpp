#pragma once
// LIO and LIVO side by side on one simulated run, in-process: the simulator's LiDAR datagrams go
// through livod's decoder, its camera frames are rendered and handed over as the camera path
// would (mid-exposure stamps), and the same measurements feed two pipelines - one without a camera
// (LIO) and one with it (LIVO). Sensor clocks are ideal (mapped = sensor time = scenario time);
// clock mapping has its own tests. Both trajectories are evaluated against the ground truth as
// `livod eval` does (SE(3) alignment). The estimator runs with the LiDAR model's defaults, as the
// daemon sets them for a configuration without an `estimator:` section.

#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "daemon/config/estimator_defaults.hpp"
#include "drivers/livox/livox_decoder.hpp"
#include "drivers/ouster/ouster_factory.hpp"
#include "estimator/pipeline.hpp"
#include "tests/replay/ideal_clock_sinks.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/eval/evaluate.hpp"
#include "tools/sim/camera_sim.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::test {

struct LivoSimOptions {
  double duration_s = 15.0;
  std::uint64_t seed = 1;
  bool run_lio = true;
  bool run_livo = true;
  // Estimator settings of the rig (both pipelines), adjusted before the run.
  std::function<void(estimator::EstimatorParams&)> tune;
  // Called with every LIVO output (after it is stored).
  std::function<void(const estimator::PipelineOutput&)> on_livo;
};

struct FrameTruth {
  double t = 0.0;
  double exposure_s = 0.0;  // of the image of this group (image groups)
};

struct LivoSimRun {
  std::vector<estimator::PipelineOutput> lio;
  std::vector<estimator::PipelineOutput> livo;
  eval::EvalResult lio_eval;
  eval::EvalResult livo_eval;
  double lio_ate = 0.0;
  double livo_ate = 0.0;
  std::vector<double> image_times;  // mid-exposure times of the images produced (s)
  std::vector<double> image_exposures;
  estimator::PipelineCounters livo_counters;
};

inline eval::Trajectory to_trajectory(const std::vector<estimator::PipelineOutput>& outputs) {
  eval::Trajectory t;
  for (const auto& o : outputs) {
    t.stamps_s.push_back(o.t.seconds());
    t.poses.emplace_back(o.x.R_world_imu, o.x.p_world_imu);
  }
  return t;
}

inline eval::Trajectory groundtruth_at(const sim::Trajectory& trajectory,
                                       const std::vector<estimator::PipelineOutput>& outputs) {
  eval::Trajectory t;
  for (const auto& o : outputs) {
    const auto s = trajectory.at(o.t.seconds());
    t.stamps_s.push_back(o.t.seconds());
    t.poses.emplace_back(s.R_world_body, s.p_world);
  }
  return t;
}

inline sim::World world_of(const sim::Scenario& s) {
  switch (s.world) {
    case sim::WorldKind::kRoom:
      return sim::make_room_world(1);
    case sim::WorldKind::kCorridor:
      return sim::make_corridor_world();
    case sim::WorldKind::kCorridorSideRooms:
      return sim::make_corridor_side_rooms_world();
    case sim::WorldKind::kStreet:
      return sim::make_street_world(1, s.street_length_m);
  }
  return sim::make_room_world(1);
}

inline LivoSimRun run_livo_sim(const sim::Scenario& scenario, const LivoSimOptions& options) {
  LivoSimRun run;
  const sim::World world = world_of(scenario);
  const sim::Trajectory trajectory(scenario.trajectory);
  const sim::LidarMount& mount = scenario.lidars.at(0);
  sim::SimLidarOptions lidar_options;
  lidar_options.range = mount.range;
  lidar_options.imu_noise = mount.imu_noise;
  lidar_options.seed = options.seed * 7 + 3;
  auto lidar = sim::make_sim_lidar(mount.model, lidar_options);
  const sim::SceneContext scene{&world, &trajectory, mount.T_body_sensor};

  std::unique_ptr<drivers::LidarDecoder> decoder;
  if (mount.model.rfind("OS", 0) == 0) {
    drivers::DecoderConfig config;
    config.model = "OS";
    config.metadata = lidar->write_side_files(temp_dir("livo-" + scenario.name), mount.name).at(0);
    decoder = drivers::ouster::make_ouster_decoder(config);
  } else {
    decoder = std::make_unique<livox::LivoxDecoder>(*livox::livox_model(mount.model),
                                                    livox::LivoxDecoderOptions{});
  }

  estimator::PipelineOptions po;
  po.T_imu_lidar = mount.T_body_sensor;  // body = the LiDAR's internal IMU in these scenarios
  // The estimator as the daemon configures this model without an `estimator:` section.
  daemon::estimator_settings_for(daemon::lidar_model_facts(mount.model), mount.model, {},
                                 po.params);
  if (mount.model.rfind("OS", 0) != 0) po.params.lio.blind = 0.3;
  if (options.tune) options.tune(po.params);
  std::unique_ptr<estimator::LioPipeline> lio;
  std::unique_ptr<estimator::LioPipeline> livo;
  if (options.run_lio) lio = std::make_unique<estimator::LioPipeline>(po);
  const sim::CameraMount* cam = scenario.cameras.empty() ? nullptr : &scenario.cameras.front();
  if (options.run_livo && cam != nullptr) {
    estimator::PipelineOptions lpo = po;
    estimator::vio::VioCamera camera;
    camera.intrinsics = cam->params.intrinsics;
    camera.T_imu_cam = cam->T_body_cam;
    lpo.camera = camera;
    livo = std::make_unique<estimator::LioPipeline>(lpo);
  }

  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) {
    LidarScan copy = s;
    copy.start.mapped = MappedTime(s.start.sensor.ns);
    if (lio) lio->add_scan(copy);
    if (livo) livo->add_scan(std::move(copy));
  };
  sinks.on_imu = [&](const ImuSample& m) {
    ImuSample copy = m;
    copy.stamp.mapped = MappedTime(m.stamp.sensor.ns);
    if (lio) lio->add_imu(copy);
    if (livo) livo->add_imu(copy);
  };
  sim::SimOutputs out;
  out.on_datagram = [&](sim::SimDatagram&& d) {
    decoder->on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
  };

  std::unique_ptr<sim::CameraSim> camera_sim;
  if (cam != nullptr) camera_sim = std::make_unique<sim::CameraSim>(cam->params);
  std::mt19937_64 rng(options.seed * 31 + 5);
  const double period = cam != nullptr ? 1.0 / cam->params.rate_hz : 0.0;
  double next_frame = period / 2;
  std::uint32_t sequence = 0;
  sim::GreyImage grey;
  for (double t = 0.0; t < options.duration_s; t += 0.1) {
    lidar->run(t, t + 0.1, scene, out);
    while (cam != nullptr && next_frame < t + 0.1) {
      const double tf = next_frame;
      next_frame += period;
      if (cam->params.in_outage(tf)) continue;
      const double exposure = camera_sim->exposure_at(tf);
      run.image_times.push_back(tf);
      run.image_exposures.push_back(exposure);
      if (!livo) continue;
      const Eigen::Isometry3d T_world_cam = trajectory.at(tf).T_world_body() * cam->T_body_cam;
      camera_sim->render(world, T_world_cam, exposure, rng, grey);
      ImageFrame frame;
      frame.image = cv::Mat(grey.height, grey.width, CV_8UC1, grey.pixels.data()).clone();
      frame.stamp.sensor = SensorTime::from_seconds(tf);
      frame.stamp.host = HostTime::from_seconds(tf);
      frame.stamp.mapped = MappedTime::from_seconds(tf);
      frame.exposure = from_seconds(exposure);
      frame.sequence = sequence++;
      set_exposure_times(frame);
      livo->add_image(std::move(frame));
    }
    if (lio) lio->process([&](const estimator::PipelineOutput& o) { run.lio.push_back(o); });
    if (livo) {
      livo->process([&](const estimator::PipelineOutput& o) {
        run.livo.push_back(o);
        run.livo.back().report.vio.debug.clear();
        if (options.on_livo) options.on_livo(o);
      });
    }
  }
  auto evaluate = [&](const std::vector<estimator::PipelineOutput>& outputs, eval::EvalResult& r,
                      double& ate) {
    if (outputs.size() < 10) {
      ADD_FAILURE() << scenario.name << ": too few poses (" << outputs.size() << ")";
      return;
    }
    r = eval::evaluate(groundtruth_at(trajectory, outputs), to_trajectory(outputs),
                       eval::EvalOptions{});
    ate = r.ape.rmse;
  };
  if (lio) evaluate(run.lio, run.lio_eval, run.lio_ate);
  if (livo) {
    evaluate(run.livo, run.livo_eval, run.livo_ate);
    run.livo_counters = livo->counters();
  }
  std::size_t vio_updates = 0;
  double vio_patches = 0.0;
  for (const auto& o : run.livo) {
    if (o.report.vio.updated) {
      ++vio_updates;
      vio_patches += o.report.vio.patches;
    }
  }
  std::printf(
      "[livo] %s: %.0f s, LIO %zu poses ATE %.4f m; LIVO %zu poses ATE %.4f m, %zu visual "
      "updates (%.0f patches each), %zu images\n",
      scenario.name.c_str(), options.duration_s, run.lio.size(), run.lio_ate, run.livo.size(),
      run.livo_ate, vio_updates, vio_updates > 0 ? vio_patches / vio_updates : 0.0,
      run.image_times.size());
  return run;
}

}  // namespace livod::test
