#pragma once
// The replay's outputs, written synchronously on the scheduler's thread (deterministic: nothing
// is dropped, equal inputs give equal bytes): OUTDIR/trajectory.txt (TUM), the map accumulated
// for OUTDIR/map.pcd and the per-frame table OUTDIR/frames.csv, plus the per-frame series the
// timing report summarises. With a camera the map holds the points the images saw, coloured from
// them (FAST-LIVO2's coloured map; frames without an image add none), the visual update's
// per-image series are kept, and with a debug folder every image is drawn with its patches
// (debug_images.hpp).

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

// The per-image columns of the visual update (4 bytes each per image).
struct VioSeries {
  std::vector<float> total, pyramid, selection, update, map, patches;

  void add(const estimator::vio::VioReport& v);
  void summarise(ReplaySummary& summary) const;
};

class FileOutputs final : public runtime::OutputSink {
 public:
  struct Paths {
    std::filesystem::path trajectory;  // empty: not written
    std::filesystem::path frames_csv;  // empty: not written
  };
  struct CameraOutputs {
    bool colored_map = false;            // map.pcd from the coloured points of image groups
    std::filesystem::path debug_images;  // --debug-images folder (created); empty: none
    int patch_size = 8;                  // estimator.vio.patch_size, for the drawing
  };
  // Creates the files (livod::Error when one cannot be created).
  FileOutputs(const Paths& paths, double map_cell_m, std::size_t map_max_points,
              CameraOutputs camera);

  void on_frame(const runtime::FrameOutput& frame) override;

  // Closes the files (livod::Error when data could not be written).
  void close();

  [[nodiscard]] const MapAccumulator& map() const { return map_; }
  [[nodiscard]] const FrameSeries& series() const { return series_; }
  [[nodiscard]] const VioSeries& vio_series() const { return vio_series_; }
  [[nodiscard]] bool colored_map() const { return camera_.colored_map; }
  // The inverse exposure of the newest image that the visual update processed (1 before any).
  [[nodiscard]] double inv_exposure() const { return inv_exposure_; }
  [[nodiscard]] std::size_t poses() const { return poses_; }
  [[nodiscard]] std::size_t map_bytes_peak() const { return map_bytes_peak_; }

 private:
  std::optional<TrajectoryWriter> trajectory_;
  std::optional<FrameTable> frames_;
  MapAccumulator map_;
  FrameSeries series_;
  CameraOutputs camera_;
  VioSeries vio_series_;
  double inv_exposure_ = 1.0;
  std::size_t poses_ = 0;
  std::size_t map_bytes_peak_ = 0;
};

}  // namespace livod::daemon::replay
