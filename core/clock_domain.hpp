#pragma once
// livod::ClockDomain - maps one sensor clock onto the host CLOCK_MONOTONIC timeline.
//
// One object per sensor clock (a LiDAR and its internal IMU share one, they share the clock).
// Design: /work/shared/docs/sensor-protocols.md §8.3-8.4 and docs/clocks.md (accuracy figures).
//
// How a driver feeds it, once per packet / frame / sample:
//
//   livod::ClockDomain clock(config);                           // at start-up (allocates)
//   ...
//   const MappedTime t = clock.observe(t_sensor, rx, expected_tx_latency);
//
//   t_sensor             the sensor's timestamp of the packet's reference instant (usually its
//                        first point), unwrapped to ns.
//   rx                   the kernel receive stamp of the packet on CLOCK_MONOTONIC.
//   expected_tx_latency  how long after the reference instant the sensor can send the packet at
//                        the earliest: the accumulation time (last point time - first point
//                        time), e.g. Livox SDK2 time_interval * 100 ns, Ouster
//                        columns_per_packet * column period, IMU ~0.
//   returns              the reference instant on the host timeline. Other instants of the same
//                        packet (per-point times) are map()ped or offset from it.
//
// Modes (ClockDomainConfig::mode):
//   direct        the sensor clock is disciplined (PTP/GPS): mapped = t_sensor + direct_offset,
//                 where the caller supplies the offset (e.g. TAI -> CLOCK_MONOTONIC) and may
//                 update it with set_direct_offset(). The hull estimator still runs as a health
//                 check; if the disciplined mapping disagrees with the receive stamps (see
//                 sync_loss_*), quality becomes `lost` and the mapping falls back to the
//                 free-running estimate until the disagreement ends.
//   free_running  the sensor clock runs on its own oscillator: rx = a * t_sensor + b + delay is
//                 fitted with the windowed lower convex hull (core/clock_hull.hpp), |a - 1| <=
//                 max_skew_ppm. Until the window holds min_fine_span of data the mapping is
//                 coarse: t_sensor plus the smallest rx - expected_tx_latency - t_sensor seen so
//                 far, minus min_transport_delay (skew taken as 0; no queueing jitter, so sample
//                 spacings stay those of the sensor clock).
//   receive_time  no sensor clock: mapped = rx - receive_latency - expected_tx_latency. t_sensor is
//                 ignored by observe(); map(t) treats t as a host receive stamp.
//
// Resets and glitches: a sample whose sensor time went backwards by more than jump_threshold, or
// ahead of what its receive stamp allows (by early_tolerance against the fit; by jump_threshold
// before there is one) is rejected and mapped from its receive stamp. (Smaller backward steps
// are reordered packets, or the samples that follow a glitch.) reset_confirm_samples such
// samples in a row mean the sensor clock really jumped (reboot, PPS re-zeroing, PTP step): the
// estimator restarts and `resets` counts it. A backward step larger than jump_threshold but
// smaller than the packet interval (sensor time still increases) shows up as samples arriving
// more than jump_threshold late for late_reset_after, which also restarts it. Backward steps
// smaller than jump_threshold are not detected (see docs/clocks.md). A driver that knows of a
// reboot from the protocol (Ouster init_id, Livox frame counter restart) calls reset().
//
// Not thread-safe: the capture thread that calls observe() owns the object; it copies stats()
// into its health counters. observe() and map() never allocate and are O(1) except when the
// hull changes (O(window_bins), a few µs).

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "core/clock_hull.hpp"
#include "core/time.hpp"

namespace livod {

enum class ClockMode : std::uint8_t { direct, free_running, receive_time };

// coarse: no fitted sensor clock model (start-up, after a reset, or receive_time mode: the
//         mapping carries the full receive jitter);
// fine:   disciplined clock in sync, or a free-running clock with a converged hull fit;
// lost:   direct mode whose sensor clock disagrees with the receive stamps (sync lost).
enum class SyncQuality : std::uint8_t { coarse, fine, lost };

std::string_view to_string(ClockMode mode);
std::string_view to_string(SyncQuality quality);

struct ClockDomainConfig {
  ClockMode mode = ClockMode::free_running;

  // direct: mapped = t_sensor + direct_offset.
  Nanoseconds direct_offset{0};
  // receive_time: the calibrated latency from the event to the receive stamp.
  Nanoseconds receive_latency{0};
  // free_running / direct health: the always-present part of the one-way delay (wire + stack) that
  // one-way stamps cannot reveal. The hull line sits at the *minimum* delay; subtracting the
  // calibrated floor makes mapped times unbiased. Left at 0, mapped times are late by the floor.
  Nanoseconds min_transport_delay{0};

  // Sliding window of sensor time for the hull, cut into window_bins sub-windows (one kept sample
  // each). Longer averages the noise of the minimum-delay samples better but follows skew changes
  // (temperature) more slowly.
  Nanoseconds window = std::chrono::seconds(60);
  std::size_t window_bins = 120;
  // |a - 1| bound: crystal oscillators are within +-100 ppm; beyond that the data is wrong.
  double max_skew_ppm = 200.0;
  // The hull fit is used (quality fine) once the window spans this much sensor time.
  Nanoseconds min_fine_span = std::chrono::seconds(2);

  // Jump / reset detection (see the header comment). early_tolerance also is the hull's spike
  // tolerance. jump_threshold must exceed the worst queueing delay / host stall expected.
  Nanoseconds early_tolerance = std::chrono::microseconds(500);
  Nanoseconds jump_threshold = std::chrono::milliseconds(100);
  Nanoseconds late_reset_after = std::chrono::seconds(1);
  std::uint32_t reset_confirm_samples = 3;

