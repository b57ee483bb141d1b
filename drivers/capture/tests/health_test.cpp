// Stream health: rate over a sliding window, STALE detection, per-stream snapshots.

#include "drivers/capture/health.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace livod::drivers::capture {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

HostTime at_s(double s) {
  return HostTime(static_cast<std::int64_t>(s * 1e9));
}

TEST(RateMeter, SteadyRateIsMeasuredOverTheWindowAndDecaysToZeroWhenSilent) {
  RateMeter meter(Nanoseconds(5 * kSecond));
  EXPECT_EQ(meter.per_second(), 0.0);  // no samples
  meter.add(at_s(100.0), 1000);
  EXPECT_EQ(meter.per_second(), 0.0);  // one sample: no interval yet
  // 640 packets/s (Ouster 1024x10), sampled at 1 Hz for 10 s.
  std::uint64_t count = 1000;
  for (int i = 1; i <= 10; ++i) {
    count += 640;
    meter.add(at_s(100.0 + i), count);
    EXPECT_DOUBLE_EQ(meter.per_second(), 640.0) << i;
  }
  // The rate changes to 100/s: after 2 s the 5 s window holds 3 s at 640 and 2 s at 100.
  for (int i = 11; i <= 12; ++i) {
    count += 100;
    meter.add(at_s(100.0 + i), count);
  }
  EXPECT_DOUBLE_EQ(meter.per_second(), (3 * 640.0 + 2 * 100.0) / 5.0);
  // Silence: the counter stops; after a full window the rate is 0.
  for (int i = 13; i <= 17; ++i) meter.add(at_s(100.0 + i), count);
  EXPECT_DOUBLE_EQ(meter.per_second(), 0.0);
}

TEST(RateMeter, IrregularSamplingUsesTheTrueElapsedTime) {
  RateMeter meter(Nanoseconds(2 * kSecond));
  // 250 events/s, sampled at irregular instants: the rate is exact whatever the spacing.
  const double times[] = {0.0, 0.13, 0.5, 0.51, 1.7, 2.05, 3.3, 3.31, 4.9};
  for (const double t : times) {
    meter.add(at_s(t), static_cast<std::uint64_t>(t * 250.0 + 0.5));
  }
  // Base = newest sample at or before 4.9 - 2 = 2.9 s, i.e. the one at 2.05 s.
  const auto count_at = [](double t) {
    return static_cast<double>(static_cast<std::uint64_t>(t * 250.0 + 0.5));
  };
  const double expected = (count_at(4.9) - count_at(2.05)) / to_seconds(at_s(4.9) - at_s(2.05));
  EXPECT_NEAR(meter.per_second(), expected, 1e-9);
  EXPECT_NEAR(meter.per_second(), 250.0, 0.5);
}

TEST(RateMeter, CounterResetRestartsAndOldSamplesAreIgnored) {
  RateMeter meter(Nanoseconds(10 * kSecond));
  meter.add(at_s(1.0), 500);
  meter.add(at_s(2.0), 600);
  EXPECT_DOUBLE_EQ(meter.per_second(), 100.0);
  meter.add(at_s(1.5), 10);  // older than the newest sample: ignored
  EXPECT_DOUBLE_EQ(meter.per_second(), 100.0);
  meter.add(at_s(3.0), 20);  // counter went down: the source restarted
  EXPECT_DOUBLE_EQ(meter.per_second(), 0.0);
  meter.add(at_s(4.0), 70);
  EXPECT_DOUBLE_EQ(meter.per_second(), 50.0);
}

TEST(RateMeter, MoreSamplesThanStorageShrinkTheWindowButStayExact) {
  RateMeter meter(Nanoseconds(10 * kSecond));
  // 1000 samples 1 ms apart: far more than kMaxSamples within the window.
  for (int i = 0; i < 1000; ++i) {
    meter.add(HostTime(i * 1'000'000LL), static_cast<std::uint64_t>(i) * 3);
  }
  EXPECT_NEAR(meter.per_second(), 3000.0, 1e-6);
  EXPECT_THROW(RateMeter(Nanoseconds(0)), std::invalid_argument);
}

