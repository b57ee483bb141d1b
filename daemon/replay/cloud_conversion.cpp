#include "daemon/replay/cloud_conversion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace livod::daemon::replay {
namespace {

namespace rb = io::rosbag;

constexpr std::int64_t kMaxOffsetNs = std::numeric_limits<std::int32_t>::max();
// Point times beyond +-73 years of the recording clock's epoch are garbage; bounding them keeps
// every sum of two stamps inside int64 (a header stamp is below 2^62 ns).
constexpr double kMaxAbsTimeNs = 2305843009213693952.0;  // 2^61

bool usable(float x, float y, float z) {
  return std::isfinite(x) && std::isfinite(y) && std::isfinite(z) &&
         !(x == 0.0F && y == 0.0F && z == 0.0F);
}

// Appends one point whose time is `t_ns` on the recording clock; the scan start must be set.
void push_point(LidarScan& out, float x, float y, float z, float intensity, std::uint16_t ring,
                std::int64_t t_ns, CloudConversionStats& stats) {
  const std::int64_t offset = t_ns - out.start.sensor.ns;
  if (offset < 0 || offset > kMaxOffsetNs) {
    ++stats.dropped_points;
    return;
  }
  const bool valid = usable(x, y, z);
  if (!valid) ++stats.invalid_points;
  ++stats.points;
  out.push_back(x, y, z, intensity, ring, 0, static_cast<std::int32_t>(offset), valid);
}

}  // namespace

double nanoseconds_per(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::ns:
      return 1.0;
    case TimeUnit::us:
      return 1e3;
    case TimeUnit::ms:
      return 1e6;
    case TimeUnit::s:
      return 1e9;
  }
  return 1.0;
}

bool custom_msg_to_scan(const rb::livox_ros_driver::CustomMsg& msg, LidarScan& out,
                        CloudConversionStats& stats) {
  ++stats.messages;
  out.clear();
  if (msg.points.empty()) {
    ++stats.empty_messages;
    return false;
  }
  if (static_cast<double>(msg.timebase) >= kMaxAbsTimeNs) {
    ++stats.bad_time_messages;
    return false;
  }
  const std::int64_t base =
      msg.timebase != 0 ? static_cast<std::int64_t>(msg.timebase) : msg.header.stamp.to_ns();
  std::uint32_t first = std::numeric_limits<std::uint32_t>::max();
  for (const auto& p : msg.points) first = std::min(first, p.offset_time);
  out.start.sensor = SensorTime(base + first);
  out.reserve(msg.points.size());
  for (const auto& p : msg.points) {
    push_point(out, p.x, p.y, p.z, static_cast<float>(p.reflectivity), p.line,
               base + static_cast<std::int64_t>(p.offset_time), stats);
  }
  return !out.empty();
}

bool point_cloud_to_scan(const rb::sensor_msgs::PointCloud2& cloud, const DatasetConfig& dataset,
                         std::vector<rb::CloudPoint>& scratch, LidarScan& out,
                         CloudConversionStats& stats) {
  ++stats.messages;
  out.clear();
  rb::CloudFields fields;
  fields.time = dataset.time_field;
  const auto names = rb::field_names(cloud);
  auto has = [&names](const char* n) {
    return std::find(names.begin(), names.end(), n) != names.end();
  };
  fields.intensity = has("intensity") ? "intensity" : (has("reflectivity") ? "reflectivity" : "");
  // The laser of each point (point_filter_num counts per ring): Velodyne and Ouster drivers write
  // "ring", livox_ros_driver2 "line"; without either, the row of an organised cloud.
  fields.ring = has("ring") ? "ring" : (has("line") ? "line" : "");
  rb::extract_points(cloud, fields, scratch);
  if (scratch.empty()) {
    ++stats.empty_messages;
    return false;
  }

  const double scale = nanoseconds_per(dataset.time_unit);
  // A point whose time is not a number or beyond kMaxAbsTimeNs is dropped (nullopt).
  auto to_ns = [scale](double v) -> std::optional<std::int64_t> {
    const double ns = v * scale;
    if (!(std::abs(ns) < kMaxAbsTimeNs)) return std::nullopt;
    return static_cast<std::int64_t>(std::llround(ns));
  };
  std::int64_t lo = std::numeric_limits<std::int64_t>::max();
  std::int64_t hi = std::numeric_limits<std::int64_t>::min();
  for (const auto& p : scratch) {
    if (const auto t = to_ns(p.time)) {
      lo = std::min(lo, *t);
      hi = std::max(hi, *t);
    }
  }
  if (lo > hi) {  // no point with a usable time
    stats.dropped_points += scratch.size();
    ++stats.bad_time_messages;
    return false;
  }
  // Point time = base + value.
  std::int64_t base = 0;
  if (dataset.time_reference == TimeReference::relative) {
    const std::int64_t stamp = cloud.header.stamp.to_ns();
    base = (dataset.stamp == ScanStamp::end && lo >= 0) ? stamp - hi : stamp;
  }
  out.start.sensor = SensorTime(base + lo);
  out.reserve(scratch.size());
  for (const auto& p : scratch) {
    const auto t = to_ns(p.time);
    if (!t) {
      ++stats.dropped_points;
      continue;
    }
    push_point(out, p.x, p.y, p.z, p.intensity, p.ring, base + *t, stats);
  }
  return !out.empty();
}

}  // namespace livod::daemon::replay
