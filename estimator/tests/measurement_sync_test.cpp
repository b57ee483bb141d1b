#include "estimator/sync/measurement_sync.hpp"

#include <gtest/gtest.h>

#include <algorithm>

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

// --- image groups (scan recombination, LIO never waiting long for a camera) ---

// A 10 Hz scan [start, start + 99 ms] with a point every millisecond; x tags the point's time.
LidarScan dense_scan(std::int64_t start_ns, std::uint32_t sequence) {
  LidarScan s;
  s.start.mapped = MappedTime(start_ns);
  s.sequence = sequence;
  for (int k = 0; k < 100; ++k) {
    const std::int64_t t = start_ns + k * kMs;
    s.push_back(static_cast<float>(static_cast<double>(t) * 1e-9), 0, 0, 0,
                static_cast<std::uint16_t>(k % 4), 0, static_cast<std::int32_t>(k * kMs));
  }
  return s;
}

ImageFrame image_at(std::int64_t t_ns) {
  ImageFrame f;
  f.stamp.mapped = MappedTime(t_ns);
  f.mid_exposure = MappedTime(t_ns);
  f.image = cv::Mat(4, 4, CV_8UC1, cv::Scalar(static_cast<double>(t_ns / kMs % 256)));
  return f;
}

// Feeds `until_ms` of a rig: 200 Hz IMU, 10 Hz scans delivered at their end, and images whose
// mid-exposure times `image_ms` says, delivered `latency_ms` later (a camera's latency); groups are
// taken every `poll_ms`. Returns the groups in order.
std::vector<MeasurementGroup> run_rig(MeasurementSync& sync, std::int64_t until_ms,
                                      const std::vector<std::int64_t>& image_ms,
                                      std::int64_t latency_ms = 20, std::int64_t poll_ms = 1) {
  std::vector<MeasurementGroup> groups;
  MeasurementGroup g;
  std::uint32_t seq = 0;
  std::size_t next_image = 0;
  for (std::int64_t t = 1; t <= until_ms; ++t) {
    if (t % 5 == 0) sync.add_imu(imu_at(t * kMs));
    if (t % 100 == 0) sync.add_scan(dense_scan((t - 100) * kMs, seq++));
    while (next_image < image_ms.size() && image_ms[next_image] + latency_ms <= t) {
      sync.add_image(image_at(image_ms[next_image++] * kMs));
    }
    if (t % poll_ms == 0) {
      while (sync.next(g)) groups.push_back(g);
    }
  }
  return groups;
}

// Every point exactly once, in the group whose (previous update, update] holds its time.
void expect_points_partitioned(const std::vector<MeasurementGroup>& groups,
                               std::int64_t last_point_ns) {
  std::int64_t previous = 0;
  std::int64_t expected_next = 0;  // points come every ms from 0
  for (const auto& g : groups) {
    std::vector<std::int64_t> times;
    for (std::size_t i = 0; i < g.scan.size(); ++i) times.push_back(g.scan.point_time(i).ns);
    std::sort(times.begin(), times.end());
    for (const auto t : times) {
      EXPECT_GT(t, previous - (previous == 0 ? 1 : 0)) << "point before the previous update";
      EXPECT_LE(t, g.t_update.ns) << "point after its group's update time";
      EXPECT_EQ(t, expected_next) << "a point lost or duplicated";
      // x tags the time the point was measured at: re-referencing kept it.
      expected_next = t + kMs;
    }
    for (std::size_t i = 0; i < g.scan.size(); ++i) {
      EXPECT_NEAR(g.scan.x[i], static_cast<double>(g.scan.point_time(i).ns) * 1e-9, 1e-6);
    }
    previous = g.t_update.ns;
  }
  EXPECT_EQ(expected_next, last_point_ns + kMs);
}

