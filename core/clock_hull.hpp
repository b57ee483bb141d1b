#pragma once
// Bounded sliding-window lower convex hull of an offset series, the geometric core of the clock
// domains (core/clock_domain.hpp).
//
// Input points are (t, z): t = sensor time, z = host event time estimate - t, both in ns, where the
// host estimate is the receive stamp minus the known transmit latency. With the model
//   rx = a * t_sensor + b + d,   d >= d_min,
// every point lies on or above the line z = (a - 1) * t + b + d_min; the points with the least
// queueing delay touch it. The best estimate of that line is a *lower support line* of the point
// set: below every point, touching the hull.
//
// Boundedness: the window is cut into `bins` sub-windows of window/bins sensor time each; every
// sub-window keeps only its minimum-delay sample (the only kind of sample that can be on the lower
// hull), so memory is `bins` + 1 points whatever the packet rate (120 s at 2 kHz is still
// `bins` + 1 points). The "minimum" is taken after removing the current slope estimate, so a skewed
// clock does not bias the choice towards the start or the end of a sub-window.
//
// Spikes: a sub-window minimum far below its neighbours (further than any allowed skew explains,
// by more than `spike_tolerance`) cannot be a low-delay sample: it is a sensor stamp that was too
// late (a glitch). It is left out of the hull, because a single such point would otherwise pull
// the support line down for a whole window. The test compares each point with the second lowest
// bound of its up to four nearest neighbours (two each side), and is repeated over a few passes
// on the survivors, so clusters of glitches in nearby sub-windows are caught too. Glitches
// smaller than the tolerance cannot be told from delay noise and may bias the fit by up to
// their size.
//
// Which support line: among all lines below every point with |slope| <= max_slope, the one that
// minimises the summed vertical distance to the kept points. That linear programme's optimum is
// the hull edge above the centroid time of the points (or, if that edge is steeper than allowed,
// the support line of slope +-max_slope). Using the whole window this way averages the offset
// noise of the minimum-delay samples over the whole window rather than trusting two of them.
//
// No I/O, no threads, no allocation after construction.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/time.hpp"

namespace livod {

// z(t) = z_ref + slope * (t - t_ref), in ns; slope is the skew (a - 1), dimensionless.
// Anchored at a kept point so that slope * (t - t_ref) stays small and exact in double.
struct OffsetLine {
  std::int64_t t_ref = 0;
  std::int64_t z_ref = 0;
  double slope = 0.0;

  // z on the line at t, rounded to ns. z_ref stays integer: z is often ~1e18 (a PTP-epoch sensor
  // clock against a boot-epoch host clock), where a double has only 256 ns resolution.
  [[nodiscard]] std::int64_t at(std::int64_t t) const {
    return z_ref + std::llround(slope * static_cast<double>(t - t_ref));
  }
  // How far the point (t, z) lies above the line, ns.
  [[nodiscard]] double above(std::int64_t t, std::int64_t z) const {
    return static_cast<double>(z - z_ref) - slope * static_cast<double>(t - t_ref);
  }
};

class WindowedLowerHull {
 public:
  // `window` > 0 of sensor time split into `bins` >= 2 sub-windows (each >= 1 ns long);
  // `spike_tolerance` >= 0 (see the header comment). Throws std::invalid_argument otherwise.
  WindowedLowerHull(Nanoseconds window, std::size_t bins, Nanoseconds spike_tolerance);

  // Forgets every point (new epoch, e.g. after a sensor clock reset).
  void clear();

  // Adds one sample. `slope_hint` is the current skew estimate (0 if none), used only to pick the
  // minimum-delay sample inside a sub-window. Samples older than the current sub-window's start
  // (reordered packets) are ignored. Returns true if the kept point set changed.
  bool add(std::int64_t t, std::int64_t z, double slope_hint);

  // The least-summed-distance support line of the kept points without spikes (see the header
  // comment), with |slope| <= max_slope. nullopt with fewer than 2 such points.
  [[nodiscard]] std::optional<OffsetLine> fit(double max_slope);

  [[nodiscard]] bool empty() const { return !has_open_; }
  // Kept points: one per non-empty sub-window in the window (at most bins + 1).
  [[nodiscard]] std::size_t points() const { return closed_count_ + (has_open_ ? 1 : 0); }
  // Sensor time between the oldest and the newest kept point (0 if fewer than 2).
  [[nodiscard]] Nanoseconds span() const;
  // Samples that fell into the sub-windows currently kept.
  [[nodiscard]] std::uint64_t samples() const;
  // Vertices of the lower hull and points left out as spikes, as of the last fit().
  [[nodiscard]] std::size_t hull_vertices() const { return hull_.size(); }
  [[nodiscard]] std::size_t spikes() const { return spikes_; }

 private:
  struct Point {
    std::int64_t t;
    std::int64_t z;
  };
  struct Bin {
    std::int64_t index = 0;  // sub-window number counted from origin_
    Point best{0, 0};        // minimum-delay sample of the sub-window
    double key = 0.0;        // best.z with the slope hint removed (what "minimum" compares)
    std::uint64_t count = 0;
  };

  [[nodiscard]] const Bin& closed_at(std::size_t i) const;  // 0 = oldest
  void close_open_bin();
  void rebuild_hull(double max_slope);
  [[nodiscard]] bool is_spike(std::size_t i, double max_slope) const;  // i indexes all_points_

  std::int64_t bin_ns_;
  std::size_t bins_;
  std::int64_t spike_tolerance_ns_;

  std::int64_t origin_ = 0;  // sensor time of the first sample of the epoch
  bool has_open_ = false;
  Bin open_;
  std::vector<Bin> closed_;  // ring of the closed sub-windows, capacity bins_
  std::size_t closed_head_ = 0;
  std::size_t closed_count_ = 0;

  bool hull_dirty_ = true;
  double hull_max_slope_ = 0.0;          // max_slope the hull was built with
  std::vector<Point> all_points_;        // scratch: kept points in time order
  std::vector<std::uint8_t> keep_;       // per all_points_: not (yet) found to be a spike
  std::vector<std::uint8_t> next_keep_;  // the same, being updated by a spike pass
  std::vector<Point> points_;            // all_points_ without spikes
  std::vector<Point> hull_;              // lower hull of points_
  std::size_t spikes_ = 0;
};

}  // namespace livod
