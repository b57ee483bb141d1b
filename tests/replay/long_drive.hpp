#pragma once
// A long street drive streamed from the simulator through livod's Ouster decoder into the LIO
// pipeline, without files (a 15-minute capture would be 9 GB): an Ouster OS1-64 with its internal
// IMU on the street scenarios' car (10 m/s, weaving in the lane), the estimator configured as the
// daemon configures it for an OS1-64 with no `estimator:` section (estimator_defaults.hpp). Used by
// the memory and drift tests of long runs.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <vector>

#include "core/so3.hpp"
#include "daemon/config/estimator_defaults.hpp"
#include "daemon/replay/timing_report.hpp"
#include "daemon/worker_pool.hpp"
#include "drivers/ouster/ouster_factory.hpp"
#include "estimator/pipeline.hpp"
#include "tests/replay/ideal_clock_sinks.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::test {

struct DriveMinute {
  double rss_mib = 0.0;
  double map_mib = 0.0;
  std::size_t root_voxels = 0;
  std::size_t retired_voxels = 0;
  Eigen::Vector3d error = Eigen::Vector3d::Zero();  // position error against the ground truth
};

struct DriveResult {
  std::vector<DriveMinute> minutes;
  std::size_t frames = 0;
  std::size_t map_bytes_max = 0;
  double path_m = 0.0;  // ground-truth distance driven while the estimator ran
  double rmse_m = 0.0;  // position error over all frames, no alignment
  Eigen::Vector3d end_error = Eigen::Vector3d::Zero();  // at the last frame, per axis
  // Attitude error at the last frame, world frame: Log(R_est R_true^T) (x roll, y pitch, rad).
  Eigen::Vector3d end_rotation_error = Eigen::Vector3d::Zero();
  estimator::VoxelMapStats map;
};

struct DriveOptions {
  double duration_s = 60.0;
  bool sliding = true;
  std::uint64_t seed = 11;
};