TEST(MeasurementSync, ImageGroupsCutScansAtImageTimes) {
  MeasurementSync sync;
  sync.enable_images(true);
  sync.start(MappedTime(0));
  // A 10 Hz camera in the middle of the scans.
  std::vector<std::int64_t> images;
  for (std::int64_t t = 50; t < 1000; t += 100) images.push_back(t);
  const auto groups = run_rig(sync, 1100, images);
  // The first group is the first whole scan (the map starts from a full sweep): the image before
  // its end has nothing to update against. Then one group per image up to 950 ms (the scan ending
  // at 999 ms has arrived at 1000 ms); nothing at the scan ends (an image is always due within the
  // timeout).
  ASSERT_EQ(groups.size(), images.size());
  EXPECT_EQ(groups[0].kind, MeasurementGroup::Kind::lidar);
  EXPECT_EQ(groups[0].t_update.ns, 99 * kMs);
  EXPECT_EQ(groups[0].scan.size(), 100U);
  EXPECT_EQ(sync.counters().images_before_map, 1U);
  for (std::size_t k = 1; k < groups.size(); ++k) {
    EXPECT_EQ(groups[k].kind, MeasurementGroup::Kind::image);
    EXPECT_EQ(groups[k].t_update.ns, images[k] * kMs);
    EXPECT_EQ(groups[k].image.mid_exposure.ns, images[k] * kMs);
    ASSERT_FALSE(groups[k].imu.empty());
    EXPECT_LE(groups[k].imu.back().stamp.mapped.ns, images[k] * kMs);
    ASSERT_TRUE(groups[k].imu_after);
    EXPECT_GT(groups[k].imu_after->stamp.mapped.ns, images[k] * kMs);
  }
  // The first image group holds the points from the scan end to the image, later ones 100 ms
  // each, taken from two scans (scan recombination).
  EXPECT_EQ(groups[1].scan.size(), 51U);
  EXPECT_EQ(groups[2].scan.size(), 100U);
  expect_points_partitioned(groups, 950 * kMs);
  EXPECT_EQ(sync.counters().image_groups, images.size() - 1);
  EXPECT_EQ(sync.counters().images_late, 0U);
}

// A camera faster than the LiDAR (20 Hz, a quarter scan off the scan ends) still waits for the
// first whole scan; from then on every image is a group holding half a scan.
TEST(MeasurementSync, AFastCameraStartsFromTheFirstWholeScan) {
  MeasurementSync sync;
  sync.enable_images(true);
  sync.start(MappedTime(0));
  std::vector<std::int64_t> images;
  for (std::int64_t t = 25; t < 500; t += 50) images.push_back(t);
  const auto groups = run_rig(sync, 600, images);
  ASSERT_FALSE(groups.empty());
  EXPECT_EQ(groups[0].kind, MeasurementGroup::Kind::lidar);
  EXPECT_EQ(groups[0].scan.size(), 100U);
  EXPECT_EQ(sync.counters().images_before_map, 2U);  // 25 and 75 ms
  std::vector<std::int64_t> times;
  for (std::size_t k = 1; k < groups.size(); ++k) {
    EXPECT_EQ(groups[k].kind, MeasurementGroup::Kind::image);
    times.push_back(groups[k].t_update.ns / kMs);
  }
  EXPECT_EQ(times, (std::vector<std::int64_t>{125, 175, 225, 275, 325, 375, 425, 475}));
  expect_points_partitioned(groups, 475 * kMs);
  EXPECT_EQ(sync.counters().images_late, 0U);
}

TEST(MeasurementSync, LidarGoesOnWhenImagesStopAndImagesResume) {
  MeasurementSync sync(SyncParams{.image_timeout_s = 0.15});
  sync.enable_images(true);
  sync.start(MappedTime(0));
  // Images until 350 ms, none until 1550 ms, then again.
  std::vector<std::int64_t> images = {50, 150, 250, 350};
  for (std::int64_t t = 1550; t < 2000; t += 100) images.push_back(t);
  const auto groups = run_rig(sync, 2200, images);
  std::vector<std::int64_t> lidar_ends;
  std::vector<std::int64_t> image_times;
  for (const auto& g : groups) {
    (g.kind == MeasurementGroup::Kind::lidar ? lidar_ends : image_times)
        .push_back(g.t_update.ns / kMs);
  }
  // The first scan end (99) starts the map. During the gap every scan end is an update (LiDAR
  // rate): 499 (with the rest of the scan cut at 350 ms), 599, ... 1399; 1499 waits for the
  // 1550 ms image, due before the next scan ends, which takes its points. After the last image
  // (1950 ms) the rest of its scan joins the next one: 2099, once the IMU is a scan period past it
  // without an image.
  EXPECT_EQ(lidar_ends, (std::vector<std::int64_t>{99, 499, 599, 699, 799, 899, 999, 1099, 1199,
                                                   1299, 1399, 2099}));
  EXPECT_EQ(image_times, (std::vector<std::int64_t>{150, 250, 350, 1550, 1650, 1750, 1850, 1950}));
  expect_points_partitioned(groups, 2099 * kMs);
  EXPECT_EQ(groups[4].scan.size(), 149U);  // 351 .. 499 ms
}

