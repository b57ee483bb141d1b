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
  start_ = t;
  last_update_ = t;
  last_imu_ = t;
  last_image_ = t;
  map_start_ = t;
  imu_.clear();
  scans_.clear();
  images_.clear();
  lidars_.clear();
  if (params_.lidars > 1) lidars_.resize(params_.lidars);
}

std::size_t MeasurementSync::queued_scans() const {
  std::size_t n = scans_.size();
  for (const LidarQueue& q : lidars_) n += q.scans.size();
  return n;
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

void MeasurementSync::add_scan(LidarScan scan, std::size_t lidar) {
  if (params_.lidars > 1) {
    add_scan_of(std::move(scan), lidar);
    return;
  }
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
    ++(t <= map_start_ ? counters_.images_before_map : counters_.images_late);
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

void MeasurementSync::take_points_until(MappedTime t, std::deque<QueuedScan>& queue,
                                        LidarScan& out) {
  out.clear();
  if (queue.empty()) return;
  const LidarScan& first = queue.front().scan;
  out.start = first.start;
  out.sequence = first.sequence;
  while (!queue.empty() && queue.front().begin <= t) {
    QueuedScan& q = queue.front();
    if (q.end <= t) {
      append_points(q.scan, t, true, out);
      queue.pop_front();
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
    take_points_until(t, scans_, group.scan);
  }
  take_imu_until(t, group);
  last_update_ = t;
  ++counters_.groups;
  return true;
}

bool MeasurementSync::next(MeasurementGroup& group) {
  if (!started_ || imu_.empty()) return false;
  if (params_.lidars > 1) return next_of_lidars(group);
  const MappedTime imu_reach = imu_.back().stamp.mapped;
  if (!images_enabled_) {
    if (scans_.empty() || imu_reach < scans_.front().end) return false;
    return next_lidar(group, 0);
  }
  while (!images_.empty() && images_.front().mid_exposure <= last_update_) {
    ++(images_.front().mid_exposure <= map_start_ ? counters_.images_before_map
                                                  : counters_.images_late);
    images_.pop_front();
  }
  // The first group is the first whole scan, as without a camera: the map starts from a full
  // sweep. An image group cut earlier would start it from a slice, and the next slices, which see
  // what the map does not hold yet, would pull the state away (10 to 35 cm at rest with a 20 Hz
  // camera beside a 10 Hz Ouster). The images up to that scan's end have no map to update against.
  if (counters_.groups == 0) {
    if (scans_.empty() || imu_reach < scans_.front().end) return false;
    map_start_ = scans_.front().end;
    while (!images_.empty() && images_.front().mid_exposure <= map_start_) {
      images_.pop_front();
      ++counters_.images_before_map;
    }
    return next_lidar(group, 0);
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
  take_points_until(t_img, scans_, group.scan);
  take_imu_until(t_img, group);
  group.image = std::move(images_.front());
  images_.pop_front();
  last_update_ = t_img;
  ++counters_.groups;
  ++counters_.image_groups;
  return true;
}

void MeasurementSync::add_scan_of(LidarScan scan, std::size_t lidar) {
  ++counters_.scans_in;
  if (scan.empty() || lidar >= params_.lidars) return;
  if (lidars_.size() < params_.lidars) lidars_.resize(params_.lidars);
  LidarQueue& q = lidars_[lidar];
  const MappedTime end = scan_end(scan);
  if (q.seen && end <= q.reach) {
    ++counters_.scans_out_of_order;
    return;
  }
  MappedTime begin = scan_begin(scan);
  q.seen = true;
  q.reach = end;
  q.span = end - begin;
  if (started_ && end <= last_update_) {
    // A LiDAR late by more than a scan: the filter has passed all of its points.
    ++counters_.scans_late;
    counters_.points_late += scan.size();
    return;
  }
  if (started_ && begin <= last_update_) {
    // Its earlier points precede the filter's time (it did not wait for this LiDAR): the rest is
    // used.
    const std::size_t before = scan.size();
    keep_after(scan, last_update_);
    counters_.points_late += before - scan.size();
    begin = scan_begin(scan);
  }
  q.scans.push_back(QueuedScan{std::move(scan), begin, end});
  if (q.scans.size() > params_.max_queued_scans) {
    q.scans.pop_front();
    ++counters_.scans_queue_overflow;
  }
}

bool MeasurementSync::next_of_lidars(MeasurementGroup& group) {
  const MappedTime imu_reach = imu_.back().stamp.mapped;
  // The update time: the earliest scan end queued.
  std::size_t first = lidars_.size();
  for (std::size_t l = 0; l < lidars_.size(); ++l) {
    if (lidars_[l].scans.empty()) continue;
    if (first == lidars_.size() ||
        lidars_[l].scans.front().end < lidars_[first].scans.front().end) {
      first = l;
    }
  }
  if (first == lidars_.size()) return false;
  const MappedTime t = lidars_[first].scans.front().end;
  if (imu_reach < t) return false;
  // Every LiDAR's points up to t must have arrived, unless that LiDAR is late.
  const Nanoseconds wait = from_seconds(params_.lidar_wait_s);
  for (const LidarQueue& q : lidars_) {
    const bool arrived = q.seen && q.reach >= t;
    // A LiDAR without a scan yet is waited for at the start only (its first scan may come a scan
    // after the others'); one that never sends is late from then on.
    const bool late = q.seen ? imu_reach - q.reach > q.span + wait
                             : imu_reach - start_ > from_seconds(kFirstScanWaitS) + wait;
    if (!arrived && !late) return false;
  }
  group.kind = MeasurementGroup::Kind::lidar;
  group.t_update = t;
  group.lidar = first;
  group.scan_sequence = lidars_[first].scans.front().scan.sequence;
  group.scan.clear();
  group.scans.resize(lidars_.size());
  for (std::size_t l = 0; l < lidars_.size(); ++l) {
    take_points_until(t, lidars_[l].scans, group.scans[l]);
  }
  take_imu_until(t, group);
  last_update_ = t;
  ++counters_.groups;
  return true;
}

}  // namespace livod::estimator
