#pragma once
// Offline replay, as fast as possible and deterministic (the same recordings and configuration
// give byte-identical trajectories): one thread reads, decodes and runs the filter; the estimator
// spreads its residuals and map refits over a worker pool without changing a bit of the result.
//
//   recordings ──(one ReplaySource per sensor: pcap / candump / bag topic)──▶ k-way merge on the
//   recording's receive time (ties: configuration order) ──▶ the sensor's decoder ──▶ its
//   ClockDomain (+ time_offset_s) ──▶ LioPipeline ──▶ trajectory, map, timing report
//
// The estimator takes the body IMU (body_frame) and one LiDAR: the body IMU's own LiDAR when the
// body is an internal IMU ("<lidar>.imu"), else the first enabled LiDAR. T_imu_lidar is that
// LiDAR's T_body_sensor (the body IMU defines the body frame). With estimator.vio.enabled it also
// takes the first enabled camera (image_sources.hpp: EuRoC/ASL or plain image folders, ROS1 bag
// image topics), through that camera's clock domain, for the visual update; T_imu_cam is its
// T_body_sensor. Other sensors are not replayed (the result's notes say so). The LiDAR's internal
// IMU, when enabled, feeds its clock domain even when it is not the body IMU.
//
// Outputs in ReplayOptions::out_dir (created): trajectory.txt (TUM, mapped measurement time,
// body frame in the estimator's world = the IMU frame at initialisation), map.pcd (binary PCD,
// registered downsampled points through a bounded voxel filter; with a camera x y z rgb, the
// points seen in the images coloured from them, as FAST-LIVO2's coloured map), timing.txt,
// timing.json and frames.csv (see timing_report.hpp); with debug_images_dir, one PNG per image
// with its patches drawn (debug_images.hpp).

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/replay/timing_report.hpp"

namespace livod::daemon::replay {

struct ReplayOptions {
  std::filesystem::path out_dir;
  std::vector<std::string> inputs;         // command-line recordings (input_assignment.hpp)
  bool progress = false;                   // draw the progress line on stderr
  double map_cell_m = 0.2;                 // map.pcd voxel filter cell
  std::size_t map_max_points = 2'000'000;  // map.pcd budget (<= 88 MB, map_accumulator.hpp)
  // Stop once this much recording (receive time) has been replayed; <= 0: everything.
  double max_duration_s = 0.0;
  // Estimator threads; < 0: the configuration's estimator.threads (0 there: one per core).
  int threads = -1;
  // --debug-images: a folder (created) for the visual update's images with their patches drawn;
  // empty: none.
  std::filesystem::path debug_images_dir;
};

struct ReplayResult {
  ReplaySummary summary;
  std::vector<std::string> notes;  // sensors not used and why
  std::filesystem::path trajectory;
  std::filesystem::path map;
  std::filesystem::path timing_text;
  std::filesystem::path timing_json;
  std::filesystem::path frames_csv;
};

// Replays the configuration's recordings. The configuration must have loaded without errors.
// Throws livod::Error when the configuration cannot be replayed (no body IMU or LiDAR recording,
// an unsupported driver/format pair, unreadable files) and livod::FormatError for corrupt
// recordings.
ReplayResult run_replay(const LivodConfig& config, const ReplayOptions& options);

}  // namespace livod::daemon::replay
