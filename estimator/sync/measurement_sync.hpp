#pragma once
// Measurement groups (fast-livo2-notes.md 1.1, sync_packages): what the filter consumes in one
// step - an update time, the IMU samples up to it, the LiDAR points measured since the last
// update and, at image times, the image.
//
// Two kinds of group:
//  - lidar: the update time is a scan's end (its latest point) and the points are those of the
//    scan not used yet (FAST-LIO2 / FAST-LIVO2 ONLY_LIO grouping). The rest of a scan cut at an
//    image time never makes a group of its own: it joins the next scan (a LIO update always sees
//    at least a whole scan's worth of points);
//  - image: the update time is an image's mid-exposure time and the points are those measured
//    since the last update up to that time (scan recombination: scans are cut at image times,
//    the rest of a cut scan waits for the next group). The pipeline runs the LIO update and
//    then the VIO update at that one instant.
//
// With images enabled (enable_images), the first group is still the first whole scan (the map
// starts from a full sweep; the images up to its end are dropped and counted, images_before_map).
// Then image groups are made whenever the points up to the image time have arrived; a scan end
// becomes a lidar group only when no image is due for it. An image
// is due when it comes within image_timeout of the scan end and before the next scan would end
// (one scan period, the scan's own span, later): then its group takes the scan's points. With no
// image queued, the scan end waits until the data (the IMU) reaches that horizon. LIO therefore
// never waits more than min(image_timeout, a scan period) of data time for a camera: when images
// stop, odometry goes on at LiDAR rate, and it returns to image times when they come back
// (FAST-LIVO2 stops: defect 1).
//
// Several LiDARs (SyncParams::lidars > 1; docs/estimator.md "Several LiDARs"): every scan end of
// every LiDAR is an update time, and a group takes the points of every LiDAR measured in
// (previous update, t_update] - the scans of the other LiDARs are cut at that time, their rest
// waits for the next group. Each point is thus used once, in the interval the filter propagates
// through, and the state never goes back in time however the scans overlap. A group waits until
// every LiDAR's data have reached its update time, except for a LiDAR that is late: one whose
// newest scan ended more than its own scan span + lidar_wait_s before the newest IMU sample (a
// LiDAR that stopped, or one whose scans arrive much later than the others'); a LiDAR that has not
// sent a scan yet is waited for during the first 0.2 s + lidar_wait_s only. Points of such a
// LiDAR that arrive after the filter passed their time are dropped and counted. Image groups are
// not made with several LiDARs (the configuration check refuses VIO with more than one LiDAR).
//
// Inputs carry mapped times: every per-sensor offset has been applied once, by the sensor's clock
// domain, before anything reaches this class. Out-of-order input is dropped and counted; queues
// are bounded (the oldest entry is dropped and counted), so a stalled consumer cannot grow memory.

#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "core/image.hpp"
#include "core/measurement.hpp"

namespace livod::estimator {

struct SyncParams {
  std::size_t max_queued_scans = 20;  // 2 s at 10 Hz
  std::size_t max_queued_imu = 4000;  // 2 s at 2 kHz, 10 s at 400 Hz
  std::size_t max_queued_images = 8;  // 0.8 s at 10 Hz (each holds its pixels)
  double image_timeout_s = 0.15;      // see the header comment
  std::size_t lidars = 1;             // LiDARs feeding add_scan (index 0 .. lidars - 1)
  double lidar_wait_s = 0.05;         // beyond a LiDAR's scan span: see the header comment
};

struct MeasurementGroup {
  enum class Kind { lidar, image };
  Kind kind = Kind::lidar;
  MappedTime t_update;  // lidar: the scan end; image: the image's mid-exposure time
  // The points measured in (previous update, t_update]; times relative to scan.start as usual.
  // May be empty in an image group (no LiDAR point since the last update). Empty with several
  // LiDARs: see `scans`.
  LidarScan scan;
  // Several LiDARs: per LiDAR (by index) its points measured in (previous update, t_update], each
  // scan referenced to its own start; empty with one LiDAR.
  std::vector<LidarScan> scans;
  std::size_t lidar = 0;            // the LiDAR whose scan ends at t_update
  std::uint32_t scan_sequence = 0;  // that scan's sequence number
  // Samples stamped in (previous update, t_update], in time order.
  std::vector<ImuSample> imu;
  // The first sample after t_update, when it has arrived (interpolates the last interval).
  std::optional<ImuSample> imu_after;
  ImageFrame image;  // image groups
};

struct SyncCounters {
  std::uint64_t scans_in = 0;
  std::uint64_t scans_out_of_order = 0;  // end at or before the previous group's
  std::uint64_t scans_queue_overflow = 0;
  // Several LiDARs: scans of a late LiDAR that ended before the filter's time (dropped whole), and
  // the points of partly late scans measured before it (dropped, the rest of the scan used).
  std::uint64_t scans_late = 0;
  std::uint64_t points_late = 0;
  std::uint64_t imu_in = 0;
  std::uint64_t imu_out_of_order = 0;  // stamp at or before the previous sample's
  std::uint64_t imu_queue_overflow = 0;
  std::uint64_t images_in = 0;
  std::uint64_t images_out_of_order = 0;  // at or before the previous image
  std::uint64_t images_late = 0;          // arrived after the estimator passed their time (later)
  std::uint64_t images_queue_overflow = 0;
  // Up to the first scan's end (the first group's, whenever they arrive): no map to update against.
  std::uint64_t images_before_map = 0;
  std::uint64_t groups = 0;
  std::uint64_t image_groups = 0;
};

class MeasurementSync {
 public:
  explicit MeasurementSync(SyncParams params = {}) : params_(params) {}

