#pragma once
// What the scheduler thread hands to the publisher thread: the published records of
// daemon/publish/records.hpp (poses, health, clouds) with what only the runtime needs beside them
// (the receive time a latency is measured from, the frame's report for the timing report and the
// registered scan for the map). Filled in place from pre-allocated pools (record_channel.hpp).

#include <cstdint>
#include <vector>

#include "daemon/publish/records.hpp"
#include "estimator/pipeline.hpp"

namespace livod::daemon::runtime {

using publish::PoseRecord;
using publish::PoseSource;
using publish::PoseStatus;

const char* to_string(PoseStatus s);

// An IMU-rate pose.
struct ImuPoseRecord {
  PoseRecord pose;
  std::int64_t rx_ns = 0;  // host receive time of its IMU packet
};

// A filter frame. A frame whose pose.status is kSensorStale repeats the last pose for LIVOD_POSE
// subscribers while the LiDAR is silent: it is published, never written as a new frame.
struct FrameRecord {
  PoseRecord pose;
  std::int64_t rx_ns = 0;  // host receive time of the packet that completed the scan
  estimator::FrameReport report;
  double cpu_ms = 0.0;
  // The registered scan in the world frame (x y z), decimated to the record's capacity; kept only
  // when an output needs it (map, cloud).
  std::vector<float> xyz_world;
  std::size_t registered_points = 0;  // before decimation
  // The pose already left through PublisherChannels::estimates (published as soon as the update
  // ended, before the map insertion): the publisher does not publish it again.
  bool pose_published = false;
};

// The health snapshot as published; the publisher thread adds its threads, channels and latency.
using HealthRecord = publish::HealthRecord;

}  // namespace livod::daemon::runtime
