#include "daemon/replay/file_outputs.hpp"

#include <algorithm>

#include "daemon/replay/debug_images.hpp"

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

void VioSeries::add(const estimator::vio::VioReport& v) {
  total.push_back(static_cast<float>(v.timings.total_ms));
  pyramid.push_back(static_cast<float>(v.timings.pyramid_ms));
  selection.push_back(static_cast<float>(v.timings.selection_ms));
  update.push_back(static_cast<float>(v.timings.update_ms));
  map.push_back(static_cast<float>(v.timings.map_ms));
  patches.push_back(static_cast<float>(v.patches));
}

void VioSeries::summarise(ReplaySummary& s) const {
  s.vio_ms = distribution(total);
  s.vio_pyramid_ms = distribution(pyramid);
  s.vio_selection_ms = distribution(selection);
  s.vio_update_ms = distribution(update);
  s.vio_map_ms = distribution(map);
  s.vio_patches = distribution(patches);
}

FileOutputs::FileOutputs(const Paths& paths, double map_cell_m, std::size_t map_max_points,
                         CameraOutputs camera)
    : map_(map_cell_m, map_max_points), camera_(std::move(camera)) {
  if (!paths.trajectory.empty()) trajectory_.emplace(paths.trajectory);
  if (!paths.frames_csv.empty()) frames_.emplace(paths.frames_csv);
  if (!camera_.debug_images.empty()) std::filesystem::create_directories(camera_.debug_images);
}

void FileOutputs::on_frame(const runtime::FrameOutput& frame) {
  const auto& o = frame.estimate;
  if (trajectory_) trajectory_->write(o.t, o.x.R_world_imu, o.x.p_world_imu);
  ++poses_;
  if (!camera_.colored_map) {
    for (const auto& p : o.registered_world) map_.add(p.p);
  } else {
    // A camera's map holds the points its images saw, coloured (frames without an image add none).
    for (std::size_t i = 0; i < o.colored_world.size() && i < o.colors.size(); ++i) {
      if (o.in_image[i] != 0) map_.add(o.colored_world[i], o.colors[i]);
    }
  }
  if (o.report.kind == estimator::MeasurementGroup::Kind::image && o.report.vio.ran) {
    vio_series_.add(o.report.vio);
    inv_exposure_ = o.report.vio.inv_exposure;
    if (!camera_.debug_images.empty() && !o.vio_grey.empty()) {
      write_debug_image(camera_.debug_images, o.t, o.vio_grey, o.report.vio.debug,
                        camera_.patch_size);
    }
  }
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
