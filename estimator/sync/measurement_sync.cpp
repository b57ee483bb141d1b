#include "estimator/sync/measurement_sync.hpp"

#include <algorithm>
#include <utility>

namespace livod::estimator {
namespace {

MappedTime scan_begin(const LidarScan& scan) {
  std::int32_t first = scan.t_offset_ns.empty() ? 0 : scan.t_offset_ns.front();
  for (const auto t : scan.t_offset_ns) first = std::min(first, t);
  return scan.start.mapped + Nanoseconds(first);
}

// Appends src's points whose time is <= t (all when `all`) to dst, re-referenced to dst.start.
void append_points(const LidarScan& src, MappedTime t, bool all, LidarScan& dst) {
  const std::int64_t shift = src.start.mapped.ns - dst.start.mapped.ns;
  for (std::size_t i = 0; i < src.size(); ++i) {
    if (!all && src.point_time(i) > t) continue;
    dst.push_back(src.x[i], src.y[i], src.z[i], src.intensity[i],
                  i < src.ring.size() ? src.ring[i] : 0,
                  i < src.return_index.size() ? src.return_index[i] : 0,
                  static_cast<std::int32_t>(src.t_offset_ns[i] + shift), src.valid[i] != 0);
  }
}

// Keeps only the points after t (in place).
void keep_after(LidarScan& scan, MappedTime t) {
  std::size_t out = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (scan.point_time(i) <= t) continue;
    scan.x[out] = scan.x[i];
    scan.y[out] = scan.y[i];
    scan.z[out] = scan.z[i];
    scan.intensity[out] = scan.intensity[i];
    if (i < scan.ring.size()) scan.ring[out] = scan.ring[i];
    if (i < scan.return_index.size()) scan.return_index[out] = scan.return_index[i];
    scan.t_offset_ns[out] = scan.t_offset_ns[i];
    scan.valid[out] = scan.valid[i];
    ++out;
  }
  scan.x.resize(out);
  scan.y.resize(out);
  scan.z.resize(out);
  scan.intensity.resize(out);
  scan.ring.resize(std::min(scan.ring.size(), out));
  scan.return_index.resize(std::min(scan.return_index.size(), out));
  scan.t_offset_ns.resize(out);
  scan.valid.resize(out);
}

}  // namespace

MappedTime MeasurementSync::scan_end(const LidarScan& scan) {
  return scan.start.mapped + Nanoseconds(scan.span_ns());
}

void MeasurementSync::start(MappedTime t) {
  started_ = true;
  last_update_ = t;
  last_imu_ = t;
  last_image_ = t;
  imu_.clear();
  scans_.clear();
  images_.clear();
}

void MeasurementSync::add_imu(const ImuSample& sample) {
  ++counters_.imu_in;
  if (started_ && sample.stamp.mapped <= last_imu_) {
    ++counters_.imu_out_of_order;
    return;
  }
  last_imu_ = sample.stamp.mapped;
  imu_.push_back(sample);
  if (imu_.size() > params_.max_queued_imu) {
    imu_.pop_front();
    ++counters_.imu_queue_overflow;
  }
}

void MeasurementSync::add_scan(LidarScan scan) {
  ++counters_.scans_in;
  if (scan.empty()) return;
  const MappedTime end = scan_end(scan);
  const MappedTime newest = scans_.empty() ? last_update_ : scans_.back().end;
  if (started_ && end <= newest) {
    ++counters_.scans_out_of_order;
    return;
  }
  const MappedTime begin = scan_begin(scan);
  scans_.push_back(QueuedScan{std::move(scan), begin, end});
  if (scans_.size() > params_.max_queued_scans) {
    scans_.pop_front();
    ++counters_.scans_queue_overflow;
  }
}

