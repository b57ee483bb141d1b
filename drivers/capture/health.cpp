#include "drivers/capture/health.hpp"

#include <algorithm>
#include <cinttypes>
#include <cstdarg>
#include <cstdio>
#include <stdexcept>
#include <utility>

namespace livod::drivers::capture {
namespace {

// printf-style append (the drivers library does not link fmt; this runs on the logging thread).
__attribute__((format(printf, 2, 3))) void appendf(std::string& out, const char* format, ...) {
  char buffer[256];
  va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(buffer, sizeof(buffer), format, args);
  va_end(args);
  if (n > 0) out.append(buffer, std::min(static_cast<std::size_t>(n), sizeof(buffer) - 1));
}

}  // namespace

RateMeter::RateMeter(Nanoseconds window) : window_(window) {
  if (window <= Nanoseconds(0)) throw std::invalid_argument("RateMeter: window must be > 0");
}

void RateMeter::add(HostTime now, std::uint64_t cumulative) {
  if (size_ > 0) {
    const Sample& newest = at(size_ - 1);
    if (now < newest.t) return;
    if (cumulative < newest.count) size_ = 0;  // counter reset: old samples mean nothing now
  }
  if (size_ == kMaxSamples) {
    first_ = (first_ + 1) % kMaxSamples;
    --size_;
  }
  samples_[(first_ + size_) % kMaxSamples] = Sample{now, cumulative};
  ++size_;
  // Keep exactly one sample at or before the window start as the base, drop older ones.
  const HostTime window_start = now - window_;
  while (size_ >= 2 && at(1).t <= window_start) {
    first_ = (first_ + 1) % kMaxSamples;
    --size_;
  }
}

double RateMeter::per_second() const {
  if (size_ < 2) return 0.0;
  const Sample& base = at(0);
  const Sample& newest = at(size_ - 1);
  const Nanoseconds elapsed = newest.t - base.t;
  if (elapsed <= Nanoseconds(0)) return 0.0;
  return static_cast<double>(newest.count - base.count) / to_seconds(elapsed);
}

const char* to_string(StreamState s) {
  switch (s) {
    case StreamState::kWaiting:
      return "WAITING";
    case StreamState::kStreaming:
      return "STREAMING";
    case StreamState::kStale:
      return "STALE";
  }
  return "?";
}

StaleDetector::StaleDetector(Nanoseconds stale_after) : stale_after_(stale_after) {
  if (stale_after <= Nanoseconds(0)) {
    throw std::invalid_argument("StaleDetector: stale_after must be > 0");
  }
}

StreamState StaleDetector::update(HostTime now, std::optional<HostTime> last_packet) {
  if (!first_update_) {
    first_update_ = now;
    since_ = now;
  }
  StreamState next = StreamState::kWaiting;
  if (last_packet) {
    next = now - *last_packet <= stale_after_ ? StreamState::kStreaming : StreamState::kStale;
  } else if (now - *first_update_ > stale_after_) {
    next = StreamState::kStale;  // never heard from: as bad as gone silent
  }
  if (next != state_) {
    if (next == StreamState::kStale) ++stale_events_;
    if (state_ == StreamState::kStale && next == StreamState::kStreaming) ++recoveries_;
    state_ = next;
    since_ = now;
  }
  return state_;
}

std::uint64_t SourceHealth::lost_packets() const {
  std::uint64_t lost = decoder.sequence_gaps;
  for (const StreamHealth& s : streams) lost += s.capture.kernel_drops + s.capture.ring_overruns;
  return lost;
}

bool SourceHealth::all_streaming() const {
  for (const StreamHealth& s : streams) {
    if (s.state != StreamState::kStreaming) return false;
  }
  return !streams.empty();
}

StreamMonitor::StreamMonitor(std::string name, Nanoseconds stale_after, Nanoseconds rate_window)
    : name_(std::move(name)),
      stale_(stale_after),
      packet_rate_(rate_window),
      byte_rate_(rate_window) {}

StreamHealth StreamMonitor::update(HostTime now, const CaptureCounters& counters) {
  std::optional<HostTime> last;
  if (counters.last_rx_ns != 0) last = HostTime(counters.last_rx_ns);
  stale_.update(now, last);
  packet_rate_.add(now, counters.datagrams);
  byte_rate_.add(now, counters.bytes);

  StreamHealth h;
  h.name = name_;
  h.state = stale_.state();
  h.packets_per_s = packet_rate_.per_second();
  h.megabits_per_s = byte_rate_.per_second() * 8e-6;
  if (last) h.last_packet_age = now - *last;
  h.stale_events = stale_.stale_events();
  h.recoveries = stale_.recoveries();
  h.capture = counters;
  return h;
}

std::string format_health(const SourceHealth& health) {
  std::string out = health.name;
  for (const StreamHealth& s : health.streams) {
    appendf(out, " [%s %s %.1f pkt/s %.2f Mbit/s", s.name.c_str(), to_string(s.state),
            s.packets_per_s, s.megabits_per_s);
    if (s.last_packet_age) {
      appendf(out, " age %" PRId64 " ms",
              static_cast<std::int64_t>(s.last_packet_age->count() / 1'000'000));
    }
    appendf(out, " kdrop %" PRIu64 " ovr %" PRIu64, s.capture.kernel_drops,
            s.capture.ring_overruns);
    if (s.capture.truncated != 0) appendf(out, " trunc %" PRIu64, s.capture.truncated);
    if (s.capture.priority == SchedulingResult::kDenied) {
      appendf(out, " rt-denied(%d)", s.capture.priority_error);
    }
    out += "]";
  }
  appendf(out, " scans %" PRIu64 " points %" PRIu64 " gaps %" PRIu64 " errors %" PRIu64,
          health.decoder.scans, health.decoder.points, health.decoder.sequence_gaps,
          health.decoder.decode_errors);
  if (!health.device_state.empty()) {
    appendf(out, " device %s reconnects %" PRIu64, health.device_state.c_str(), health.reconnects);
  }
  if (health.sensor_reinits != 0 || health.metadata_refreshes != 0) {
    appendf(out, " reinits %" PRIu64 " metadata-refreshes %" PRIu64, health.sensor_reinits,
            health.metadata_refreshes);
  }
  if (!health.last_error.empty()) out += " error: " + health.last_error;
  return out;
}

}  // namespace livod::drivers::capture
