// A Velodyne with a reduced field of view (the sensor's FOV setting), issue 13 defects 3 and 4.
// The sensor sends only the firings inside its window; packets stay full, so the packet at each
// window edge holds the last firings of one window and the first firings of the next, fired
// about (skipped sector / rotation rate) later than its timestamp says. Constructed VLP-32C
// streams (10 Hz, window 270 -> 90 degrees): every firing's range encodes its index, so each
// decoded point is traced back to its true firing time.

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "drivers/velodyne/data_packet.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"
#include "drivers/velodyne/wire.hpp"

namespace livod::drivers::velodyne {
namespace {

constexpr std::int64_t kSequenceNs = 55'296;       // VLP-32C firing sequence (one block)
constexpr double kRate = 36000.0 / 100'000'000.0;  // 0.01 degree per ns at 10 Hz
constexpr std::int64_t kHourBaseNs = 1'699'999'200LL * 1'000'000'000LL;  // a top of the hour
constexpr std::int64_t kStartNs = 1'000'000'000'000LL;                   // 1000 s into the hour
constexpr int kRawBase = 2000;  // range of firing k: (2000 + k) x 4 mm

struct Firing {
  int k = 0;
  std::int64_t t_ns = 0;  // since the top of the hour
  std::uint16_t azimuth = 0;
};

struct Stream {
  std::vector<std::vector<std::byte>> packets;
  std::vector<std::int64_t> host_ns;
  std::map<int, std::int64_t> firing_time;  // k -> t_ns
};

bool in_window(std::uint16_t azimuth) {
  return azimuth >= 27000 || azimuth < 9000;
}

// `seconds` of a 10 Hz VLP-32C limited to 270 -> 90 degrees (or unlimited).
Stream make_stream(double seconds, bool limited) {
  std::vector<Firing> sent;
  const auto firings = static_cast<int>(seconds * 1e9 / kSequenceNs);
  for (int k = 0; k < firings; ++k) {
    const std::int64_t t = kStartNs + k * kSequenceNs;
    const auto azimuth = static_cast<std::uint16_t>(
        std::llround(static_cast<double>(t % 100'000'000) * kRate) % 36000);
    if (limited && !in_window(azimuth)) continue;
    sent.push_back({k, t, azimuth});
  }
  Stream s;
  for (std::size_t first = 0; first + 12 <= sent.size(); first += 12) {
    std::vector<std::byte> p(wire::kDataPacketSize, std::byte{0});
    for (std::size_t b = 0; b < 12; ++b) {
      const Firing& f = sent[first + b];
      const std::size_t base = b * wire::kBlockSize;
      wire::put_u16le(p, base, wire::kBank0Flag);
      wire::put_u16le(p, base + 2, f.azimuth);
      for (std::size_t c = 0; c < 32; ++c) {
        wire::put_u16le(p, base + 4 + c * 3, static_cast<std::uint16_t>(kRawBase + f.k));
        p[base + 4 + c * 3 + 2] = std::byte{100};
      }
      s.firing_time[f.k] = f.t_ns;
    }
    const std::int64_t stamp_ns = sent[first].t_ns;
    wire::put_u32le(p, wire::kTimestampOffset, static_cast<std::uint32_t>(stamp_ns / 1000));
    p[wire::kReturnModeOffset] = std::byte{0x37};
    p[wire::kFactoryByteOffset] = std::byte{0x28};
    s.packets.push_back(std::move(p));
    // Received when the last block has fired.
    s.host_ns.push_back(kHourBaseNs + sent[first + 11].t_ns + 100'000);
  }
  return s;
}

struct Result {
  std::vector<LidarScan> scans;
  DecoderCounters counters;
  VelodyneCounters velodyne;
};

Result decode(const Stream& s, const VelodyneOptions& options, int drop = -1) {
  VelodyneDecoder decoder(options);
  Result out;
  DecoderSinks sinks;
  sinks.on_scan = [&out](const LidarScan& scan) { out.scans.push_back(scan); };
  for (std::size_t i = 0; i < s.packets.size(); ++i) {
    if (static_cast<int>(i) == drop) continue;
    decoder.on_packet({s.packets[i], s.host_ns[i], 2368}, sinks);
  }
  decoder.flush(sinks);
  out.counters = decoder.counters();
  out.velodyne = decoder.velodyne_counters();
  return out;
}

VelodyneOptions vlp32c() {
  VelodyneOptions options;
  options.model = Model::kVlp32c;
  return options;
}

// Largest |decoded point time - true firing time of its sequence| minus the in-sequence offset
// allowance (lasers fire in pairs over 16 x 2.304 us).
std::int64_t worst_time_error_ns(const Result& r, const Stream& s, std::size_t* points) {
  std::int64_t worst = 0;
  *points = 0;
  for (const auto& scan : r.scans) {
    for (std::size_t i = 0; i < scan.size(); ++i) {
      const double d = std::sqrt(static_cast<double>(scan.x[i]) * scan.x[i] +
                                 static_cast<double>(scan.y[i]) * scan.y[i] +
                                 static_cast<double>(scan.z[i]) * scan.z[i]);
      const int k = static_cast<int>(std::lround(d / 0.004)) - kRawBase;
      const auto it = s.firing_time.find(k);
      EXPECT_NE(it, s.firing_time.end()) << "point with range " << d;
      if (it == s.firing_time.end()) continue;
      const std::int64_t t = scan.start.sensor.ns + scan.t_offset_ns[i] - kHourBaseNs;
      const std::int64_t after = t - it->second;  // within [0, 15 x 2.304 us] if exact
      const std::int64_t error = after < 0 ? -after : std::max<std::int64_t>(0, after - 34'560);
      worst = std::max(worst, error);
      ++*points;
    }
  }
  return worst;
}

TEST(VelodyneFieldOfView, SkippedSectorIsNoLossAndScansAreComplete) {
  const Stream s = make_stream(2.05, true);
  const Result r = decode(s, vlp32c());
  EXPECT_EQ(r.counters.decode_errors, 0U);
  EXPECT_EQ(r.counters.sequence_gaps, 0U);  // was ~75 per revolution
  ASSERT_GE(r.scans.size(), 20U);
  // Only the first and the last scans (partial revolutions of the capture) are incomplete. One
  // window edge of this stream falls exactly between two packets: the window learned from the
  // earlier boundary packets tells it from loss.
  EXPECT_EQ(r.counters.incomplete_scans, 2U);
  // One window edge per revolution falls inside a packet.
  EXPECT_GE(r.velodyne.fov_boundary_packets, 19U);
  EXPECT_LE(r.velodyne.fov_boundary_packets, 21U);
  EXPECT_EQ(r.velodyne.undated_blocks, 0U);
}

TEST(VelodyneFieldOfView, BoundaryBlocksAreDatedByTheirFiringTime) {
  const Stream s = make_stream(2.05, true);
  const Result r = decode(s, vlp32c());
  std::size_t points = 0;
  // Was about 50 ms early for the blocks after each window edge.
  EXPECT_LT(worst_time_error_ns(r, s, &points), 20'000);
  EXPECT_EQ(points, s.firing_time.size() * 32);
}

TEST(VelodyneFieldOfView, BoundaryPacketBlocksCarryTheSkippedSectorsDelay) {
  // The packet decoder alone: the first boundary packet of the stream.
  const Stream s = make_stream(0.3, true);
  const DataPacketDecoder decoder(Model::kVlp32c, default_calibration(Model::kVlp32c), {});
  std::vector<DecodedReturn> out(DataPacketDecoder::kMaxReturns);
  bool found = false;
  for (const auto& p : s.packets) {
    const DataPacketResult r = decoder.decode(p, kRate, out, kRate);
    ASSERT_EQ(r.status, DataDecodeStatus::kOk);
    if (r.azimuth_jumps == 0) continue;
    found = true;
    // Each block's firing index is in its ranges: the true delay is its firing time minus the
    // first block's, minus what the timing table says (one sequence per block).
    auto firing_of = [&p](int b) {
      return static_cast<int>(wire::u16le(p, static_cast<std::size_t>(b) * wire::kBlockSize + 4)) -
             kRawBase;
    };
    const std::int64_t t0 = s.firing_time.at(firing_of(0));
    int jumped_blocks = 0;
    for (int b = 0; b < 12; ++b) {
      const std::int64_t truth = s.firing_time.at(firing_of(b)) - t0 - b * kSequenceNs;
      const std::int32_t delay = r.block_delay_ns[static_cast<std::size_t>(b)];
      EXPECT_NEAR(static_cast<double>(delay), static_cast<double>(truth), 3'000.0) << "block " << b;
      if (truth > 40'000'000) ++jumped_blocks;  // about 50 ms: half a turn at 10 Hz
    }
    EXPECT_GT(jumped_blocks, 0);
    EXPECT_LT(jumped_blocks, 12);
    break;
  }
  EXPECT_TRUE(found);
}

TEST(VelodyneFieldOfView, RealLossInsideTheWindowIsStillCounted) {
  const Stream s = make_stream(1.05, true);
  const Result r = decode(s, vlp32c(), 300);
  EXPECT_EQ(r.counters.sequence_gaps, 1U);
}

TEST(VelodyneFieldOfView, ConfiguredWindowExcludesTheSectorWhenAPacketAtTheEdgeIsLost) {
  // Dropping a boundary packet leaves a path through the skipped sector between two packets:
  // only the configured window tells the sector (no loss) from the one lost packet.
  const Stream s = make_stream(1.05, true);
  const DataPacketDecoder probe(Model::kVlp32c, default_calibration(Model::kVlp32c), {});
  std::vector<DecodedReturn> out(DataPacketDecoder::kMaxReturns);
  int boundary = -1;
  for (std::size_t i = 200; i < s.packets.size(); ++i) {
    if (probe.decode(s.packets[i], kRate, out, kRate).azimuth_jumps > 0) {
      boundary = static_cast<int>(i);
      break;
    }
  }
  ASSERT_GE(boundary, 0);
  VelodyneOptions options = vlp32c();
  options.fov = AzimuthWindow{270.0, 90.0};
  const Result r = decode(s, options, boundary);
  EXPECT_EQ(r.counters.sequence_gaps, 1U);
}

TEST(VelodyneFieldOfView, FullTurnStreamIsUnchanged) {
  const Stream s = make_stream(1.05, false);
  const Result r = decode(s, vlp32c());
  EXPECT_EQ(r.counters.sequence_gaps, 0U);
  EXPECT_EQ(r.velodyne.fov_boundary_packets, 0U);
  std::size_t points = 0;
  EXPECT_LT(worst_time_error_ns(r, s, &points), 2'000);
  EXPECT_EQ(points, s.firing_time.size() * 32);
}

}  // namespace
}  // namespace livod::drivers::velodyne
