#pragma once
// Recorded, already decoded LiDAR messages -> LidarScan (dataset_lidar sensors, and packet
// LiDARs recorded as clouds). Stamps: `start.sensor` is the scan's first point on the recording's
// clock, `t_offset_ns` each point's time after it; `start.host` and `start.mapped` are left to
// the caller (the record time and the clock mapping).
//
//  livox_ros_driver/CustomMsg: point time = timebase + offset_time (ns); timebase 0 (some
//    recorders leave it unset) falls back to header.stamp. The dataset time settings do not apply.
//  sensor_msgs/PointCloud2: the per-point field `time_field` in `time_unit`:
//    time_reference relative: values are offsets. Non-negative offsets count from the scan start,
//      which is header.stamp (stamp: start) or header.stamp - the largest offset (stamp: end,
//      NTU-VIRAL's convention); any negative offset means the values count from header.stamp
//      itself, whatever it marks.
//    time_reference absolute: values are point times on the recording's clock (header ignored).
//
// NaN / infinite coordinates and points at the origin (Livox "no return") are kept as invalid
// (valid = 0), as decoders keep layout. A point more than 2.1 s (the int32 ns offset range) from
// the scan start, or whose time is not a number, is dropped and counted: no real scan spans that
// long. Each point keeps its laser (CustomMsg line, PointCloud2 "ring"/"line" field or the row of
// an organised cloud) for the per-ring point filter.

#include <cstdint>
#include <vector>

#include "core/measurement.hpp"
#include "daemon/config/config.hpp"
#include "io/rosbag/point_cloud.hpp"
#include "io/rosbag/ros_messages.hpp"

namespace livod::daemon::replay {

struct CloudConversionStats {
  std::uint64_t messages = 0;
  std::uint64_t points = 0;          // points emitted (valid or not)
  std::uint64_t invalid_points = 0;  // NaN / origin points (emitted with valid = 0)
  std::uint64_t dropped_points = 0;  // beyond the int32 offset range from the scan start
  std::uint64_t empty_messages = 0;  // messages without points (no scan emitted)
  // Messages whose stamps are garbage (a timebase or every point time beyond 73 years): skipped.
  std::uint64_t bad_time_messages = 0;
};

// Nanoseconds per unit of a per-point time field.
double nanoseconds_per(TimeUnit unit);

// Both return false (and leave `out` cleared) for a message without any point.
bool custom_msg_to_scan(const io::rosbag::livox_ros_driver::CustomMsg& msg, LidarScan& out,
                        CloudConversionStats& stats);

// `scratch` is reused between calls (no allocation in steady state). Throws livod::Error when
// the cloud lacks x/y/z or the configured time field (the message names the fields it has).
bool point_cloud_to_scan(const io::rosbag::sensor_msgs::PointCloud2& cloud,
                         const DatasetConfig& dataset, std::vector<io::rosbag::CloudPoint>& scratch,
                         LidarScan& out, CloudConversionStats& stats);

}  // namespace livod::daemon::replay
