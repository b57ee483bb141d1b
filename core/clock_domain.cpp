#include "core/clock_domain.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

namespace livod {

std::string_view to_string(ClockMode mode) {
  switch (mode) {
    case ClockMode::direct:
      return "direct";
    case ClockMode::free_running:
      return "free_running";
    case ClockMode::receive_time:
      return "receive_time";
  }
  return "unknown";
}

std::string_view to_string(SyncQuality quality) {
  switch (quality) {
    case SyncQuality::coarse:
      return "coarse";
    case SyncQuality::fine:
      return "fine";
    case SyncQuality::lost:
      return "lost";
  }
  return "unknown";
}

namespace {

const ClockDomainConfig& validated(const ClockDomainConfig& c) {
  const auto negative = [](Nanoseconds d) { return d.count() < 0; };
  if (!(c.max_skew_ppm >= 0.0 && c.max_skew_ppm < 1e5)) {
    throw std::invalid_argument("ClockDomainConfig: max_skew_ppm must be in [0, 1e5)");
  }
  if (negative(c.receive_latency) || negative(c.min_transport_delay) || negative(c.min_fine_span) ||
      negative(c.early_tolerance) || negative(c.jump_threshold) || negative(c.late_reset_after) ||
      negative(c.sync_loss_late) || negative(c.sync_loss_early)) {
    throw std::invalid_argument("ClockDomainConfig: latencies and tolerances must be >= 0");
  }
  if (c.reset_confirm_samples < 1) {
    throw std::invalid_argument("ClockDomainConfig: reset_confirm_samples must be >= 1");
  }
  if (c.sync_check_period.count() <= 0) {
    throw std::invalid_argument("ClockDomainConfig: sync_check_period must be > 0");
  }
  return c;
}

}  // namespace

ClockDomain::ClockDomain(const ClockDomainConfig& config)
    : config_(validated(config)),
      max_skew_(config.max_skew_ppm * 1e-6),
      hull_(config.window, config.window_bins, config.early_tolerance) {}

MappedTime ClockDomain::observe(SensorTime t_sensor, HostTime rx, Nanoseconds expected_tx_latency) {
  ++observations_;
  // Host time at which the packet could have been sent at the earliest; the transport delay
  // (floor + queueing) separates it from the event's true host time.
  const std::int64_t y = rx.ns - expected_tx_latency.count();
  if (config_.mode == ClockMode::receive_time) {
    return MappedTime(y - config_.receive_latency.count());
  }

  const std::int64_t t = t_sensor.ns;
  const std::int64_t z = y - t;
  const std::int64_t floor = config_.min_transport_delay.count();
  const std::int64_t coarse = y - floor;

  bool direct_in_sync = false;
  if (config_.mode == ClockMode::direct) {
    // Health check first: entering `lost` restarts the estimator, so that the fallback fit uses
    // only samples from after the loss.
    check_direct_sync(y, coarse - (t + config_.direct_offset.count()));
    direct_in_sync = !sync_lost_;
  }
  const Verdict verdict = track(t, z, y);

  std::int64_t mapped = 0;
  if (direct_in_sync) {
    mapped = t + config_.direct_offset.count();
  } else if (verdict == Verdict::rejected) {
    // The sensor stamp is implausible; the receive stamp is the best information there is.
    // It does not update the state that map() and stats() use.
    return MappedTime(coarse);
  } else if (fine_) {
    mapped = t + fitted_offset_at(t);
  } else {
    // Before the fit: the smallest delay seen so far (a lower bound of the offset, skew taken as
    // 0). Unlike each sample's own receive stamp it carries no queueing jitter, so consecutive
    // samples keep their sensor spacing (an IMU's dt is right from the first sample on) and a
    // scan lines up with the IMU samples around it; it only drifts by the skew (<= 200 ppm) until
    // the fit takes over.
    mapped = t + z_lowest_ - floor;
  }
  // Residuals only mean something against a clock model (a coarse one is 0 by construction).
  if (direct_in_sync || fine_) record_residual(coarse - mapped);
  have_last_ = true;
  last_offset_ = mapped - t;
  return MappedTime(mapped);
}

ClockDomain::Verdict ClockDomain::track(std::int64_t t, std::int64_t z, std::int64_t y) {
  const auto start_epoch = [&] {
    have_epoch_ = true;
    t_newest_ = t;
    t_lowest_ = t;
    z_lowest_ = z;
    y_last_not_late_ = y;
    consecutive_rejected_ = 0;
    hull_.add(t, z, 0.0);
    refit();
  };
  if (!have_epoch_) {
    start_epoch();
    return Verdict::accepted;
  }

  bool impossible = false;
  bool late = false;
  if (t < t_newest_ - config_.jump_threshold.count()) {
    impossible = true;  // the sensor clock went backwards
  } else {
    // Distance above the reference line. With a fit, a sample more than early_tolerance below it
    // was stamped later than its reception allows. Without one, the reference is the lowest
    // point of the epoch, whose own queueing delay is unknown (up to the largest delays), so
    // only gross jumps can be told apart from delay noise there; small stamp glitches that get
    // in are left out of the fit by the hull's spike test.
    const double jump = static_cast<double>(config_.jump_threshold.count());
    if (fine_) {
      const double above = line_->above(t, z);
      impossible = above < -static_cast<double>(config_.early_tolerance.count());
      late = above > jump;
    } else {
      const double above = static_cast<double>(z - z_lowest_);
      const double slack = max_skew_ * static_cast<double>(std::abs(t - t_lowest_));
      impossible = above < -(jump + slack);
      late = above > jump + slack;
    }
  }

  if (impossible) {
    if (++consecutive_rejected_ < config_.reset_confirm_samples) {
      ++rejected_;
      return Verdict::rejected;
    }
    // Consistently impossible: not a glitch, the sensor clock jumped. Start over from here.
    ++resets_;
    restart_estimator();
    start_epoch();
    return Verdict::restarted;
  }
  consecutive_rejected_ = 0;

  if (!late) {
    y_last_not_late_ = y;
  } else if (y - y_last_not_late_ > config_.late_reset_after.count()) {
    // Nothing but late samples for a long time: the clock stepped back (a queueing spike or a
    // host stall ends well before this).
    ++resets_;
    restart_estimator();
    start_epoch();
    return Verdict::restarted;
  }

  t_newest_ = std::max(t_newest_, t);
  if (z < z_lowest_) {
    t_lowest_ = t;
    z_lowest_ = z;
  }
  if (hull_.add(t, z, fine_ ? line_->slope : 0.0)) refit();
  return Verdict::accepted;
}

void ClockDomain::restart_estimator() {
  hull_.clear();
  line_.reset();
  fine_ = false;
  have_epoch_ = false;
  consecutive_rejected_ = 0;
}

void ClockDomain::refit() {
  line_ = hull_.fit(max_skew_);
  fine_ = line_.has_value() && hull_.span() >= config_.min_fine_span;
}

void ClockDomain::check_direct_sync(std::int64_t y, std::int64_t direct_residual) {
  if (!have_sync_period_) {
    have_sync_period_ = true;
    sync_period_start_ = y;
    sync_period_min_ = direct_residual;
    return;
  }
  if (y - sync_period_start_ < config_.sync_check_period.count()) {
    sync_period_min_ = std::min(sync_period_min_, direct_residual);
    return;
  }
  // Judge the completed period by its least-delayed sample: single delayed packets cannot raise
  // it, and any "received before sent" sample lowers it.
  direct_residual_ = sync_period_min_;
  const bool bad = sync_period_min_ > config_.sync_loss_late.count() ||
                   sync_period_min_ < -config_.sync_loss_early.count();
  if (bad != sync_lost_) {
    // Either transition starts a new clock regime (free-running after a loss, disciplined after a
    // re-lock): the hull must not mix the two.
    if (bad) ++sync_losses_;
    sync_lost_ = bad;
    restart_estimator();
  }
  sync_period_start_ = y;
  sync_period_min_ = direct_residual;
}

std::int64_t ClockDomain::fitted_offset_at(std::int64_t t) const {
  return line_->at(t) - config_.min_transport_delay.count();
}

void ClockDomain::record_residual(std::int64_t residual) {
  last_residual_ = residual;
  residuals_[residual_next_] = residual;
  residual_next_ = (residual_next_ + 1) % kResidualHistory;
  residual_count_ = std::min(residual_count_ + 1, kResidualHistory);
}

MappedTime ClockDomain::map(SensorTime t_sensor) const {
  const std::int64_t t = t_sensor.ns;
  switch (config_.mode) {
    case ClockMode::receive_time:
      return MappedTime(t - config_.receive_latency.count());
    case ClockMode::direct:
      if (!sync_lost_) return MappedTime(t + config_.direct_offset.count());
      break;
    case ClockMode::free_running:
      break;
  }
  if (fine_) return MappedTime(t + fitted_offset_at(t));
  if (have_last_) return MappedTime(t + last_offset_);
  return MappedTime(config_.mode == ClockMode::direct ? t + config_.direct_offset.count() : t);
}

SyncQuality ClockDomain::quality() const {
  switch (config_.mode) {
    case ClockMode::receive_time:
      return SyncQuality::coarse;
    case ClockMode::direct:
      return sync_lost_ ? SyncQuality::lost : SyncQuality::fine;
    case ClockMode::free_running:
      break;
  }
  return fine_ ? SyncQuality::fine : SyncQuality::coarse;
}

void ClockDomain::reset() {
  ++resets_;
  restart_estimator();
  have_last_ = false;
}

ClockDomainStats ClockDomain::stats() const {
  ClockDomainStats s;
  s.mode = config_.mode;
  s.quality = quality();
  if (have_last_) {
    s.offset = Nanoseconds(last_offset_);
  } else if (config_.mode == ClockMode::direct) {
    s.offset = config_.direct_offset;
  } else if (config_.mode == ClockMode::receive_time) {
    s.offset = -config_.receive_latency;
  }
  s.skew_ppm = fine_ ? line_->slope * 1e6 : 0.0;

  if (residual_count_ > 0) {
    // Median and median absolute deviation on a stack copy (no allocation).
    std::array<std::int64_t, kResidualHistory> work{};
    const auto n = static_cast<std::ptrdiff_t>(residual_count_);
    std::copy_n(residuals_.begin(), n, work.begin());
    const auto mid = work.begin() + n / 2;
    std::nth_element(work.begin(), mid, work.begin() + n);
    const std::int64_t median = *mid;
    for (std::ptrdiff_t i = 0; i < n; ++i) work[i] = std::abs(work[i] - median);
    std::nth_element(work.begin(), mid, work.begin() + n);
    s.residual_median = Nanoseconds(median);
    s.jitter = Nanoseconds(*mid);
  }
  s.last_residual = Nanoseconds(last_residual_);
  s.direct_residual = Nanoseconds(direct_residual_);
  s.samples = config_.mode == ClockMode::receive_time ? observations_ : hull_.samples();
  s.window_points = hull_.points();
  s.observations = observations_;
  s.resets = resets_;
  s.rejected = rejected_;
  s.sync_losses = sync_losses_;
  return s;
}

}  // namespace livod
