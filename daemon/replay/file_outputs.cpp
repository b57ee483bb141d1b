#include "daemon/replay/file_outputs.hpp"

#include <algorithm>

namespace livod::daemon::replay {

void FrameSeries::add(const estimator::FrameReport& r, double cpu_ms) {
  const auto& t = r.timings;
  total.push_back(static_cast<float>(t.total_ms));
  cpu.push_back(static_cast<float>(cpu_ms));
  propagate.push_back(static_cast<float>(t.propagate_ms));
  undistort.push_back(static_cast<float>(t.undistort_ms));
  downsample.push_back(static_cast<float>(t.downsample_ms));
  residuals.push_back(static_cast<float>(t.residuals_ms));
  update.push_back(static_cast<float>(t.update_ms));
  map.push_back(static_cast<float>(t.map_ms));
  raw_points.push_back(static_cast<float>(r.raw_points));
  used_points.push_back(static_cast<float>(r.used_points));
  matched.push_back(static_cast<float>(r.matched));
  iterations.push_back(static_cast<float>(r.iterations));
}

void FrameSeries::summarise(ReplaySummary& s) const {
  s.frame_ms = distribution(total);
  s.frame_cpu_ms = distribution(cpu);
  s.propagate_ms = distribution(propagate);
  s.undistort_ms = distribution(undistort);
  s.downsample_ms = distribution(downsample);
  s.residuals_ms = distribution(residuals);
  s.update_ms = distribution(update);
  s.map_ms = distribution(map);
  s.raw_points = distribution(raw_points);
  s.used_points = distribution(used_points);
  s.matched = distribution(matched);
  s.iterations = distribution(iterations);
}

FileOutputs::FileOutputs(const Paths& paths, double map_cell_m, std::size_t map_max_points)
    : map_(map_cell_m, map_max_points) {
  if (!paths.trajectory.empty()) trajectory_.emplace(paths.trajectory);
  if (!paths.frames_csv.empty()) frames_.emplace(paths.frames_csv);
}

void FileOutputs::on_frame(const runtime::FrameOutput& frame) {
  const auto& o = frame.estimate;
  if (trajectory_) trajectory_->write(o.t, o.x.R_world_imu, o.x.p_world_imu);
  ++poses_;
  for (const auto& p : o.registered_world) map_.add(p.p);
  map_bytes_peak_ = std::max(map_bytes_peak_, o.report.map.bytes);
  if (frames_) {
    frames_->add(frame.index, o.report, frame.cpu_ms, map_.size(), current_rss_bytes());
  }
  series_.add(o.report, frame.cpu_ms);
}

void FileOutputs::close() {
  if (trajectory_) trajectory_->close();
  if (frames_) frames_->close();
}

}  // namespace livod::daemon::replay
