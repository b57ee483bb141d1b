#pragma once
// A camera's clock domain: puts each frame's exposure on the common timeline (CLOCK_MONOTONIC)
// and derives mid-exposure, the instant the estimator uses.
//
//   start of exposure (sensor clock) = sensor_time                       (StampInstant SOE)
//                                    = sensor_time - readout - exposure  (StampInstant EOF)
//   exposure_start (mapped)          = ClockDomain(start of exposure, host_rx,
//                                                  expected latency = exposure + readout)
//                                      + time_offset
//   mid_exposure                     = exposure_start + exposure / 2
//
// The clock model follows the frames' clock (automatic mode), unless the configuration forces one:
//   host monotonic (V4L2 MONOTONIC stamps)  direct, offset 0 (the hull still checks it)
//   device ticks (GigE/USB3 Vision)         free_running: lower convex hull over (stamp, rx)
//   PTP (locked GigE camera)                direct, offset CLOCK_TAI -> CLOCK_MONOTONIC, measured
//                                           by bracketed clock reads and refreshed every second
//                                           (the host's TAI must be disciplined: ptp4l/phc2sys
//                                           or chrony with a TAI offset)
// `readout` (readout + transfer after the end of exposure, calibrated) matters only for
// end-of-frame stamps; time_offset is the sensor's configured time_offset_s, added once here.
//
// Single-threaded: the consumer (scheduler) thread owns it.

#include <cstdint>
#include <optional>

#include "core/clock_domain.hpp"
#include "drivers/camera/camera_frame.hpp"

namespace livod::camera {

struct CameraClockConfig {
  // nullopt: chosen from the first frame's clock (see above); otherwise this mode for every
  // frame (e.g. receive_time for a camera whose stamps are useless).
  std::optional<ClockMode> mode;
  ClockDomainConfig domain;  // window, skew bound, latencies; its `mode` is overridden
  Nanoseconds readout{0};
  Nanoseconds time_offset{0};
};

// CLOCK_TAI - CLOCK_MONOTONIC now, from the tightest of a few bracketed reads.
Nanoseconds tai_to_monotonic_offset();

class CameraClock {
 public:
  explicit CameraClock(CameraClockConfig config);

  // Sets frame.stamp (sensor, host and mapped), exposure_start and mid_exposure from frame.info.
  void map(CameraFrame& frame);

  // Nullopt until the first frame chose the domain.
  [[nodiscard]] std::optional<ClockDomainStats> stats() const;

 private:
  CameraClockConfig config_;
  std::optional<ClockDomain> domain_;
  std::optional<CameraClockKind> kind_;
  std::int64_t last_tai_refresh_ns_ = 0;
};

}  // namespace livod::camera
