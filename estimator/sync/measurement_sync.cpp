#include "estimator/sync/measurement_sync.hpp"

#include <utility>

namespace livod::estimator {

MappedTime MeasurementSync::scan_end(const LidarScan& scan) {
  return scan.start.mapped + Nanoseconds(scan.span_ns());
}

void MeasurementSync::start(MappedTime t) {
  started_ = true;
  last_update_ = t;
  last_imu_ = t;
  imu_.clear();
  scans_.clear();
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
  scans_.push_back(QueuedScan{std::move(scan), end});
  if (scans_.size() > params_.max_queued_scans) {
    scans_.pop_front();
    ++counters_.scans_queue_overflow;
  }
}

bool MeasurementSync::next(MeasurementGroup& group) {
  if (!started_ || scans_.empty() || imu_.empty()) return false;
  const MappedTime t = scans_.front().end;
  if (imu_.back().stamp.mapped < t) return false;  // the IMU has not reached the scan end yet
  group.kind = MeasurementGroup::Kind::lidar;
  group.t_update = t;
  group.scan = std::move(scans_.front().scan);
  scans_.pop_front();
  group.imu.clear();
  while (!imu_.empty() && imu_.front().stamp.mapped <= t) {
    group.imu.push_back(imu_.front());
    imu_.pop_front();
  }
  group.imu_after.reset();
  if (!imu_.empty()) group.imu_after = imu_.front();
  last_update_ = t;
  ++counters_.groups;
  return true;
}

}  // namespace livod::estimator