inline DriveResult run_street_drive(const DriveOptions& options) {
  constexpr double kSpeedMps = 10.0;  // the street scenarios' vehicle
  constexpr std::size_t kFramesPerMinute = 600;
  const sim::Scenario street = sim::make_scenario("street_vehicle_os1_128");
  const sim::LidarMount mount = sim::make_scenario("room_handheld_os1_64").lidars.at(0);
  // The drive measures drift over distance, not sensor realism (the accuracy tests do): the
  // OS1-64's plain range model (its datasheet noise, no divergence or detection limit) and the
  // street without traffic or foliage keep the 9 km inside CI's time.
  const sim::World world =
      sim::make_street_world(7, kSpeedMps * options.duration_s + 100.0, sim::WorldOptions{});
  const sim::Trajectory trajectory(street.trajectory);
  sim::SimLidarOptions sim_options;
  sim_options.range = sim::plain_range_model(mount.range);
  sim_options.imu_noise = mount.imu_noise;
  sim_options.seed = options.seed;
  auto lidar = sim::make_sim_lidar("OS1-64", sim_options);
  const sim::SceneContext scene{&world, &trajectory, mount.T_body_sensor};
  drivers::DecoderConfig decoder_config;
  decoder_config.model = "OS";
  decoder_config.metadata = lidar->write_side_files(temp_dir("long-drive"), "os1").at(0);
  const auto decoder = drivers::ouster::make_ouster_decoder(decoder_config);

  daemon::WorkerPool pool(2);
  estimator::PipelineOptions po;
  po.T_imu_lidar = mount.T_body_sensor;  // body = the OS1's internal IMU
  // What `livod run` configures for an OS1-64 without an estimator section.
  daemon::estimator_settings_for(daemon::lidar_model_facts("OS1-64"), "OS1-64", {}, po.params);
  po.params.map.sliding = options.sliding;
  // Without sliding, the whole street: the voxel budget (map.max_voxels) would otherwise evict
  // the farthest voxels once the map outgrows it, which is sliding by another name.
  if (!options.sliding) po.params.map.max_voxels = std::numeric_limits<std::size_t>::max();
  po.runner = &pool;
  estimator::LioPipeline pipeline(po);

  const drivers::DecoderSinks sinks = ideal_clock_sinks(pipeline);
  sim::SimOutputs out;
  out.on_datagram = [&](sim::SimDatagram&& d) {
    decoder->on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
  };

  // The estimator's world is the IMU frame at initialisation (the platform stands still until
  // then): compare against the ground truth relative to its first pose.
  const Eigen::Isometry3d T_gt0_inv = trajectory.at(0.0).T_world_body().inverse();
  DriveResult r;
  double sq_error_sum = 0.0;
  double first_t = -1.0;
  double last_t = 0.0;
  for (double t = 0.0; t < options.duration_s; t += 0.1) {
    lidar->run(t, t + 0.1, scene, out);
    pipeline.process([&](const estimator::PipelineOutput& o) {
      ++r.frames;
      r.map_bytes_max = std::max(r.map_bytes_max, o.report.map.bytes);
      const double t_out = o.t.seconds();
      if (first_t < 0.0) first_t = t_out;
      last_t = t_out;
      const Eigen::Isometry3d gt = T_gt0_inv * trajectory.at(t_out).T_world_body();
      const Eigen::Vector3d error = o.x.p_world_imu - gt.translation();
      sq_error_sum += error.squaredNorm();
      r.end_error = error;
      r.end_rotation_error = so3::log(o.x.R_world_imu * gt.linear().transpose());
      if (r.frames % kFramesPerMinute == 0) {
        const auto map = pipeline.map().stats();
        r.minutes.push_back({static_cast<double>(daemon::replay::current_rss_bytes()) / 1048576.0,
                             static_cast<double>(map.bytes) / 1048576.0, map.root_voxels,
                             map.retired_voxels, error});
      }
    });
  }
  EXPECT_TRUE(pipeline.initialised()) << pipeline.init_status();
  r.map = pipeline.map().stats();
  // Distance driven between the first and the last frame, on the ground truth.
  for (double t = std::max(first_t, 0.0); t < last_t; t += 0.05) {
    r.path_m +=
        (trajectory.at(std::min(t + 0.05, last_t)).p_world - trajectory.at(t).p_world).norm();
  }
  r.rmse_m = r.frames > 0 ? std::sqrt(sq_error_sum / static_cast<double>(r.frames)) : 0.0;
  for (std::size_t m = 0; m < r.minutes.size(); ++m) {
    const auto& s = r.minutes[m];
    std::printf(
        "[long-drive] minute %2zu: RSS %6.1f MiB, estimator map %5.1f MiB (%zu root voxels, %zu "
        "awaiting release), position error %.3f m (%+.3f %+.3f %+.3f)\n",
        m + 1, s.rss_mib, s.map_mib, s.root_voxels, s.retired_voxels, s.error.norm(), s.error.x(),
        s.error.y(), s.error.z());
  }
  std::printf(
      "[long-drive] %s sliding: %zu frames over %.0f m: end error (%+.3f %+.3f %+.3f) m = "
      "(%+.4f %+.4f %+.4f) %% of the distance, RMSE %.3f m; %llu voxels dropped (sliding, "
      "budget)\n",
      options.sliding ? "with" : "without", r.frames, r.path_m, r.end_error.x(), r.end_error.y(),
      r.end_error.z(), 100.0 * r.end_error.x() / r.path_m, 100.0 * r.end_error.y() / r.path_m,
      100.0 * r.end_error.z() / r.path_m, r.rmse_m,
      static_cast<unsigned long long>(r.map.removed_voxels));
  std::printf("[long-drive] end attitude error (roll, pitch, yaw) %+.3f %+.3f %+.3f mrad\n",
              1e3 * r.end_rotation_error.x(), 1e3 * r.end_rotation_error.y(),
              1e3 * r.end_rotation_error.z());
  return r;
}

// The bound on a long drive: the end-point error within 0.05 % of the distance driven, in
// every axis.
constexpr double kEndErrorFraction = 0.0005;

inline void expect_end_error_within_bound(const DriveResult& r) {
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_LE(std::abs(r.end_error[axis]), kEndErrorFraction * r.path_m)
        << "axis " << axis << ": end error " << r.end_error[axis] << " m over " << r.path_m << " m";
  }
}

}  // namespace livod::test
