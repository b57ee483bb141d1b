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
// LiDAR's T_body_sensor (the body IMU defines the body frame). Other sensors are not replayed
// (the result's notes say so). The LiDAR's internal IMU, when enabled, feeds its clock domain even
// when it is not the body IMU.
//
// Outputs in ReplayOptions::out_dir (created): trajectory.txt (TUM, mapped measurement time,
// body frame in the estimator's world = the IMU frame at initialisation), map.pcd (binary PCD,
// registered downsampled points through a bounded voxel filter), timing.txt, timing.json and
// frames.csv (see timing_report.hpp).

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/replay/timing_report.hpp"
#include "io/input_loss.hpp"

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
};

struct ReplayResult {
  ReplaySummary summary;
  std::vector<std::string> notes;  // sensors not used and why, recordings read with repairs
  io::InputLossLog losses;         // what the sources could not read of their recordings
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
