#pragma once
// Clock and link faults of a simulated sensor. Scenario time t (seconds from the start of the
// sequence) is the truth; the host clock reads host_epoch + t exactly (ground truth is stamped
// on it), a sensor's own clock reads with an offset, a skew, stamp jitter and optionally a reset,
// and packets reach the host after a delay with a floor and a heavy tail, or not at all.

#include <cmath>
#include <cstdint>
#include <random>

namespace livod::sim {

struct ClockFaults {
  double offset_s = 0.0;   // sensor clock reading at t = 0 (free-running clocks start anywhere)
  double skew_ppm = 0.0;   // sensor clock rate error
  double jitter_s = 0.0;   // white jitter of the stamps the sensor writes (1 sigma)
  double reset_at_s = -1;  // scenario time of a clock reset to zero (< 0: never)
};

struct LinkFaults {
  double delay_floor_s = 80e-6;      // wire + stack minimum
  double delay_mean_s = 40e-6;       // mean of the exponential queueing delay on top
  double spike_probability = 0.002;  // occasional scheduler/queue spikes
  double spike_mean_s = 2e-3;
  double loss_probability = 0.0;  // independent packet loss
};

class SensorClock {
 public:
  SensorClock(const ClockFaults& faults, std::uint64_t seed) : faults_(faults), rng_(seed) {}

  // The sensor's own stamp (ns) for an event at scenario time t.
  std::int64_t stamp_ns(double t) {
    double since = t;
    double base = faults_.offset_s;
    if (faults_.reset_at_s >= 0.0 && t >= faults_.reset_at_s) {
      since = t - faults_.reset_at_s;
      base = 0.0;
    }
    double reading = base + since * (1.0 + faults_.skew_ppm * 1e-6);
    if (faults_.jitter_s > 0.0) reading += faults_.jitter_s * normal_(rng_);
    return static_cast<std::int64_t>(std::llround(reading * 1e9));
  }

  [[nodiscard]] const ClockFaults& faults() const { return faults_; }

 private:
  ClockFaults faults_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

class Link {
 public:
  Link(const LinkFaults& faults, std::uint64_t seed) : faults_(faults), rng_(seed) {}

  // Delay (s) of a packet sent now; negative when the packet is lost.
  double delay_s() {
    if (faults_.loss_probability > 0.0 && unit_(rng_) < faults_.loss_probability) return -1.0;
    double d = faults_.delay_floor_s;
    if (faults_.delay_mean_s > 0.0) d += -faults_.delay_mean_s * std::log(1.0 - unit_(rng_));
    if (faults_.spike_probability > 0.0 && unit_(rng_) < faults_.spike_probability) {
      d += -faults_.spike_mean_s * std::log(1.0 - unit_(rng_));
    }
    return d;
  }

 private:
  LinkFaults faults_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> unit_{0.0, 1.0};
};

}  // namespace livod::sim