  // direct mode health check: over each sync_check_period (host time), the smallest residual
  // rx - expected_tx_latency - min_transport_delay - mapped must stay within
  // [-sync_loss_early, sync_loss_late]. Early means "received before it was sent" (the sensor
  // clock runs ahead); a smallest delay above sync_loss_late means it runs behind.
  Nanoseconds sync_check_period = std::chrono::milliseconds(500);
  Nanoseconds sync_loss_late = std::chrono::milliseconds(5);
  Nanoseconds sync_loss_early = std::chrono::microseconds(100);
};

struct ClockDomainStats {
  ClockMode mode = ClockMode::free_running;
  SyncQuality quality = SyncQuality::coarse;
  // mapped - t_sensor at the newest sample (ns): the sensor -> host offset in use.
  Nanoseconds offset{0};
  // Estimated rate error of the sensor clock as seen from the host, (a - 1) * 1e6, from the hull
  // fit (also in direct mode, as a health figure); 0 while there is no fit. A sensor clock that
  // runs fast by 50 ppm shows as about -50.
  double skew_ppm = 0.0;
  // Residuals r = rx - expected_tx_latency - min_transport_delay - mapped of the recent samples
  // (the last kResidualHistory): their median (typical queueing delay above the floor) and
  // their median absolute deviation (a robust jitter figure). Both 0 in receive_time mode.
  Nanoseconds residual_median{0};
  Nanoseconds jitter{0};
  // Residual of the newest sample (its distance above the hull line).
  Nanoseconds last_residual{0};
  // direct mode: smallest residual of the last completed sync check period.
  Nanoseconds direct_residual{0};
  std::uint64_t samples = 0;       // samples in the current window (all, in receive_time mode)
  std::size_t window_points = 0;   // kept minimum-delay points (<= window_bins + 1)
  std::uint64_t observations = 0;  // observe() calls since construction
  std::uint64_t resets = 0;        // sensor clock resets / jumps detected (+ reset() calls)
  std::uint64_t rejected = 0;      // samples rejected as impossible (not used by the estimator)
  std::uint64_t sync_losses = 0;   // direct mode: transitions into `lost`
};

class ClockDomain {
 public:
  // Number of recent residuals kept for the jitter figures.
  static constexpr std::size_t kResidualHistory = 512;

  // Throws std::invalid_argument for inconsistent settings (window/bins, negative tolerances).
  explicit ClockDomain(const ClockDomainConfig& config);

  // Feeds one (sensor stamp, receive stamp) pair and returns the mapped time of t_sensor.
  MappedTime observe(SensorTime t_sensor, HostTime rx,
                     Nanoseconds expected_tx_latency = Nanoseconds(0));

  // Maps another instant of the same sensor clock with the current model (e.g. a per-point time or
  // an IMU sample between packets). Before the first observe() only the configured offsets apply.
  [[nodiscard]] MappedTime map(SensorTime t_sensor) const;

  [[nodiscard]] ClockDomainStats stats() const;
  [[nodiscard]] SyncQuality quality() const;

  // The driver knows the sensor clock restarted (protocol-level reboot marker): restart the
  // estimator and count a reset.
  void reset();

  // direct mode: the caller's sensor -> CLOCK_MONOTONIC offset changed (e.g. its 10 Hz
  // realtime/TAI -> monotonic refresh).
  void set_direct_offset(Nanoseconds offset) { config_.direct_offset = offset; }

  [[nodiscard]] const ClockDomainConfig& config() const { return config_; }

 private:
  enum class Verdict : std::uint8_t { accepted, rejected, restarted };

  Verdict track(std::int64_t t, std::int64_t z, std::int64_t y);
  void restart_estimator();
  void refit();
  void check_direct_sync(std::int64_t y, std::int64_t direct_residual);
  [[nodiscard]] std::int64_t fitted_offset_at(std::int64_t t) const;  // host - sensor, ns
  void record_residual(std::int64_t residual);

  ClockDomainConfig config_;
  double max_skew_;  // dimensionless
  WindowedLowerHull hull_;
  std::optional<OffsetLine> line_;  // current fit, if any
  bool fine_ = false;               // line_ is usable (window spans min_fine_span)

  // Newest accepted sample of the epoch, and the lowest z of the epoch (reference before a fit).
  bool have_epoch_ = false;
  std::int64_t t_newest_ = 0;
  std::int64_t t_lowest_ = 0;
  std::int64_t z_lowest_ = 0;
  std::int64_t y_last_not_late_ = 0;
  std::uint32_t consecutive_rejected_ = 0;

  // Offset (mapped - t_sensor) of the newest observe(), used by map() without a fit.
  bool have_last_ = false;
  std::int64_t last_offset_ = 0;

  // direct mode health.
  bool sync_lost_ = false;
  bool have_sync_period_ = false;
  std::int64_t sync_period_start_ = 0;
  std::int64_t sync_period_min_ = 0;
  std::int64_t direct_residual_ = 0;

  std::array<std::int64_t, kResidualHistory> residuals_{};
  std::size_t residual_count_ = 0;
  std::size_t residual_next_ = 0;
  std::int64_t last_residual_ = 0;

  std::uint64_t observations_ = 0;
  std::uint64_t resets_ = 0;
  std::uint64_t rejected_ = 0;
  std::uint64_t sync_losses_ = 0;
};

}  // namespace livod
