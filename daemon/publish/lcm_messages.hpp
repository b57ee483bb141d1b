#pragma once
// Records (records.hpp) -> the LCM messages of docs/lcm.md. Pure functions: no clock, no I/O; the
// caller passes the time base and the message sequence numbers.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <string>

#include "daemon/publish/records.hpp"
#include "lcmtypes/bot_core/pose_t.hpp"
#include "lcmtypes/livod/cloud_t.hpp"
#include "lcmtypes/livod/health_t.hpp"
#include "lcmtypes/livod/pose_t.hpp"

namespace livod::daemon::publish {

// UNIX ns -> LCM utime (µs), rounding towards minus infinity so that utime <= time_ns / 1000 also
// before 1970 (replays of synthetic recordings start near 0).
[[nodiscard]] std::int64_t utime_of(std::int64_t unix_ns);

// Unit quaternion of a rotation matrix, with w >= 0 (q and -q are the same rotation; LCM
// consumers comparing quaternions get one of them).
[[nodiscard]] Eigen::Quaterniond unit_quaternion(const Eigen::Matrix3d& R);

// livod.pose_t. `sequence`: the message's number on its channel.
[[nodiscard]] ::livod::pose_t to_lcm_pose(const PoseRecord& pose, const Frames& frames,
                                          TimeBase time_base, std::int64_t sequence);

// libbot2's bot_core.pose_t: position, velocity, orientation as livod.pose_t; rotation_rate in the
// world ("local") frame, R_world_body * omega_body, as libbot2 defines it; accel in the world
// frame without gravity.
[[nodiscard]] ::bot_core::pose_t to_bot_core_pose(const PoseRecord& pose, TimeBase time_base);

// livod.health_t. Counters above INT64_MAX (never in practice) saturate.
[[nodiscard]] ::livod::health_t to_lcm_health(const HealthRecord& health, std::int64_t sequence);

// Which of n points a cloud of at most max_points keeps: the i-th kept point is
// floor(i * n / kept), i.e. evenly spread over the scan. max_points >= 1.
[[nodiscard]] std::size_t decimated_count(std::size_t n, std::size_t max_points);
[[nodiscard]] std::size_t decimated_index(std::size_t i, std::size_t n, std::size_t kept);

// livod.cloud_t: fields x, y, z, intensity (FLOAT32, offsets 0, 4, 8, 12; point_step 16,
// little-endian), decimated to at most max_points (>= 1, std::invalid_argument otherwise; capped
// at 2^24 points, 256 MiB being LCM's message size limit).
[[nodiscard]] ::livod::cloud_t to_lcm_cloud(const CloudRecord& cloud,
                                            const std::string& world_frame, TimeBase time_base,
                                            std::int64_t sequence, std::size_t max_points);

// The int8 codes of the messages.
[[nodiscard]] std::int8_t status_code(PoseStatus status);
[[nodiscard]] std::int8_t source_code(PoseSource source);
[[nodiscard]] std::int8_t state_code(SensorState state);
[[nodiscard]] std::int8_t clock_quality_code(ClockQuality quality);
[[nodiscard]] std::int8_t thread_state_code(ThreadState state);

}  // namespace livod::daemon::publish
