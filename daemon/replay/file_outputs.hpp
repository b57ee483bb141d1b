#pragma once
// The replay's outputs, written synchronously on the scheduler's thread (deterministic: nothing
// is dropped, equal inputs give equal bytes): OUTDIR/trajectory.txt (TUM), the map accumulated
// for OUTDIR/map.pcd and the per-frame table OUTDIR/frames.csv, plus the per-frame series the
// timing report summarises.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <vector>

#include "daemon/replay/map_accumulator.hpp"
#include "daemon/replay/timing_report.hpp"
#include "daemon/replay/trajectory_writer.hpp"
#include "daemon/runtime/output_sink.hpp"

namespace livod::daemon::replay {

// The per-frame columns kept for the report's distributions (4 bytes each per frame).
struct FrameSeries {
  std::vector<float> total, cpu, propagate, undistort, downsample, residuals, update, map;
  std::vector<float> raw_points, used_points, matched, iterations;

  void add(const estimator::FrameReport& r, double cpu_ms);
  // Fills the distributions of `summary` from the series.
  void summarise(ReplaySummary& summary) const;
};

class FileOutputs final : public runtime::OutputSink {
 public:
  struct Paths {
    std::filesystem::path trajectory;  // empty: not written
    std::filesystem::path frames_csv;  // empty: not written
  };
  // Creates the files (livod::Error when one cannot be created).
  FileOutputs(const Paths& paths, double map_cell_m, std::size_t map_max_points);

  void on_frame(const runtime::FrameOutput& frame) override;

  // Closes the files (livod::Error when data could not be written).
  void close();

  [[nodiscard]] const MapAccumulator& map() const { return map_; }
  [[nodiscard]] const FrameSeries& series() const { return series_; }
  [[nodiscard]] std::size_t poses() const { return poses_; }
  [[nodiscard]] std::size_t map_bytes_peak() const { return map_bytes_peak_; }

 private:
  std::optional<TrajectoryWriter> trajectory_;
  std::optional<FrameTable> frames_;
  MapAccumulator map_;
  FrameSeries series_;
  std::size_t poses_ = 0;
  std::size_t map_bytes_peak_ = 0;
};

}  // namespace livod::daemon::replay
