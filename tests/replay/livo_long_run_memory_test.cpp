// Bounded memory of LIVO over a quarter of an hour: a 15-minute flight (4.5 km at 5 m/s along a
// simulated street, 1-9 m high: the street_drone_os1_64 trajectory, Ouster OS1-64 with its
// internal IMU and a forward camera) streamed from the simulator into the pipeline without files.
// FAST-LIVO2 never prunes its visual map and keeps every image a patch came from alive (about 2 GB
// per 4 GB bag); here the visual map slides with the LiDAR map and has a point budget, and patches
// are small pixel blocks. The visual map must stop growing after warm-up, points must leave it as
// the car drives on, the process's resident memory must be flat, and the odometry must still be
// right at the end.
//
// The camera is the rig camera at half resolution (320x256) and 5 Hz, to keep the rendering of
// 4500 frames affordable; the visual update per image does the same work at any rate, and a
// 5 Hz camera with a 10 Hz LiDAR also exercises LIO updates between images. The LiDAR has the
// OS1-64's plain range model (its datasheet noise, no beam divergence): memory does not depend on
// sensor realism (the accuracy tests check that), and the divergence's three sub-rays per beam
// made ray casting two thirds of this test's time.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>

#include "core/so3.hpp"
#include "daemon/replay/timing_report.hpp"
#include "daemon/worker_pool.hpp"
#include "drivers/ouster/ouster_factory.hpp"
#include "estimator/pipeline.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/sim/camera_sim.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace livod {
namespace {

constexpr double kDurationS = 15.0 * 60.0 + 10.0;
constexpr double kSpeedMps = 5.0;  // the drone's forward speed
constexpr double kCameraRateHz = 5.0;

struct MinuteSample {
  double rss_mib = 0.0;
  double visual_mib = 0.0;
  std::size_t visual_points = 0;
  double lidar_map_mib = 0.0;
  double error_m = 0.0;
};

double max_over(const std::vector<MinuteSample>& m, std::size_t begin, std::size_t end,
                double MinuteSample::*field) {
  double best = 0.0;
  for (std::size_t i = begin; i < std::min(end, m.size()); ++i) best = std::max(best, m[i].*field);
  return best;
}

TEST(LivoLongRunMemory, FifteenMinuteDriveWithCameraStaysBounded) {
  const sim::Scenario drone = sim::make_scenario("street_drone_os1_64");
  const sim::LidarMount mount = drone.lidars.at(0);
  sim::CameraMount cam = drone.cameras.at(0);
  cam.params.intrinsics = cam.params.intrinsics.scaled(0.5);
  cam.params.rate_hz = kCameraRateHz;
  const sim::World world = sim::make_street_world(7, kSpeedMps * kDurationS + 100.0);
  const sim::Trajectory trajectory(drone.trajectory);
  sim::SimLidarOptions sim_options;
  sim_options.range = sim::plain_range_model(mount.range);
  sim_options.imu_noise = mount.imu_noise;
  sim_options.seed = 11;
  auto lidar = sim::make_sim_lidar("OS1-64", sim_options);
  const sim::SceneContext scene{&world, &trajectory, mount.T_body_sensor};
  drivers::DecoderConfig decoder_config;
  decoder_config.model = "OS";
  decoder_config.metadata = lidar->write_side_files(test::temp_dir("livo-long-run"), "os1").at(0);
  const auto decoder = drivers::ouster::make_ouster_decoder(decoder_config);
  const sim::CameraSim camera(cam.params);

  daemon::WorkerPool pool(2);
  estimator::PipelineOptions po;
  po.T_imu_lidar = mount.T_body_sensor;
  // The OS1 street rig settings of replay_accuracy_test.cpp / long_run_memory_test.cpp.
  po.params.lio.point_filter_num = 4;
  po.params.lio.filter_size_surf = 0.5;
  po.params.vio.grid_cell_px = 20;  // 16 x 13 cells on 320 x 256
  po.runner = &pool;
  estimator::vio::VioCamera vio_camera;
  vio_camera.intrinsics = cam.params.intrinsics;
  vio_camera.T_imu_cam = cam.T_body_cam;
  po.camera = vio_camera;
  estimator::LioPipeline pipeline(po);

  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) {
    LidarScan copy = s;
    copy.start.mapped = MappedTime(s.start.sensor.ns);
    pipeline.add_scan(std::move(copy));
  };
  sinks.on_imu = [&](const ImuSample& m) {
    ImuSample copy = m;
    copy.stamp.mapped = MappedTime(m.stamp.sensor.ns);
    pipeline.add_imu(copy);
  };
  sim::SimOutputs out;
  out.on_datagram = [&](sim::SimDatagram&& d) {
    decoder->on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
  };

