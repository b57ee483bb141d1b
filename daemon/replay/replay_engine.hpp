#pragma once
// Offline replay, as fast as possible and deterministic (the same recordings and configuration
// give byte-identical trajectories): the runtime's scheduler loop (daemon/runtime/scheduler.hpp)
// driven by one thread over recorded sources until they are exhausted, writing its outputs
// synchronously; the estimator spreads its residuals and map refits over a worker pool without
// changing a bit of the result.
//
//   recordings ──(one source per sensor: pcap / candump / bag topic)──▶ runtime::Scheduler (merge
//   on the recording's receive time, decoders, clock domains, LioPipeline) ──▶ FileOutputs ──▶
//   trajectory, map, timing report
//
// Which sensors the estimator takes: runtime::assign_roles (the body IMU, one LiDAR and, with
// estimator.vio.enabled, the first enabled camera: its frames come from EuRoC/ASL or plain image
// folders or ROS1 bag image topics, image_sources.hpp). Other sensors are not replayed (the
// result's notes say so).
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
  // --debug-images: a folder (created) for the visual update's images with their patches drawn;
  // empty: none. Needs a camera the visual update uses (livod::Error otherwise).
  std::filesystem::path debug_images_dir;
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
  // The configuration's outputs.trajectory / map_pcd / timing_report, when set: copies of the
  // files above.
  std::vector<std::filesystem::path> configured_outputs;
  // SIGINT or SIGTERM stopped the replay early (0: it ran to the end). The outputs are complete
  // for what was replayed until then.
  int interrupted_by = 0;
};

// Replays the configuration's recordings. SIGINT and SIGTERM are taken by the replay (blocked in
// the calling thread while it runs): they stop it early, with complete outputs. The configuration
// must have loaded without errors. Throws livod::Error when the configuration cannot be replayed
// (no body IMU or LiDAR recording, an unsupported driver/format pair, unreadable files) and
// livod::FormatError for corrupt recordings.
ReplayResult run_replay(const LivodConfig& config, const ReplayOptions& options);

}  // namespace livod::daemon::replay
