#include "estimator/sync/measurement_sync.hpp"

#include <gtest/gtest.h>

namespace livod::estimator {
namespace {

constexpr std::int64_t kMs = 1'000'000;

ImuSample imu_at(std::int64_t t_ns) {
  ImuSample s;
  s.stamp.mapped = MappedTime(t_ns);
  s.gyro_rad_s = Eigen::Vector3d(static_cast<double>(t_ns) * 1e-9, 0.0, 0.0);  // tags the sample
  return s;
}

// A scan starting at `start_ns` whose points span [0, span_ns] (out of time order on purpose:
// the end is the latest point, not the last one).
LidarScan scan_at(std::int64_t start_ns, std::int32_t span_ns, std::uint32_t sequence) {
  LidarScan s;
  s.start.mapped = MappedTime(start_ns);
  s.sequence = sequence;
  s.push_back(1, 0, 0, 0, 0, 0, 0);
  s.push_back(1, 1, 0, 0, 0, 0, span_ns);
  s.push_back(1, 2, 0, 0, 0, 0, span_ns / 2);
  return s;
}

TEST(MeasurementSync, GroupsAtScanEndPartitionTheImu) {
  MeasurementSync sync;
  sync.start(MappedTime(0));
  // 200 Hz IMU over 0.5 s and five 10 Hz scans; scans arrive after their last point (as a driver
  // completes them), IMU as it comes.
  std::vector<MeasurementGroup> groups;
  MeasurementGroup g;
  std::uint32_t seq = 0;
  for (std::int64_t t = 5 * kMs; t <= 520 * kMs; t += 5 * kMs) {
    sync.add_imu(imu_at(t));
    if ((t - 5 * kMs) % (100 * kMs) == 0 && t > 100 * kMs) {
      const std::int64_t start = t - 105 * kMs;
      sync.add_scan(scan_at(start, static_cast<std::int32_t>(99 * kMs), seq++));
    }
    while (sync.next(g)) groups.push_back(g);
  }
  ASSERT_EQ(groups.size(), 5U);
  std::int64_t previous = 0;
  std::size_t samples = 0;
  for (std::size_t k = 0; k < groups.size(); ++k) {
    const auto& group = groups[k];
    EXPECT_EQ(group.kind, MeasurementGroup::Kind::lidar);
    EXPECT_EQ(group.scan.sequence, k);
    const std::int64_t end = static_cast<std::int64_t>(k) * 100 * kMs + 99 * kMs;
    EXPECT_EQ(group.t_update.ns, end);
    ASSERT_FALSE(group.imu.empty());
    // Every sample of (previous update, t_update], in order, and nothing else.
    EXPECT_GT(group.imu.front().stamp.mapped.ns, previous);
    EXPECT_LE(group.imu.front().stamp.mapped.ns, previous + 5 * kMs);
    EXPECT_LE(group.imu.back().stamp.mapped.ns, end);
    for (std::size_t i = 1; i < group.imu.size(); ++i) {
      EXPECT_EQ(group.imu[i].stamp.mapped.ns - group.imu[i - 1].stamp.mapped.ns, 5 * kMs);
    }
    ASSERT_TRUE(group.imu_after.has_value());
    EXPECT_GT(group.imu_after->stamp.mapped.ns, end);
    EXPECT_EQ(group.imu_after->stamp.mapped.ns, group.imu.back().stamp.mapped.ns + 5 * kMs);
    samples += group.imu.size();
    previous = end;
  }
  EXPECT_EQ(samples, 99U);  // 5 ms .. 495 ms
  EXPECT_EQ(sync.counters().groups, 5U);
  EXPECT_EQ(sync.counters().scans_out_of_order, 0U);
}

TEST(MeasurementSync, AScanWaitsForTheImuToReachItsEnd) {
  MeasurementSync sync;
  sync.start(MappedTime(0));
  MeasurementGroup g;
  sync.add_scan(scan_at(0, static_cast<std::int32_t>(100 * kMs), 0));
  EXPECT_FALSE(sync.next(g));  // no IMU at all
  sync.add_imu(imu_at(50 * kMs));
  sync.add_imu(imu_at(99 * kMs));
  EXPECT_FALSE(sync.next(g));  // IMU stops short of the scan end
  sync.add_imu(imu_at(100 * kMs));
  ASSERT_TRUE(sync.next(g));  // a sample exactly at the end completes the group
  EXPECT_EQ(g.imu.size(), 3U);
  EXPECT_FALSE(g.imu_after.has_value());
  EXPECT_FALSE(sync.next(g));
}

TEST(MeasurementSync, OutOfOrderInputIsDroppedAndCounted) {
  MeasurementSync sync;
  sync.start(MappedTime(10 * kMs));
  sync.add_imu(imu_at(5 * kMs));  // before the start (the initialisation's last sample)
  sync.add_imu(imu_at(20 * kMs));
  sync.add_imu(imu_at(20 * kMs));  // duplicate stamp
  sync.add_imu(imu_at(15 * kMs));  // backwards
  EXPECT_EQ(sync.counters().imu_out_of_order, 3U);
  EXPECT_EQ(sync.queued_imu(), 1U);

  sync.add_scan(scan_at(-100 * kMs, static_cast<std::int32_t>(99 * kMs), 0));  // ends before start
  sync.add_scan(scan_at(0, static_cast<std::int32_t>(100 * kMs), 1));
  sync.add_scan(scan_at(-50 * kMs, static_cast<std::int32_t>(140 * kMs), 2));  // ends earlier
  sync.add_scan(LidarScan{});                                                  // empty
  EXPECT_EQ(sync.counters().scans_out_of_order, 2U);
  EXPECT_EQ(sync.counters().scans_in, 4U);
  EXPECT_EQ(sync.queued_scans(), 1U);
  MeasurementGroup g;
  sync.add_imu(imu_at(120 * kMs));
  ASSERT_TRUE(sync.next(g));
  EXPECT_EQ(g.scan.sequence, 1U);
  // A scan ending at or before the update just made is now out of order too.
  sync.add_scan(scan_at(0, static_cast<std::int32_t>(100 * kMs), 3));
  EXPECT_EQ(sync.counters().scans_out_of_order, 3U);
}

TEST(MeasurementSync, QueuesAreBounded) {
  MeasurementSync sync(SyncParams{.max_queued_scans = 4, .max_queued_imu = 10});
  sync.start(MappedTime(0));
  for (int k = 0; k < 10; ++k) {
    sync.add_scan(
        scan_at(k * 100 * kMs, static_cast<std::int32_t>(99 * kMs), static_cast<std::uint32_t>(k)));
  }
  for (int k = 1; k <= 25; ++k) sync.add_imu(imu_at(k * kMs));
  EXPECT_EQ(sync.queued_scans(), 4U);
  EXPECT_EQ(sync.queued_imu(), 10U);
  EXPECT_EQ(sync.counters().scans_queue_overflow, 6U);
  EXPECT_EQ(sync.counters().imu_queue_overflow, 15U);
  // The oldest were dropped: the queue now starts with scan 6.
  for (int k = 26; k <= 1000; ++k) sync.add_imu(imu_at(k * kMs));
  MeasurementGroup g;
  ASSERT_TRUE(sync.next(g));
  EXPECT_EQ(g.scan.sequence, 6U);
}

TEST(MeasurementSync, NothingBeforeStart) {
  MeasurementSync sync;
  sync.add_scan(scan_at(0, static_cast<std::int32_t>(100 * kMs), 0));
  sync.add_imu(imu_at(200 * kMs));
  MeasurementGroup g;
  EXPECT_FALSE(sync.next(g));
  sync.start(MappedTime(0));  // start clears what came before it
  EXPECT_EQ(sync.queued_scans(), 0U);
  EXPECT_EQ(sync.queued_imu(), 0U);
}

}  // namespace
}  // namespace livod::estimator
