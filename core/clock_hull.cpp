#include "core/clock_hull.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>

namespace livod {

namespace {

// Orientation of (a - o) x (b - o). The products reach ~1e11 ns (window) x ~1e9 ns (offset
// change), beyond int64, so they are formed in 128 bits to stay exact.
__int128 cross(std::int64_t ot, std::int64_t oz, std::int64_t at, std::int64_t az, std::int64_t bt,
               std::int64_t bz) {
  return static_cast<__int128>(at - ot) * (bz - oz) - static_cast<__int128>(az - oz) * (bt - ot);
}

}  // namespace

WindowedLowerHull::WindowedLowerHull(Nanoseconds window, std::size_t bins,
                                     Nanoseconds spike_tolerance)
    : bin_ns_(bins == 0 ? 0 : window.count() / static_cast<std::int64_t>(bins)),
      bins_(bins),
      spike_tolerance_ns_(spike_tolerance.count()) {
  if (window.count() <= 0 || bins < 2 || bin_ns_ < 1) {
    throw std::invalid_argument("WindowedLowerHull: need window > 0 and 2 <= bins <= window (ns)");
  }
  if (spike_tolerance_ns_ < 0) {
    throw std::invalid_argument("WindowedLowerHull: spike_tolerance must be >= 0");
  }
  closed_.resize(bins_);
  all_points_.reserve(bins_ + 1);
  keep_.reserve(bins_ + 1);
  next_keep_.reserve(bins_ + 1);
  points_.reserve(bins_ + 1);
  hull_.reserve(bins_ + 1);
}

void WindowedLowerHull::clear() {
  has_open_ = false;
  closed_head_ = 0;
  closed_count_ = 0;
  hull_dirty_ = true;
  hull_.clear();
}

const WindowedLowerHull::Bin& WindowedLowerHull::closed_at(std::size_t i) const {
  return closed_[(closed_head_ + i) % bins_];
}

void WindowedLowerHull::close_open_bin() {
  if (closed_count_ == bins_) {  // full: the oldest sub-window leaves the window
    closed_head_ = (closed_head_ + 1) % bins_;
    --closed_count_;
  }
  closed_[(closed_head_ + closed_count_) % bins_] = open_;
  ++closed_count_;
}

bool WindowedLowerHull::add(std::int64_t t, std::int64_t z, double slope_hint) {
  const double key = static_cast<double>(z) - slope_hint * static_cast<double>(t - origin_);
  if (!has_open_) {
    origin_ = t;
    open_ = Bin{0, Point{t, z}, static_cast<double>(z), 1};
    has_open_ = true;
    hull_dirty_ = true;
    return true;
  }
  if (t < origin_ + open_.index * bin_ns_) return false;  // older than the open sub-window
  const std::int64_t index = (t - origin_) / bin_ns_;
  if (index == open_.index) {
    ++open_.count;
    if (key >= open_.key) return false;
    open_.best = Point{t, z};
    open_.key = key;
    hull_dirty_ = true;
    return true;
  }
  close_open_bin();
  open_ = Bin{index, Point{t, z}, key, 1};
  // Keep the sub-windows index - bins .. index - 1: the window is `bins` full sub-windows plus
  // the open one. After a gap in the data several leave at once.
  while (closed_count_ > 0 && closed_at(0).index < index - static_cast<std::int64_t>(bins_)) {
    closed_head_ = (closed_head_ + 1) % bins_;
    --closed_count_;
  }
  hull_dirty_ = true;
  return true;
}

Nanoseconds WindowedLowerHull::span() const {
  if (!has_open_ || closed_count_ == 0) return Nanoseconds(0);
  return Nanoseconds(open_.best.t - closed_at(0).best.t);
}

std::uint64_t WindowedLowerHull::samples() const {
  std::uint64_t n = has_open_ ? open_.count : 0;
  for (std::size_t i = 0; i < closed_count_; ++i) n += closed_at(i).count;
  return n;
}

bool WindowedLowerHull::is_spike(std::size_t i, double max_slope) const {
  // The lowest z each neighbour allows at t_i (its z minus the largest skew over the distance);
  // a spike lies below the second lowest of these bounds by more than the tolerance. Neighbours
  // are the two nearest points on each side that are not spikes (so far).
  const Point& p = all_points_[i];
  // The two lowest bounds so far, relative to p.z.
  double lowest = std::numeric_limits<double>::infinity();
  double second = std::numeric_limits<double>::infinity();
  int count = 0;
  const auto consider = [&](std::size_t j) {
    const Point& q = all_points_[j];
    const double bound =
        static_cast<double>(q.z - p.z) - max_slope * static_cast<double>(std::abs(q.t - p.t));
    if (bound < lowest) {
      second = lowest;
      lowest = bound;
    } else if (bound < second) {
      second = bound;
    }
    ++count;
  };
  int found = 0;
  for (std::size_t j = i; j-- > 0 && found < 2;) {
    if (keep_[j] != 0) {
      consider(j);
      ++found;
    }
  }
  found = 0;
  for (std::size_t j = i + 1; j < all_points_.size() && found < 2; ++j) {
    if (keep_[j] != 0) {
      consider(j);
      ++found;
    }
  }
  return count >= 2 && second > static_cast<double>(spike_tolerance_ns_);
}

void WindowedLowerHull::rebuild_hull(double max_slope) {
  all_points_.clear();
  for (std::size_t i = 0; i < closed_count_; ++i) all_points_.push_back(closed_at(i).best);
  if (has_open_) all_points_.push_back(open_.best);

  // Spike removal in passes: a run of glitches can hide one of them behind its neighbours until
  // the others are gone (e.g. glitches in sub-windows 0, 2 and 3). Each pass judges every point
  // against the previous pass's survivors; a few passes settle any realistic cluster.
  constexpr int kMaxSpikePasses = 4;
  keep_.assign(all_points_.size(), 1);
  next_keep_.assign(all_points_.size(), 1);
  for (int pass = 0; pass < kMaxSpikePasses; ++pass) {
    bool changed = false;
    for (std::size_t i = 0; i < all_points_.size(); ++i) {
      if (keep_[i] != 0 && is_spike(i, max_slope)) {
        next_keep_[i] = 0;
        changed = true;
      }
    }
    keep_ = next_keep_;
    if (!changed) break;
  }
  points_.clear();
  for (std::size_t i = 0; i < all_points_.size(); ++i) {
    if (keep_[i] != 0) points_.push_back(all_points_[i]);
  }
  spikes_ = all_points_.size() - points_.size();

  // Andrew's monotone chain, lower half. The points are already sorted by t (one per
  // sub-window, sub-windows in order), so this is linear.
  hull_.clear();
  for (const Point& p : points_) {
    while (hull_.size() >= 2) {
      const Point& o = hull_[hull_.size() - 2];
      const Point& a = hull_.back();
      // Drop `a` unless o -> a -> p turns left (strictly convex from below).
      if (cross(o.t, o.z, a.t, a.z, p.t, p.z) > 0) break;
      hull_.pop_back();
    }
    hull_.push_back(p);
  }
  hull_dirty_ = false;
  hull_max_slope_ = max_slope;
}

std::optional<OffsetLine> WindowedLowerHull::fit(double max_slope) {
  if (hull_dirty_ || max_slope != hull_max_slope_) rebuild_hull(max_slope);
  if (points_.size() < 2) return std::nullopt;

  // Centroid time of the kept points, relative to the first one (exact int64 sum, then double).
  const std::int64_t t0 = points_.front().t;
  std::int64_t sum_dt = 0;
  for (const Point& p : points_) sum_dt += p.t - t0;
  const double centroid = static_cast<double>(sum_dt) / static_cast<double>(points_.size());

  // Hull edge whose time range contains the centroid. The hull spans the first to the last point,
  // so such an edge exists.
  std::size_t edge = 0;
  while (edge + 2 < hull_.size() && static_cast<double>(hull_[edge + 1].t - t0) <= centroid) {
    ++edge;
  }
  const Point& left = hull_[edge];
  const Point& right = hull_[edge + 1];
  const double slope =
      static_cast<double>(right.z - left.z) / static_cast<double>(right.t - left.t);
  if (std::abs(slope) <= max_slope) return OffsetLine{left.t, left.z, slope};

  // Steeper than any plausible clock: use the support line with the extreme allowed slope, which
  // touches the hull at the vertex where z - slope * t is smallest.
  const double clamped = std::clamp(slope, -max_slope, max_slope);
  std::size_t best = 0;
  double best_value = 0.0;
  for (std::size_t i = 0; i < hull_.size(); ++i) {
    const double value =
        static_cast<double>(hull_[i].z - left.z) - clamped * static_cast<double>(hull_[i].t - t0);
    if (i == 0 || value < best_value) {
      best = i;
      best_value = value;
    }
  }
  return OffsetLine{hull_[best].t, hull_[best].z, clamped};
}

}  // namespace livod
