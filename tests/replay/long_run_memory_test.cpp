// Bounded memory over a quarter of an hour: a 15-minute drive (9 km at 10 m/s along a simulated
// street, Ouster OS1-64 with its internal IMU, the street_vehicle scenarios' trajectory) streamed
// from the simulator through livod's Ouster decoder into the LIO pipeline, without files (the
// capture would be 9 GB). The estimator's map must stay the size of its sliding box, its
// accounted bytes must stop growing after warm-up, the voxels it drops must be freed, and the
// process's resident memory must be flat from the third minute to the last. The odometry must
// still be right at the end: a bounded map that lost track would prove nothing.
//
// The replay engine around the estimator (sources, clock domains, map export) has its own bounded
// memory test on a shorter drive through real files: replay_memory_test.cpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "core/so3.hpp"
#include "daemon/replay/timing_report.hpp"
#include "daemon/worker_pool.hpp"
#include "drivers/ouster/ouster_factory.hpp"
#include "estimator/pipeline.hpp"
#include "tests/replay/ideal_clock_sinks.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace livod {
namespace {

constexpr double kDurationS = 15.0 * 60.0 + 10.0;
constexpr double kSpeedMps = 10.0;  // the street scenarios' vehicle
constexpr std::size_t kFramesPerMinute = 600;

struct MinuteSample {
  double rss_mib = 0.0;
  double map_mib = 0.0;
  std::size_t root_voxels = 0;
  std::size_t retired_voxels = 0;
  Eigen::Vector3d error = Eigen::Vector3d::Zero();  // position error against the ground truth
};

double max_over(const std::vector<MinuteSample>& m, std::size_t begin, std::size_t end,
                double MinuteSample::*field) {
  double best = 0.0;
  for (std::size_t i = begin; i < std::min(end, m.size()); ++i) best = std::max(best, m[i].*field);
  return best;
}

TEST(LongRunMemory, FifteenMinuteDriveStaysBounded) {
  const sim::Scenario street = sim::make_scenario("street_vehicle_os1_128");
  const sim::LidarMount mount = sim::make_scenario("room_handheld_os1_64").lidars.at(0);
  const sim::World world = sim::make_street_world(7, kSpeedMps * kDurationS + 100.0);
  const sim::Trajectory trajectory(street.trajectory);
  sim::SimLidarOptions sim_options;
  sim_options.range = mount.range;
  sim_options.imu_noise = mount.imu_noise;
  sim_options.seed = 11;
  auto lidar = sim::make_sim_lidar("OS1-64", sim_options);
  const sim::SceneContext scene{&world, &trajectory, mount.T_body_sensor};
  drivers::DecoderConfig decoder_config;
  decoder_config.model = "OS";
  decoder_config.metadata = lidar->write_side_files(test::temp_dir("long-run"), "os1").at(0);
  const auto decoder = drivers::ouster::make_ouster_decoder(decoder_config);

  daemon::WorkerPool pool(2);
  estimator::PipelineOptions po;
  po.T_imu_lidar = mount.T_body_sensor;  // body = the OS1's internal IMU
  // The OS1 street rig settings of replay_accuracy_test.cpp.
  po.params.lio.point_filter_num = 4;
  po.params.lio.filter_size_surf = 0.5;
  po.runner = &pool;
  estimator::LioPipeline pipeline(po);

  const drivers::DecoderSinks sinks = test::ideal_clock_sinks(pipeline);
  sim::SimOutputs out;
  out.on_datagram = [&](sim::SimDatagram&& d) {
    decoder->on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
  };

  // The estimator's world is the IMU frame at initialisation (the platform stands still until
  // then): compare against the ground truth relative to its first pose.
  const Eigen::Isometry3d T_gt0_inv = trajectory.at(0.0).T_world_body().inverse();
  std::vector<MinuteSample> minutes;
  std::size_t frames = 0;
  std::size_t map_bytes_max = 0;
  double sq_error_sum = 0.0;
  for (double t = 0.0; t < kDurationS; t += 0.1) {
    lidar->run(t, t + 0.1, scene, out);
    pipeline.process([&](const estimator::PipelineOutput& o) {
      ++frames;
      map_bytes_max = std::max(map_bytes_max, o.report.map.bytes);
      const Eigen::Isometry3d gt = T_gt0_inv * trajectory.at(o.t.seconds()).T_world_body();
      const Eigen::Vector3d error = o.x.p_world_imu - gt.translation();
      sq_error_sum += error.squaredNorm();
      if (frames % kFramesPerMinute == 0) {
        const auto map = pipeline.map().stats();
        minutes.push_back({static_cast<double>(daemon::replay::current_rss_bytes()) / 1048576.0,
                           static_cast<double>(map.bytes) / 1048576.0, map.root_voxels,
                           map.retired_voxels, error});
      }
    });
  }
  ASSERT_TRUE(pipeline.initialised()) << pipeline.init_status();
  ASSERT_GE(minutes.size(), 15U);
  for (std::size_t m = 0; m < minutes.size(); ++m) {
    const auto& s = minutes[m];
    std::printf(
        "[long-run] minute %2zu: RSS %6.1f MiB, estimator map %5.1f MiB (%zu root voxels, %zu "
        "awaiting release), position error %.3f m (%+.2f %+.2f %+.2f)\n",
        m + 1, s.rss_mib, s.map_mib, s.root_voxels, s.retired_voxels, s.error.norm(), s.error.x(),
        s.error.y(), s.error.z());
  }
  const auto stats = pipeline.map().stats();
  const double path_m = kSpeedMps * (kDurationS - 5.0);
  const double rmse = std::sqrt(sq_error_sum / static_cast<double>(frames));
  std::printf(
      "[long-run] %zu frames over %.0f m: position RMSE %.3f m (%.4f %% of the distance, no "
      "alignment); %llu voxels dropped by sliding\n",
      frames, path_m, rmse, 100.0 * rmse / path_m,
      static_cast<unsigned long long>(stats.removed_voxels));

  EXPECT_GE(static_cast<double>(frames), (kDurationS - 5.0) / 0.1);
  // The map slid all the way (9 km of street hold millions of voxels), kept the size of its box
  // and freed what it dropped.
  EXPECT_GT(stats.removed_voxels, 1'000'000U);
  EXPECT_LT(stats.root_voxels, 100'000U);
  EXPECT_LT(stats.retired_voxels, 100'000U);
  const double map_warm = max_over(minutes, 2, 5, &MinuteSample::map_mib);
  const double map_late = max_over(minutes, 5, minutes.size(), &MinuteSample::map_mib);
  EXPECT_LT(map_late, 1.25 * map_warm) << "the estimator's map keeps growing";
  EXPECT_LT(static_cast<double>(map_bytes_max) / 1048576.0, 1.25 * map_warm);
  // Flat after warm-up: the heap may settle, it may not grow with the distance driven.
  const double rss_warm = max_over(minutes, 2, 5, &MinuteSample::rss_mib);
  const double rss_late = max_over(minutes, 5, minutes.size(), &MinuteSample::rss_mib);
  EXPECT_LT(rss_late, rss_warm + 24.0) << "resident memory keeps growing";
  // Still on track after 9 km. Not the 36 s street target (0.05 % of the distance): over 9 km the
  // estimate drifts down, 17-20 m at the end (0.08-0.09 % RMSE, 0.2 % final), as the session's
  // starting code did too (docs/estimator.md, "Long drives"). The bounds catch a lost track.
  EXPECT_LT(rmse, 0.002 * path_m);
  EXPECT_LT(minutes.back().error.norm(), 0.005 * path_m);
}

}  // namespace
}  // namespace livod