  // The timeline starts at t (the IMU initialisation's last sample): earlier input is out of order.
  void start(MappedTime t);
  [[nodiscard]] bool started() const { return started_; }
  // Image groups from now on (the pipeline has a camera and VIO on); without it images are not
  // accepted and every group is a lidar group.
  void enable_images(bool on) { images_enabled_ = on; }

  void add_imu(const ImuSample& sample);
  // Empty scans are ignored. The scan end is its latest point time. Taken by value: a caller that
  // no longer needs its copy moves it into the queue. `lidar`: which LiDAR (< SyncParams::lidars).
  void add_scan(LidarScan scan, std::size_t lidar = 0);
  // Queued by mid_exposure. The group shares the pixel buffer (cv::Mat reference counting).
  void add_image(ImageFrame image);

  // Moves the next complete group into `group`; false when no group is complete yet.
  bool next(MeasurementGroup& group);

  [[nodiscard]] const SyncCounters& counters() const { return counters_; }
  [[nodiscard]] std::size_t queued_scans() const;
  [[nodiscard]] std::size_t queued_imu() const { return imu_.size(); }
  [[nodiscard]] std::size_t queued_images() const { return images_.size(); }

  // The time of a scan's last point.
  [[nodiscard]] static MappedTime scan_end(const LidarScan& scan);

 private:
  struct QueuedScan {
    LidarScan scan;
    MappedTime begin;  // earliest point
    MappedTime end;    // latest point
    bool cut = false;  // the rest of a scan cut at an image time
  };

  // One LiDAR's queue in the several-LiDAR mode.
  struct LidarQueue {
    std::deque<QueuedScan> scans;
    bool seen = false;    // a scan of this LiDAR has arrived
    MappedTime reach;     // the end of its newest scan
    Nanoseconds span{0};  // the span of its newest scan (its scan period, near enough)
  };

  // A lidar group ending at the end of scans_[index] (index 1: the front is the rest of a cut).
  bool next_lidar(MeasurementGroup& group, std::size_t index);
  // Fills `out` with every point of `queue` up to t (cutting the scan that straddles t).
  static void take_points_until(MappedTime t, std::deque<QueuedScan>& queue, LidarScan& out);
  void add_scan_of(LidarScan scan, std::size_t lidar);
  bool next_of_lidars(MeasurementGroup& group);
  void take_imu_until(MappedTime t, MeasurementGroup& group);

  SyncParams params_;
  bool started_ = false;
  bool images_enabled_ = false;
  // Several LiDARs: how long a LiDAR without any scan yet is waited for after the start (a scan
  // period of the slowest common LiDARs, 5 Hz).
  static constexpr double kFirstScanWaitS = 0.2;
  MappedTime start_;        // where the timeline started
  MappedTime last_update_;  // the last group's update time (or the start)
  MappedTime last_imu_;     // the newest accepted sample (or the start)
  MappedTime last_image_;   // the newest accepted image
  MappedTime map_start_;    // with images: the first group's time (the first scan's end)
  std::deque<ImuSample> imu_;
  std::deque<QueuedScan> scans_;
  std::vector<LidarQueue> lidars_;  // several LiDARs only (scans_ is then unused)
  std::deque<ImageFrame> images_;
  SyncCounters counters_;
};

}  // namespace livod::estimator