TEST(MeasurementSync, AScanEndIsNotSwallowedByALaterImageArrivingWithTheNextScan) {
  // Groups taken every 100 ms. When the camera returns, its first image (1599) comes with the scan
  // after the one ending at 1499: that image is more than a scan period after 1499, so 1499 keeps
  // its own LIO update even though the image is already queued when its turn comes (taking the
  // image first would merge the two scans).
  MeasurementSync sync(SyncParams{.image_timeout_s = 0.15});
  sync.enable_images(true);
  sync.start(MappedTime(0));
  const auto groups = run_rig(sync, 2000, {50, 150, 1599, 1699}, 1, 100);
  std::vector<std::int64_t> times;
  for (const auto& g : groups) times.push_back(g.t_update.ns / kMs);
  EXPECT_EQ(times, (std::vector<std::int64_t>{99, 150, 299, 399, 499, 599, 699, 799, 899, 999, 1099,
                                              1199, 1299, 1399, 1499, 1599, 1699, 1799, 1899}));
  expect_points_partitioned(groups, 1899 * kMs);
}

TEST(MeasurementSync, ImagesUpToAScanPeriodLateAreUsed) {
  // A camera delivering 80 ms after mid-exposure: every image still gets its group.
  MeasurementSync sync;
  sync.enable_images(true);
  sync.start(MappedTime(0));
  std::vector<std::int64_t> images;
  for (std::int64_t t = 50; t < 1000; t += 100) images.push_back(t);
  const auto groups = run_rig(sync, 1200, images, 80);
  std::vector<std::int64_t> image_times;
  for (const auto& g : groups) {
    if (g.kind == MeasurementGroup::Kind::image) image_times.push_back(g.t_update.ns / kMs);
  }
  // All but the one before the first scan's end (counted apart, not as late).
  EXPECT_EQ(image_times, std::vector<std::int64_t>(images.begin() + 1, images.end()));
  EXPECT_EQ(sync.counters().images_late, 0U);
  EXPECT_EQ(sync.counters().images_before_map, 1U);
  expect_points_partitioned(groups, groups.back().t_update.ns);
}

TEST(MeasurementSync, ASlowCameraLeavesScanEndsToLio) {
  MeasurementSync sync(SyncParams{.image_timeout_s = 0.15});
  sync.enable_images(true);
  sync.start(MappedTime(0));
  // 2.5 Hz: an image every 400 ms.
  const auto groups = run_rig(sync, 1700, {150, 550, 950, 1350});
  std::vector<std::int64_t> times;
  for (const auto& g : groups) times.push_back(g.t_update.ns / kMs);
  // Scan ends more than the timeout before the next image are LIO updates at LiDAR rate; the
  // rest of a cut scan joins the next one.
  EXPECT_EQ(times, (std::vector<std::int64_t>{99, 150, 299, 399, 550, 699, 799, 950, 1099, 1199,
                                              1350, 1499, 1599}));
  expect_points_partitioned(groups, 1599 * kMs);
}

TEST(MeasurementSync, LateAndDisabledImages) {
  MeasurementSync off;
  off.start(MappedTime(0));
  off.add_image(image_at(50 * kMs));
  EXPECT_EQ(off.queued_images(), 0U);  // images not enabled: not queued, not counted

  MeasurementSync sync;
  sync.enable_images(true);
  sync.start(MappedTime(0));
  const auto groups = run_rig(sync, 1000, {50, 150});
  ASSERT_FALSE(groups.empty());
  // An image older than the last update can no longer be used.
  sync.add_image(image_at(100 * kMs));
  EXPECT_EQ(sync.counters().images_out_of_order + sync.counters().images_late, 1U);
  EXPECT_EQ(sync.queued_images(), 0U);
}

// Several LiDARs. A scan of `span_ms` + 1 points, one per ms from `start_ms`; x tags the LiDAR,
// y the point's absolute time in ms.
LidarScan dense_scan(int lidar, std::int64_t start_ms, int span_ms, std::uint32_t sequence) {
  LidarScan s;
  s.start.mapped = MappedTime(start_ms * kMs);
  s.sequence = sequence;
  for (int i = 0; i <= span_ms; ++i) {
    s.push_back(static_cast<float>(lidar), static_cast<float>(start_ms + i), 0, 0, 0, 0,
                static_cast<std::int32_t>(i * kMs));
  }
  return s;
}