  const Eigen::Isometry3d T_gt0_inv = trajectory.at(0.0).T_world_body().inverse();
  std::vector<MinuteSample> minutes;
  std::size_t frames = 0;
  std::size_t images = 0;
  std::size_t visual_updates = 0;
  double sq_error_sum = 0.0;
  double next_frame = 0.5 / kCameraRateHz;
  double next_minute = 60.0;
  std::mt19937_64 rng(5);
  sim::GreyImage grey;
  double last_error = 0.0;
  for (double t = 0.0; t < kDurationS; t += 0.1) {
    lidar->run(t, t + 0.1, scene, out);
    while (next_frame < t + 0.1) {
      const double tf = next_frame;
      next_frame += 1.0 / kCameraRateHz;
      camera.render(world, trajectory.at(tf).T_world_body() * cam.T_body_cam,
                    camera.exposure_at(tf), rng, grey);
      ImageFrame frame;
      frame.image = cv::Mat(grey.height, grey.width, CV_8UC1, grey.pixels.data()).clone();
      frame.stamp.mapped = MappedTime::from_seconds(tf);
      set_exposure_times(frame);
      pipeline.add_image(std::move(frame));
      ++images;
    }
    pipeline.process([&](const estimator::PipelineOutput& o) {
      ++frames;
      visual_updates += o.report.vio.updated ? 1 : 0;
      const Eigen::Isometry3d gt = T_gt0_inv * trajectory.at(o.t.seconds()).T_world_body();
      last_error = (o.x.p_world_imu - gt.translation()).norm();
      sq_error_sum += last_error * last_error;
    });
    if (t + 0.1 >= next_minute) {
      next_minute += 60.0;
      ASSERT_NE(pipeline.vio(), nullptr);
      const auto visual = pipeline.vio()->map().stats();
      minutes.push_back({static_cast<double>(daemon::replay::current_rss_bytes()) / 1048576.0,
                         static_cast<double>(visual.bytes) / 1048576.0, visual.points,
                         static_cast<double>(pipeline.map().stats().bytes) / 1048576.0,
                         last_error});
    }
  }
  ASSERT_TRUE(pipeline.initialised()) << pipeline.init_status();
  ASSERT_GE(minutes.size(), 15U);
  for (std::size_t m = 0; m < minutes.size(); ++m) {
    const auto& s = minutes[m];
    std::printf(
        "[livo long-run] minute %2zu: RSS %6.1f MiB, visual map %5.1f MiB (%zu points), LiDAR map "
        "%5.1f MiB, position error %.3f m\n",
        m + 1, s.rss_mib, s.visual_mib, s.visual_points, s.lidar_map_mib, s.error_m);
  }
  const auto visual = pipeline.vio()->map().stats();
  const double path_m = kSpeedMps * (kDurationS - 5.0);
  const double rmse = std::sqrt(sq_error_sum / static_cast<double>(frames));
  std::printf(
      "[livo long-run] %zu frames, %zu images (%zu visual updates) over %.0f m: position RMSE "
      "%.3f m (%.4f %%); visual points created %llu, left the sliding box %llu, evicted by the "
      "budget %llu\n",
      frames, images, visual_updates, path_m, rmse, 100.0 * rmse / path_m,
      static_cast<unsigned long long>(visual.created),
      static_cast<unsigned long long>(visual.removed_sliding),
      static_cast<unsigned long long>(visual.removed_budget));

  // The camera was used all along.
  EXPECT_GT(static_cast<double>(visual_updates), 0.8 * static_cast<double>(images));
  // The visual map slid with the car and holds what the box and the budget allow.
  EXPECT_GT(visual.removed_sliding, visual.created / 2);
  EXPECT_LE(visual.points, 20000U);
  const double visual_warm = max_over(minutes, 2, 5, &MinuteSample::visual_mib);
  const double visual_late = max_over(minutes, 5, minutes.size(), &MinuteSample::visual_mib);
  EXPECT_LT(visual_late, 1.25 * visual_warm) << "the visual map keeps growing";
  // Flat resident memory after warm-up.
  const double rss_warm = max_over(minutes, 2, 5, &MinuteSample::rss_mib);
  const double rss_late = max_over(minutes, 5, minutes.size(), &MinuteSample::rss_mib);
  EXPECT_LT(rss_late, rss_warm + 24.0) << "resident memory keeps growing";
  // Still on track after 4.5 km (the LIO-only drive's bound, long_run_memory_test.cpp).
  EXPECT_LT(rmse, 0.002 * path_m);
}

}  // namespace
}  // namespace livod
