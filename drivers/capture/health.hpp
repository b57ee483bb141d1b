#pragma once
// Stream health as small, clock-free classes (the caller passes `now`), in the spirit of
// tier4/nebula's diagnostics: a rate over a sliding window, STALE detection for a stream that went
// silent, and the per-stream / per-source snapshots the daemon's 1 Hz health thread publishes
// (LIVOD_HEALTH, sd_notify STATUS=). Nothing here runs on a capture thread.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "drivers/capture/capture_thread.hpp"
#include "drivers/capture/stream_consumer.hpp"
#include "drivers/lidar_decoder.hpp"

namespace livod::drivers::capture {

// Events per second over a sliding window, from a cumulative counter sampled at any cadence.
// Fixed storage (kMaxSamples): sampled faster than kMaxSamples per window, the effective window
// shrinks to the newest kMaxSamples samples.
class RateMeter {
 public:
  static constexpr std::size_t kMaxSamples = 64;

  // window > 0 (std::invalid_argument otherwise).
  explicit RateMeter(Nanoseconds window);

  // Records the counter's value at `now`. A sample older than the newest one is ignored; a counter
  // that went down (the source was reset) restarts the window.
  void add(HostTime now, std::uint64_t cumulative);

  // (newest - base) / elapsed, where base is the newest sample at or before now - window (or the
  // oldest kept). 0 with fewer than two samples.
  [[nodiscard]] double per_second() const;

  [[nodiscard]] Nanoseconds window() const { return window_; }

 private:
  struct Sample {
    HostTime t;
    std::uint64_t count = 0;
  };
  [[nodiscard]] const Sample& at(std::size_t i) const {
    return samples_[(first_ + i) % kMaxSamples];
  }

  Nanoseconds window_;
  std::array<Sample, kMaxSamples> samples_{};
  std::size_t first_ = 0;
  std::size_t size_ = 0;
};

// WAITING: nothing received yet (and not for longer than stale_after); STREAMING: a packet within
// stale_after; STALE: silent for longer than stale_after (including never heard from).
enum class StreamState : std::uint8_t { kWaiting, kStreaming, kStale };
const char* to_string(StreamState s);

class StaleDetector {
 public:
  // stale_after > 0 (std::invalid_argument otherwise).
  explicit StaleDetector(Nanoseconds stale_after);

  // `last_packet`: receive time of the newest packet, nullopt if none arrived yet. Returns the
  // state after the update.
  StreamState update(HostTime now, std::optional<HostTime> last_packet);

  [[nodiscard]] StreamState state() const { return state_; }
  [[nodiscard]] std::uint64_t stale_events() const { return stale_events_; }  // entries into STALE
  [[nodiscard]] std::uint64_t recoveries() const { return recoveries_; }      // STALE -> STREAMING
  [[nodiscard]] HostTime state_since() const { return since_; }
  [[nodiscard]] Nanoseconds stale_after() const { return stale_after_; }

 private:
  Nanoseconds stale_after_;
  StreamState state_ = StreamState::kWaiting;
  std::optional<HostTime> first_update_;
  HostTime since_{};
  std::uint64_t stale_events_ = 0;
  std::uint64_t recoveries_ = 0;
};

// One capture stream (one UDP port).
struct StreamHealth {
  std::string name;
  StreamState state = StreamState::kWaiting;
  double packets_per_s = 0.0;
  double megabits_per_s = 0.0;  // UDP payload bits
  std::optional<Nanoseconds> last_packet_age;
  std::uint64_t stale_events = 0;
  std::uint64_t recoveries = 0;
  CaptureCounters capture;  // kernel drops, ring overruns, truncation, RT status...
};

// One sensor: its streams, its decoder and what supervision did.
struct SourceHealth {
  std::string name;
  std::vector<StreamHealth> streams;
  DecoderCounters decoder;  // sequence gaps, decode errors, scans... (totals over decoder swaps)
  ConsumerCounters consumer;
  std::string device_state;              // Livox: LivoxDevice state ("STREAMING"); empty otherwise
  std::uint64_t reconnects = 0;          // Livox: streaming re-established after STALE
  std::uint64_t sensor_reinits = 0;      // Ouster: init_id changes seen by the decoder
  std::uint64_t metadata_refreshes = 0;  // Ouster: metadata re-read and decoder rebuilt
  std::string last_error;                // supervision's latest failure (e.g. metadata fetch)

  // Packets lost anywhere on the path: kernel + ring + the sensor's own sequence counters.
  [[nodiscard]] std::uint64_t lost_packets() const;
  // Every stream STREAMING.
  [[nodiscard]] bool all_streaming() const;
};

// Rate + STALE tracking of one capture stream; update() at the health cadence.
class StreamMonitor {
 public:
  StreamMonitor(std::string name, Nanoseconds stale_after, Nanoseconds rate_window);
  StreamHealth update(HostTime now, const CaptureCounters& counters);
  [[nodiscard]] const StaleDetector& stale_detector() const { return stale_; }

 private:
  std::string name_;
  StaleDetector stale_;
  RateMeter packet_rate_;
  RateMeter byte_rate_;
};

// One log line for the low-priority logging thread, e.g.
// "os1 [lidar STREAMING 640.0 pkt/s 42.5 Mbit/s age 1 ms] scans 10 gaps 0 kdrop 0 ovr 0 ...".
[[nodiscard]] std::string format_health(const SourceHealth& health);

}  // namespace livod::drivers::capture