// Two 10 Hz LiDARs whose scans overlap (B's are cut 40 ms after A's), each scan arriving when it
// ends, the IMU 60 ms late: every scan end of either is an update, in time order; each group holds
// every point of both measured since the last update, and nothing twice.
TEST(MeasurementSyncLidars, EveryScanEndIsAnUpdateAndEachPointIsUsedOnce) {
  MeasurementSync sync(SyncParams{.lidars = 2});
  sync.start(MappedTime(0));
  std::vector<MeasurementGroup> groups;
  MeasurementGroup g;
  std::uint32_t seq_a = 0;
  std::uint32_t seq_b = 0;
  for (std::int64_t t = 1; t <= 620; ++t) {
    if (t % 5 == 0 && t > 60) sync.add_imu(imu_at((t - 60) * kMs));
    // A: [100k + 1, 100k + 100]; B: [1, 40], then [100k + 41, 100k + 140].
    if (t % 100 == 0) sync.add_scan(dense_scan(0, t - 99, 99, seq_a++), 0);
    if (t == 40) sync.add_scan(dense_scan(1, 1, 39, seq_b++), 1);
    if (t % 100 == 40 && t >= 140) sync.add_scan(dense_scan(1, t - 99, 99, seq_b++), 1);
    while (sync.next(g)) groups.push_back(g);
  }
  ASSERT_EQ(groups.size(), 11U);  // 40, 100, 140, ..., 540
  std::int64_t previous = 0;
  std::vector<int> seen_a;
  std::vector<int> seen_b;
  for (const auto& group : groups) {
    EXPECT_EQ(group.kind, MeasurementGroup::Kind::lidar);
    EXPECT_TRUE(group.scan.empty());
    ASSERT_EQ(group.scans.size(), 2U);
    const std::int64_t t_ms = group.t_update.ns / kMs;
    EXPECT_GT(t_ms, previous);
    // Update times: A's ends (100, 200, ...) and B's (40, 140, 240, ...).
    EXPECT_TRUE(t_ms % 100 == 0 || t_ms % 100 == 40) << t_ms;
    EXPECT_EQ(group.lidar, t_ms % 100 == 0 ? 0U : 1U);
    for (std::size_t l = 0; l < 2; ++l) {
      const LidarScan& scan = group.scans[l];
      for (std::size_t i = 0; i < scan.size(); ++i) {
        EXPECT_EQ(scan.x[i], static_cast<float>(l));
        const auto time_ms = scan.point_time(i).ns / kMs;
        EXPECT_EQ(time_ms, static_cast<std::int64_t>(scan.y[i])) << "re-referenced time";
        EXPECT_GT(time_ms, previous);
        EXPECT_LE(time_ms, t_ms);
        (l == 0 ? seen_a : seen_b).push_back(static_cast<int>(time_ms));
      }
    }
    // The IMU samples of the interval, as with one LiDAR.
    ASSERT_FALSE(group.imu.empty());
    EXPECT_GT(group.imu.front().stamp.mapped.ns, previous * kMs);
    EXPECT_LE(group.imu.back().stamp.mapped.ns, t_ms * kMs);
    previous = t_ms;
  }
  EXPECT_EQ(previous, 540);
  // No point twice, none lost up to the last update.
  for (auto* seen : {&seen_a, &seen_b}) {
    std::vector<int> sorted = *seen;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end());
    EXPECT_EQ(sorted.size(), 540U);
  }
  EXPECT_EQ(sync.counters().points_late, 0U);
  EXPECT_EQ(sync.counters().scans_late, 0U);
}