void MeasurementSync::add_image(ImageFrame image) {
  if (!images_enabled_) return;
  ++counters_.images_in;
  const MappedTime t = image.mid_exposure;
  if (started_ && t <= last_image_) {
    ++counters_.images_out_of_order;
    return;
  }
  if (started_ && t <= last_update_) {
    ++counters_.images_late;
    return;
  }
  last_image_ = t;
  images_.push_back(std::move(image));
  if (images_.size() > params_.max_queued_images) {
    images_.pop_front();
    ++counters_.images_queue_overflow;
  }
}

void MeasurementSync::take_imu_until(MappedTime t, MeasurementGroup& group) {
  group.imu.clear();
  while (!imu_.empty() && imu_.front().stamp.mapped <= t) {
    group.imu.push_back(imu_.front());
    imu_.pop_front();
  }
  group.imu_after.reset();
  if (!imu_.empty()) group.imu_after = imu_.front();
}

void MeasurementSync::take_points_until(MappedTime t, LidarScan& out) {
  out.clear();
  if (scans_.empty()) return;
  const LidarScan& first = scans_.front().scan;
  out.start = first.start;
  out.sequence = first.sequence;
  while (!scans_.empty() && scans_.front().begin <= t) {
    QueuedScan& q = scans_.front();
    if (q.end <= t) {
      append_points(q.scan, t, true, out);
      scans_.pop_front();
      continue;
    }
    // The scan straddles t: its earlier points join this group, the rest wait for the next one.
    append_points(q.scan, t, false, out);
    keep_after(q.scan, t);
    q.begin = scan_begin(q.scan);
    q.cut = true;
    break;
  }
}

bool MeasurementSync::next_lidar(MeasurementGroup& group, std::size_t index) {
  const MappedTime t = scans_[index].end;
  group.kind = MeasurementGroup::Kind::lidar;
  group.t_update = t;
  if (index == 0) {
    group.scan = std::move(scans_.front().scan);
    scans_.pop_front();
  } else {
    take_points_until(t, group.scan);
  }
  take_imu_until(t, group);
  last_update_ = t;
  ++counters_.groups;
  return true;
}

bool MeasurementSync::next(MeasurementGroup& group) {
  if (!started_ || imu_.empty()) return false;
  const MappedTime imu_reach = imu_.back().stamp.mapped;
  if (!images_enabled_) {
    if (scans_.empty() || imu_reach < scans_.front().end) return false;
    return next_lidar(group, 0);
  }
  while (!images_.empty() && images_.front().mid_exposure <= last_update_) {
    images_.pop_front();
    ++counters_.images_late;
  }
  // A lidar group at the front scan's end (the next scan's when the front is the rest of a cut)
  // when no image is due for it: an image is due when it comes within the timeout and before the
  // next scan would end (a scan period later); it then takes these points.
  if (!scans_.empty()) {
    const std::size_t index = scans_.front().cut ? 1 : 0;
    if (index < scans_.size() && imu_reach >= scans_[index].end) {
      const MappedTime t_scan = scans_[index].end;
      const Nanoseconds period = scans_[index].end - scans_[index].begin;
      const MappedTime due = t_scan + std::min(from_seconds(params_.image_timeout_s), period);
      const bool image_due =
          images_.empty() ? imu_reach < due : images_.front().mid_exposure <= due;
      if (!image_due) return next_lidar(group, index);
    }
  }
  // An image whose points have all arrived (the newest scan reaches past it) and whose IMU too.
  if (images_.empty() || scans_.empty()) return false;
  const MappedTime t_img = images_.front().mid_exposure;
  if (scans_.back().end < t_img || imu_reach < t_img) return false;
  group.kind = MeasurementGroup::Kind::image;
  group.t_update = t_img;
  take_points_until(t_img, group.scan);
  take_imu_until(t_img, group);
  group.image = std::move(images_.front());
  images_.pop_front();
  last_update_ = t_img;
  ++counters_.groups;
  ++counters_.image_groups;
  return true;
}

}  // namespace livod::estimator