TEST(StaleDetector, StreamingStaleAndRecoveryAreCountedOnce) {
  StaleDetector d{Nanoseconds(kSecond)};
  EXPECT_EQ(d.update(at_s(10.0), std::nullopt), StreamState::kWaiting);
  EXPECT_EQ(d.update(at_s(10.5), at_s(10.4)), StreamState::kStreaming);
  EXPECT_EQ(d.update(at_s(11.4), at_s(10.4)), StreamState::kStreaming);  // exactly 1 s old
  EXPECT_EQ(d.update(at_s(11.41), at_s(10.4)), StreamState::kStale);
  EXPECT_EQ(d.state_since(), at_s(11.41));
  EXPECT_EQ(d.update(at_s(12.0), at_s(10.4)), StreamState::kStale);
  EXPECT_EQ(d.update(at_s(13.0), at_s(10.4)), StreamState::kStale);
  EXPECT_EQ(d.stale_events(), 1u);
  EXPECT_EQ(d.recoveries(), 0u);
  EXPECT_EQ(d.update(at_s(14.0), at_s(13.9)), StreamState::kStreaming);
  EXPECT_EQ(d.recoveries(), 1u);
  EXPECT_EQ(d.update(at_s(20.0), at_s(13.9)), StreamState::kStale);
  EXPECT_EQ(d.update(at_s(20.1), at_s(20.05)), StreamState::kStreaming);
  EXPECT_EQ(d.stale_events(), 2u);
  EXPECT_EQ(d.recoveries(), 2u);
}

TEST(StaleDetector, ASensorNeverHeardFromBecomesStale) {
  StaleDetector d{Nanoseconds(2 * kSecond)};
  EXPECT_EQ(d.update(at_s(0.0), std::nullopt), StreamState::kWaiting);
  EXPECT_EQ(d.update(at_s(2.0), std::nullopt), StreamState::kWaiting);
  EXPECT_EQ(d.update(at_s(2.5), std::nullopt), StreamState::kStale);
  EXPECT_EQ(d.stale_events(), 1u);
  EXPECT_EQ(d.update(at_s(3.0), at_s(2.9)), StreamState::kStreaming);
  EXPECT_EQ(d.recoveries(), 1u);
  EXPECT_THROW(StaleDetector(Nanoseconds(-1)), std::invalid_argument);
}

TEST(StreamMonitor, SnapshotCarriesRatesAgeStateAndCounters) {
  StreamMonitor monitor("lidar", Nanoseconds(kSecond), Nanoseconds(4 * kSecond));
  CaptureCounters c;
  StreamHealth h = monitor.update(at_s(1.0), c);
  EXPECT_EQ(h.name, "lidar");
  EXPECT_EQ(h.state, StreamState::kWaiting);
  EXPECT_FALSE(h.last_packet_age.has_value());
  // 754 VLP-16 packets/s of 1206 bytes.
  for (int i = 1; i <= 4; ++i) {
    c.datagrams += 754;
    c.bytes += 754 * 1206;
    c.last_rx_ns = at_s(1.0 + i - 0.002).ns;
    h = monitor.update(at_s(1.0 + i), c);
  }
  EXPECT_EQ(h.state, StreamState::kStreaming);
  EXPECT_DOUBLE_EQ(h.packets_per_s, 754.0);
  EXPECT_NEAR(h.megabits_per_s, 754.0 * 1206 * 8 / 1e6, 1e-9);
  ASSERT_TRUE(h.last_packet_age.has_value());
  EXPECT_EQ(h.last_packet_age->count(), 2'000'000);
  EXPECT_EQ(h.capture.datagrams, 4u * 754u);
  // Silence for 2 s: STALE, rate going down.
  h = monitor.update(at_s(7.0), c);
  EXPECT_EQ(h.state, StreamState::kStale);
  EXPECT_EQ(h.stale_events, 1u);
  EXPECT_LT(h.packets_per_s, 754.0);
}

TEST(SourceHealth, LostPacketsAddEveryDropSourceAndTheLineNamesThem) {
  SourceHealth h;
  h.name = "vlp16";
  StreamHealth data;
  data.name = "data";
  data.state = StreamState::kStreaming;
  data.capture.kernel_drops = 3;
  data.capture.ring_overruns = 4;
  StreamHealth position;
  position.name = "position";
  position.state = StreamState::kStale;
  position.capture.ring_overruns = 1;
  position.capture.priority = SchedulingResult::kDenied;
  position.capture.priority_error = 1;
  h.streams = {data, position};
  h.decoder.sequence_gaps = 5;
  h.decoder.scans = 12;
  EXPECT_EQ(h.lost_packets(), 13u);
  EXPECT_FALSE(h.all_streaming());
  h.streams[1].state = StreamState::kStreaming;
  EXPECT_TRUE(h.all_streaming());
  h.device_state = "STALE";
  h.reconnects = 2;
  const std::string line = format_health(h);
  EXPECT_NE(line.find("vlp16"), std::string::npos) << line;
  EXPECT_NE(line.find("[data STREAMING"), std::string::npos) << line;
  EXPECT_NE(line.find("kdrop 3 ovr 4"), std::string::npos) << line;
  EXPECT_NE(line.find("rt-denied(1)"), std::string::npos) << line;
  EXPECT_NE(line.find("scans 12"), std::string::npos) << line;
  EXPECT_NE(line.find("gaps 5"), std::string::npos) << line;
  EXPECT_NE(line.find("device STALE reconnects 2"), std::string::npos) << line;
}

}  // namespace
}  // namespace livod::drivers::capture
