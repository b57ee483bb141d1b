#pragma once
// The replay's timing report (OUTDIR/timing.txt for people, OUTDIR/timing.json for scripts and
// tests) and its per-frame table (OUTDIR/frames.csv). Per-frame figures are the estimator's own
// stage timings (estimator::FrameTimings); wall, decode and estimator totals are measured around
// the replay loop; memory comes from the kernel (getrusage peak RSS, /proc/self/statm now).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "estimator/pipeline.hpp"
#include "io/output_file.hpp"

namespace livod::daemon::replay {

// Order statistics of one per-frame quantity (nearest-rank percentiles).
struct Distribution {
  std::size_t count = 0;
  double mean = 0.0;
  double p50 = 0.0;
  double p95 = 0.0;
  double p99 = 0.0;
  double max = 0.0;
};
Distribution distribution(std::vector<float> values);

struct ClockSummary {
  std::string mode;        // direct, free_running, receive_time
  std::string quality;     // coarse, fine, lost
  double offset_s = 0.0;   // mapped - sensor time at the newest sample
  double skew_ppm = 0.0;   // (a - 1) * 1e6: a sensor clock running slow by 20 ppm reads +20
  double jitter_us = 0.0;  // median absolute deviation of the receive residuals
  double residual_median_us = 0.0;
  std::uint64_t observations = 0;
  std::uint64_t resets = 0;
  std::uint64_t rejected = 0;
  double time_offset_s = 0.0;  // the configured offset added after mapping
};

struct SensorSummary {
  std::string name;
  std::string role;  // e.g. "lidar + body imu", "body imu"
  std::string file;
  std::string counters;  // the source's summary line
  std::uint64_t scans = 0;
  std::uint64_t imu_samples = 0;
  std::uint64_t images = 0;  // frames handed to the estimator
  ClockSummary clock;
};

struct ReplaySummary {
  std::string config_file;
  std::size_t frames = 0;  // poses written
  std::string init_status;
  estimator::PipelineCounters counters;
  // Per frame (estimator stages, ms). frame_ms is wall time (what a live system sees, inflated
  // when other processes take the CPU); frame_cpu_ms is the CPU time of the frame over all threads
  // (it exceeds the wall time when the worker pool keeps both cores busy).
  Distribution frame_ms, frame_cpu_ms, propagate_ms, undistort_ms, downsample_ms, residuals_ms,
      update_ms, map_ms;
  // Per frame (counts).
  Distribution raw_points, used_points, matched, iterations;
  std::uint64_t degenerate_frames = 0;
  // Whole run.
  double recording_s = 0.0;  // receive-time span of the events replayed
  double wall_s = 0.0;
  double decode_s = 0.0;         // reading + decoding + clock mapping
  double estimator_s = 0.0;      // LioPipeline::process
  double output_s = 0.0;         // trajectory, map accumulation, frames.csv
  double realtime_factor = 0.0;  // recording_s / wall_s
  std::size_t peak_rss_bytes = 0;
  std::size_t final_rss_bytes = 0;
  estimator::VoxelMapStats map;  // at the end
  std::size_t map_bytes_peak = 0;
  std::size_t exported_points = 0;
  std::uint64_t exported_dropped = 0;  // points in new cells after the budget was spent
  std::uint64_t exported_outside = 0;  // points beyond the map.pcd cell grid (not mapped)
  double exported_grid_half_extent_m = 0.0;
  std::size_t exported_budget = 0;
  std::vector<SensorSummary> sensors;
  // The visual update, per image group (empty without a camera): its time and split, the
  // patches it used, the visual map at the end and the inverse exposure of the last image.
  Distribution vio_ms, vio_pyramid_ms, vio_selection_ms, vio_update_ms, vio_map_ms, vio_patches;
  estimator::vio::VisualMapStats visual_map;
  double inv_exposure = 1.0;
};

std::string format_timing_text(const ReplaySummary& s);
std::string format_timing_json(const ReplaySummary& s);

// Peak resident set size of this process (getrusage), bytes.
std::size_t peak_rss_bytes();
// Current resident set size (/proc/self/statm), bytes; 0 when unavailable.
std::size_t current_rss_bytes();

// OUTDIR/frames.csv, one row per estimator frame, written as frames come.
class FrameTable {
 public:
  // Throws livod::Error if the file cannot be created.
  explicit FrameTable(const std::filesystem::path& path);
  void add(std::size_t frame, const estimator::FrameReport& r, double cpu_ms,
           std::size_t exported_points, std::size_t rss_bytes);
  // Throws livod::Error if the data could not be written.
  void close();

 private:
  io::OutputFile file_;  // NAME.partial until close()
};

}  // namespace livod::daemon::replay