// A group waits for the other LiDAR's points up to its update time; once that LiDAR falls behind
// by more than its scan span + lidar_wait_s of IMU time, the other goes on without it, and the
// late LiDAR's points before the filter's time are dropped and counted.
TEST(MeasurementSyncLidars, WaitsForTheOtherLidarUnlessItIsLate) {
  MeasurementSync sync(SyncParams{.lidars = 2, .lidar_wait_s = 0.05});
  sync.start(MappedTime(0));
  for (std::int64_t t = 5; t <= 150; t += 5) sync.add_imu(imu_at(t * kMs));
  sync.add_scan(dense_scan(1, 1, 59, 0), 1);  // B: [1, 60]
  sync.add_scan(dense_scan(0, 1, 99, 0), 0);  // A: [1, 100]
  MeasurementGroup g;
  ASSERT_TRUE(sync.next(g));  // B's end, 60: A's points up to 60 have arrived
  EXPECT_EQ(g.t_update.ns, 60 * kMs);
  EXPECT_EQ(g.scans[0].size(), 60U);
  EXPECT_EQ(g.scans[1].size(), 60U);
  // A's end, 100: B's data reach only 60, and the IMU (150) is within B's span (59 ms) + 50 ms.
  EXPECT_FALSE(sync.next(g));
  sync.add_imu(imu_at(170 * kMs));  // 170 - 60 > 59 + 50: B is late
  ASSERT_TRUE(sync.next(g));
  EXPECT_EQ(g.t_update.ns, 100 * kMs);
  EXPECT_EQ(g.scans[0].size(), 40U);
  EXPECT_TRUE(g.scans[1].empty());
  // B's next scan [61, 120] arrives late: its points up to 100 are dropped, the rest is used.
  sync.add_scan(dense_scan(1, 61, 59, 1), 1);
  EXPECT_EQ(sync.counters().points_late, 40U);
  EXPECT_FALSE(sync.next(g));       // 120: A (reach 100, span 99) is not late at IMU 170
  sync.add_imu(imu_at(260 * kMs));  // 260 - 100 > 99 + 50: now it is
  ASSERT_TRUE(sync.next(g));
  EXPECT_EQ(g.t_update.ns, 120 * kMs);
  EXPECT_EQ(g.scans[1].size(), 20U);
  // A scan that ended before the filter's time is dropped whole.
  sync.add_scan(dense_scan(0, 20, 50, 1), 0);
  EXPECT_EQ(sync.counters().scans_out_of_order, 1U);  // A's own order: ends before A's newest
  sync.add_scan(dense_scan(1, 121, 10, 2), 1);
  ASSERT_TRUE(sync.next(g));
  EXPECT_EQ(g.t_update.ns, 131 * kMs);
  // A's next scan [101, 110] ended before the filter's time (131): dropped whole.
  sync.add_scan(dense_scan(0, 101, 9, 2), 0);
  EXPECT_EQ(sync.counters().scans_late, 1U);
  EXPECT_EQ(sync.counters().points_late, 50U);
}

// At the start a LiDAR without a scan yet is waited for (its first scan may come a scan after the
// others'), for 0.2 s + lidar_wait_s of IMU data at most: one that never sends stalls nothing
// after.
TEST(MeasurementSyncLidars, ALidarWithoutScansIsWaitedForAtTheStartOnly) {
  MeasurementSync sync(SyncParams{.lidars = 2, .lidar_wait_s = 0.05});
  sync.start(MappedTime(0));
  for (std::int64_t t = 5; t <= 150; t += 5) sync.add_imu(imu_at(t * kMs));
  sync.add_scan(dense_scan(0, 1, 99, 0), 0);  // A: [1, 100]
  MeasurementGroup g;
  EXPECT_FALSE(sync.next(g));                  // B may still send its first scan
  sync.add_scan(dense_scan(1, 31, 99, 0), 1);  // B: [31, 130] reaches past 100
  ASSERT_TRUE(sync.next(g));
  EXPECT_EQ(g.t_update.ns, 100 * kMs);
  EXPECT_EQ(g.scans[1].size(), 70U);  // B's points 31 .. 100: none late
  EXPECT_EQ(sync.counters().points_late, 0U);

  MeasurementSync lone(SyncParams{.lidars = 2, .lidar_wait_s = 0.05});
  lone.start(MappedTime(0));
  for (std::int64_t t = 5; t <= 250; t += 5) lone.add_imu(imu_at(t * kMs));
  lone.add_scan(dense_scan(0, 1, 99, 0), 0);
  EXPECT_FALSE(lone.next(g));       // IMU 250 ms: within 0.2 s + 50 ms of the start
  lone.add_imu(imu_at(255 * kMs));  // past it: B is late, A goes on alone
  ASSERT_TRUE(lone.next(g));
  EXPECT_EQ(g.t_update.ns, 100 * kMs);
  EXPECT_TRUE(g.scans[1].empty());
}

}  // namespace
}  // namespace livod::estimator
